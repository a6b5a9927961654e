//! A DoA's ray traced through the map's walls ([`Mapper::reflected_legs`]): beside a
//! corner, reflected by the wall the point hit is on; and traced to the second order (as
//! the rule does not, [`MAX_ORDER`]), a ray at a source's image in two walls passes the
//! source on its second leg.

use super::*;
use crate::mapper::tests::reflection::{TALKER, alcove};

/// The bearing (rad) from `a` to `b`.
fn bearing(a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[1] - a[1]).atan2(b[0] - a[0])
}

/// The angle (degrees) between unit normals `n` and `m`, either way round.
fn apart_deg(n: [f64; 2], m: [f64; 2]) -> f64 {
    (n[0] * m[0] + n[1] * m[1])
        .abs()
        .min(1.0)
        .acos()
        .to_degrees()
}

#[test]
fn a_ray_that_meets_a_wall_beside_a_corner_is_reflected_by_that_wall() {
    // The alcove's west wall (cells x in [2.85, 3), its face x = 3) meets the corridor's
    // north wall (cells y in [0.5, 0.65), west of it): the cells within reach of a point
    // of the alcove's wall near that corner hold both walls.
    let (mapper, _) = alcove(IasmConfig::default());
    let res = mapper.map.resolution();
    let along_x = [1.0, 0.0];
    let cells = |hit: [f64; 2]| mapper.map.occupied_within(hit, WALL_REACH_M);
    // 0.1 m above the corridor wall's face the other wall's cells tilt their principal
    // axis by more than 5 degrees (a reflection twice as far off); 0.05 m above, they
    // leave no line at all, and the trace takes the line through the point: the alcove's
    // wall, its normal along x but for the degree or so by which a disc of cells on a
    // grid turns any line's principal axis (the cells at its rim in or out by rounding).
    let tilted = [2.975, 0.775];
    let n = line_normal(&cells(tilted)).expect("the cells still run along a line");
    assert!(apart_deg(n, along_x) > 5.0, "{n:?}");
    for hit in [tilted, [2.975, 0.725]] {
        let n = line_through(hit, &cells(hit), res).expect("the wall the point is on");
        assert!(apart_deg(n, along_x) < 1.5, "{hit:?}: {n:?}");
    }
    assert!(line_normal(&cells([2.975, 0.725])).is_none());
    // Farther up, both agree; at the corner itself, neither says.
    let clear = [2.975, 1.375];
    let (a, b) = (
        line_normal(&cells(clear)),
        line_through(clear, &cells(clear), res),
    );
    assert!(apart_deg(a.unwrap(), along_x) < 1.5 && apart_deg(b.unwrap(), along_x) < 1.5);
    assert_eq!(
        line_through([2.975, 0.525], &cells([2.975, 0.525]), res),
        None
    );
}

#[test]
fn a_ray_at_a_talkers_image_in_two_walls_passes_it_on_its_second_leg() {
    // From the corridor east of the alcove, the talker (4, 1.5) is heard by way of the
    // alcove's west wall (x = 3) and then its east wall (x = 5): its image in the east
    // wall, (6, 1.5), mirrored in the west wall, (0, 1.5). The ray towards it meets the
    // west wall 0.1 m above the corridor's wall, is reflected there and again at the east
    // wall, and its second leg passes the talker; its first leg misses it by the angle
    // at the stop between the second-order image and the first, (2, 1.5).
    let (mapper, _) = alcove(IasmConfig::default());
    let from = [8.0, -0.5];
    let b = bearing(from, [0.0, 1.5]);
    let ray = Ray {
        stop: 0,
        from,
        bearing: b,
        twin: None,
        shared: false,
    };
    let legs = mapper.reflected_legs(&ray, 2);
    assert_eq!(legs.len(), 2);
    // Each reflection in a wall along y turns the direction's x (to within twice the
    // walls' degree, above).
    let dir = |l: &Leg| l.dir[1].atan2(l.dir[0]);
    let off = |a: f64, b: f64| wrap_rad(a - b).abs().to_degrees();
    assert!(off(dir(&legs[0]), std::f64::consts::PI - b) < 3.0);
    assert!(off(dir(&legs[1]), b) < 3.0);
    assert!((legs[0].from[0] - 3.0).abs() < 0.15 && (legs[1].from[0] - 5.0).abs() < 0.15);
    let slack = mapper.config.room_margin_m;
    let second = legs[1]
        .miss(TALKER, slack)
        .expect("the second leg passes it");
    assert!(second.to_degrees() < 1.5, "{}", second.to_degrees());
    let first_order = (b - bearing(from, [2.0, 1.5])).abs().to_degrees();
    let first = legs[0]
        .miss(TALKER, slack)
        .expect("the talker lies along the first leg");
    assert!(
        (first.to_degrees() - first_order).abs() < 1.5 && first_order > 4.0,
        "{} against {first_order}",
        first.to_degrees()
    );
    // Traced to the first order only, that is all there is.
    assert_eq!(mapper.reflected_legs(&ray, MAX_ORDER).len(), 1);
}
