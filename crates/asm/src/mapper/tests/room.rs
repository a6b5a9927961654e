//! The map is the room ([`IasmConfig::room_margin_m`]): on an L-shaped room, no source
//! stands where the map holds a wall or the unknown behind one.

use super::*;

/// An L-shaped room on the ghost surveys' grid (x in [-1, 10], y in [-4, 4]): a hall
/// `y < 0.5` and a wing `x > 6`, walls 0.15 m thick along them, the unknown beyond; the
/// robot drives along the hall at y = -1. Every stop hears every source of `heard`.
fn l_room(config: IasmConfig, heard: &[[f64; 2]]) -> (Mapper, Vec<Pose>, Stops) {
    let mapper = ghost_mapper_on(
        |[x, y]| match (x, y) {
            (_, y) if y < 0.5 => Cell::Free,
            (x, _) if x > 6.0 => Cell::Free,
            (x, y) if y < 0.65 || x > 5.85 => Cell::Occupied,
            _ => Cell::Unknown,
        },
        config,
    );
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, -1.0, 0.0)).collect();
    let rows: Vec<Vec<f64>> = poses
        .iter()
        .map(|p| heard.iter().map(|&q| p.bearing_to(q)).collect())
        .collect();
    let complete = mapper.complete_by_length(&rows);
    let stops = stops_with(&poses, &rows, &complete, &vec![false; poses.len()]);
    (mapper, poses, stops)
}

#[test]
fn no_source_stands_behind_a_wall_but_one_may_stand_at_it() {
    let all: Vec<usize> = (0..9).collect();
    // Where the rays meet: in the unknown 1.9 m behind the hall's wall, on the wall's
    // face (a vent high on it), in the far wing's free space, and 0.4 m into the unknown
    // (0.25 m beyond the wall), where the rays still fit the wall's face within their
    // error.
    let (behind, vent, wing, just_behind) = ([3.0, 2.5], [3.0, 0.6], [8.0, 2.0], [1.0, 0.9]);
    let places = [behind, vent, wing, just_behind];
    let run = |config: IasmConfig| {
        let (mapper, poses, stops) = l_room(config, &places);
        let mut sources: Vec<Source> = places
            .iter()
            .map(|&q| heard_from(q, &poses, &all))
            .collect();
        let mut left = vec![Vec::new(); poses.len()];
        let refused = mapper.drop_implausible(&mut sources, &stops, &mut left);
        (sources, refused, left)
    };
    let (kept, refused, left) = run(IasmConfig::default());
    let at: Vec<[f64; 2]> = kept.iter().map(|s| [s.x, s.y]).collect();
    // The source behind the wall is refused, with its rule and stops, and gives back
    // its nine DoAs.
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(
        (
            [refused[0].x, refused[0].y],
            &refused[0].rule,
            refused[0].stops.len()
        ),
        (behind, &Refusal::OutsideRoom, 9)
    );
    assert_eq!(left.iter().map(Vec::len).sum::<usize>(), 9);
    // The vent stays at the wall, the wing's source where it is.
    assert!(at.contains(&vent) && at.contains(&wing), "{at:?}");
    // The one just behind the wall moved to the nearest free cell: the wall's face,
    // straight in front of where its rays met.
    let moved = at
        .iter()
        .find(|p| !places.contains(p))
        .expect("a source moved into the room");
    assert!(
        (moved[0] - 1.0).abs() < 0.05 && (0.4..0.5).contains(&moved[1]),
        "{moved:?}"
    );
    // With the rule off (the paper profile's value) all four stay where they were.
    let (kept, refused, _) = run(IasmConfig {
        room_margin_m: 0.0,
        ..IasmConfig::default()
    });
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(kept.iter().map(|s| [s.x, s.y]).collect::<Vec<_>>(), places);
}

#[test]
fn an_open_region_is_no_room() {
    // Without a surveyed map the unknown beyond the region around the stops is merely
    // unsurveyed: the rule has no walls to go by and keeps a source there.
    let mapper = ghost_mapper_on(
        |[_, y]| if y < 1.0 { Cell::Free } else { Cell::Unknown },
        IasmConfig::default(),
    );
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, -1.0, 0.0)).collect();
    // 0.35 m beyond the last free cell's centre: within `beyond_map_m` of the map.
    let q = [3.0, 1.3];
    let rows: Vec<Vec<f64>> = poses.iter().map(|p| vec![p.bearing_to(q)]).collect();
    let complete = mapper.complete_by_length(&rows);
    let stops = stops_with(&poses, &rows, &complete, &[false; 9]);
    let mut sources = vec![heard_from(q, &poses, &(0..9).collect::<Vec<_>>())];
    let mut left = vec![Vec::new(); 9];
    let refused = mapper.drop_implausible(&mut sources, &stops, &mut left);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!([sources[0].x, sources[0].y], q);
}

#[test]
fn unknown_space_seen_in_the_open_is_unsurveyed_not_outside() {
    // The L's hall with its north wall opened between x = 1 and 2 (a doorway): a source
    // 1.2 m beyond it, in the unknown, is seen through the doorway by stop 1 (at x = 1)
    // and stays; the same source with the wall closed is behind it.
    let q = [1.5, 1.9];
    let run = |door: bool| {
        let mapper = ghost_mapper_on(
            |[x, y]| match (x, y) {
                (_, y) if y < 0.5 => Cell::Free,
                (x, y) if door && (1.0..2.0).contains(&x) && y < 0.65 => Cell::Free,
                (x, _) if x > 6.0 => Cell::Free,
                (x, y) if y < 0.65 || x > 5.85 => Cell::Occupied,
                _ => Cell::Unknown,
            },
            IasmConfig::default(),
        );
        let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, -1.0, 0.0)).collect();
        let rows: Vec<Vec<f64>> = poses.iter().map(|p| vec![p.bearing_to(q)]).collect();
        let complete = mapper.complete_by_length(&rows);
        let stops = stops_with(&poses, &rows, &complete, &[false; 9]);
        let mut sources = vec![heard_from(q, &poses, &[0, 1, 2, 3])];
        let mut left = vec![Vec::new(); 9];
        let refused = mapper.drop_implausible(&mut sources, &stops, &mut left);
        (
            sources.iter().map(|s| [s.x, s.y]).collect::<Vec<_>>(),
            refused,
        )
    };
    let (kept, refused) = run(true);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(kept, vec![q]);
    let (kept, refused) = run(false);
    assert!(kept.is_empty(), "{kept:?}");
    assert_eq!(refused[0].rule, Refusal::OutsideRoom);
}

#[test]
fn a_source_just_behind_a_walls_face_stands_at_the_face() {
    // Rays meeting 0.05 m behind the hall's wall (y in [0.5, 0.65)), in the unknown: within
    // the margin of the free space, and each stop's view of it, shortened by the margin,
    // ends in front of the wall. It is behind the wall's face all the same (the free cell
    // nearest it is on the wall's other side) and moves to the face, straight in front.
    let all: Vec<usize> = (0..9).collect();
    let q = [3.0, 0.7];
    let (mapper, poses, stops) = l_room(IasmConfig::default(), &[q]);
    assert_eq!(mapper.map.cell_at(q), Some(Cell::Unknown));
    assert!(
        !mapper
            .map
            .free_within(q, mapper.config.room_margin_m)
            .is_empty()
    );
    let mut sources = vec![heard_from(q, &poses, &all)];
    let mut left = vec![Vec::new(); poses.len()];
    let refused = mapper.drop_implausible(&mut sources, &stops, &mut left);
    assert!(refused.is_empty(), "{refused:?}");
    let at = [sources[0].x, sources[0].y];
    assert!(
        (at[0] - 3.0).abs() < 0.05 && (0.4..0.5).contains(&at[1]),
        "{at:?}"
    );
    // A source on an occupied cell beside free space (a loudspeaker on a table, a vent
    // in a wall's grille) stays where its rays meet.
    let vent = [3.0, 0.6];
    let (mapper, poses, stops) = l_room(IasmConfig::default(), &[vent]);
    assert_eq!(mapper.map.cell_at(vent), Some(Cell::Occupied));
    let mut sources = vec![heard_from(vent, &poses, &all)];
    let refused = mapper.drop_implausible(&mut sources, &stops, &mut left);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!([sources[0].x, sources[0].y], vent);
}
