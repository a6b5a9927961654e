//! The mapper's tests, each a claim of the paper or of a rule, on scenes whose answer is
//! known; the scenes and helpers they share are here.

pub(super) use super::*;
pub(super) use crate::assoc::Ray;
pub(super) use crate::map::Cell;
pub(super) use crate::ospa::ospa;
pub(super) use rand::{SeedableRng, rngs::StdRng};

pub(super) const SEED: u64 = 17;

/// An open 8 x 6 m room at 0.05 m, a robot driving along y = 0 and a few sources.
pub(super) fn scene(sources: &[[f64; 2]], k: usize) -> (OccupancyMap, Vec<Pose>, Vec<Vec<f64>>) {
    let (w, h) = (160, 120);
    let map = OccupancyMap::new(w, h, 0.05, [-1.0, -3.0], vec![Cell::Free; w * h]);
    let poses: Vec<Pose> = (0..k)
        .map(|i| Pose {
            x: 6.0 * i as f64 / (k - 1) as f64,
            y: 0.0,
            theta: 0.3 * i as f64,
        })
        .collect();
    let doas = poses
        .iter()
        .map(|p| {
            sources
                .iter()
                .map(|s| wrap_rad((s[1] - p.y).atan2(s[0] - p.x) - p.theta))
                .collect()
        })
        .collect();
    (map, poses, doas)
}

/// `doas` as a linear array along the heading hears them: each azimuth on the
/// counter-clockwise side of its line (`[0, pi]`), the mirror image of the true one
/// for a source on the right.
pub(super) fn folded(doas: &[Vec<f64>]) -> Vec<Vec<f64>> {
    doas.iter()
        .map(|row| row.iter().map(|a| wrap_rad(*a).abs()).collect())
        .collect()
}

/// A mapper of the ghost surveys' open 11 x 8 m room, N = 3, otherwise `config`.
pub(super) fn ghost_mapper(config: IasmConfig) -> Mapper {
    ghost_mapper_on(|_| Cell::Free, config)
}

/// [`ghost_mapper`] on the same grid (x in [-1, 10], y in [-4, 4], 0.05 m cells) with
/// each cell as `cell` says at its centre.
pub(super) fn ghost_mapper_on(cell: impl Fn([f64; 2]) -> Cell, config: IasmConfig) -> Mapper {
    let (w, h) = (220, 160);
    let cells = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            cell([
                -1.0 + (i as f64 + 0.5) * 0.05,
                4.0 - (j as f64 + 0.5) * 0.05,
            ])
        })
        .collect();
    let map = OccupancyMap::new(w, h, 0.05, [-1.0, -4.0], cells);
    Mapper::new(
        &map,
        &IasmConfig {
            num_doas: 3,
            ..config
        },
    )
    .unwrap()
}

/// Every stop hears `talker`; the stops `hears_ghost` picks hear `ghost` too (exact
/// world bearings).
pub(super) fn rows(
    poses: &[Pose],
    talker: [f64; 2],
    ghost: [f64; 2],
    hears_ghost: impl Fn(usize) -> bool,
) -> Vec<Vec<f64>> {
    poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![p.bearing_to(talker)];
            if hears_ghost(k) {
                row.push(p.bearing_to(ghost));
            }
            row
        })
        .collect()
}

/// A mapped source at `q` explaining the DoAs of `stops` (exact bearings).
pub(super) fn heard_from(q: [f64; 2], poses: &[Pose], stops: &[usize]) -> Source {
    let rays: Vec<Ray> = stops
        .iter()
        .map(|&k| Ray {
            stop: k,
            from: poses[k].position(),
            bearing: poses[k].bearing_to(q),
            twin: None,
            shared: false,
        })
        .collect();
    Source {
        x: q[0],
        y: q[1],
        observations: rays.len(),
        particles: 0,
        covariance: [[0.0; 2]; 2],
        round: 1,
        cluster: Vec::new(),
        rays,
        refined: true,
        mirror: None,
        blends: Vec::new(),
        images: Vec::new(),
        history: History::default(),
    }
}

/// A mapped source at `q` holding the DoAs that `stops` heard of a source at `of`
/// (exact bearings to `of`): a cloud that took another source's DoAs.
pub(super) fn holding(q: [f64; 2], of: [f64; 2], poses: &[Pose], stops: &[usize]) -> Source {
    let mut s = heard_from(q, poses, stops);
    for r in &mut s.rays {
        r.bearing = poses[r.stop].bearing_to(of);
    }
    s
}

/// The stops that speak against the ghost survey's ghost at (2, 1.5), whose furthest
/// hearer stands 3.36 m from it, with `others` mapped.
pub(super) fn against_the_ghost(
    mapper: &Mapper,
    poses: &[Pose],
    heard: &[Vec<f64>],
    others: &[[f64; 2]],
) -> Vec<usize> {
    mapper.absences([2.0, 1.5], 3.36, &by_length(mapper, poses, heard), others)
}

/// The stops of `poses` that heard `heard` (world bearings): a row complete when it is
/// shorter than `N`, none said cut (a DoA table's stops).
pub(super) fn by_length(mapper: &Mapper, poses: &[Pose], heard: &[Vec<f64>]) -> Stops {
    let said_cut = vec![false; poses.len()];
    stops_with(poses, heard, &mapper.complete_by_length(heard), &said_cut)
}

/// The stops of `poses` that heard `heard` (world bearings), with the rows `complete`
/// marks complete and those `said_cut` marks cut.
pub(super) fn stops_with(
    poses: &[Pose],
    heard: &[Vec<f64>],
    complete: &[bool],
    said_cut: &[bool],
) -> Stops {
    let (p, h, c, s) = (
        poses.to_vec(),
        heard.to_vec(),
        complete.to_vec(),
        said_cut.to_vec(),
    );
    Stops::new(p, h, c, s).expect("one entry per stop")
}

/// Nine stops along y = 0 (x = 0..8, heading 0), N = 3, every one hearing a talker at
/// (4, -3); a "ghost" at (2, 1.5) explaining DoAs of stops 0, 4 and 5 (2.5-3.4 m from
/// it), while stops 1-3, 1.5-1.8 m from it, report one DoA less than N and nothing
/// near its bearing. `full` stops among 1-3 report a third DoA pointing elsewhere.
pub(super) fn ghost_survey(full: &[usize]) -> (Mapper, Vec<Pose>, Vec<Vec<f64>>, Vec<Source>) {
    let mapper = ghost_mapper(IasmConfig::default());
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let (talker, ghost) = ([4.0, -3.0], [2.0, 1.5]);
    let mut heard = rows(&poses, talker, ghost, |k| [0, 4, 5].contains(&k));
    for &k in full {
        heard[k].extend([std::f64::consts::PI, 0.0]);
    }
    let sources = vec![
        heard_from(talker, &poses, &(0..9).collect::<Vec<_>>()),
        heard_from(ghost, &poses, &[0, 4, 5]),
    ];
    (mapper, poses, heard, sources)
}

/// A talker at (4, 1.2) in front of a wall along y in [2.0, 2.1), with nothing the
/// robot saw behind it up to the next wall at y = 3.4 (a closed block, as by
/// arrangement II's loudspeakers, with a room beyond it), and its image in the wall at
/// (4, 2.9): every stop of the path along y = 0 hears both, rows full at N = 3. `door`
/// opens both walls for x in [2.5, 5.5).
pub(super) fn walled_room(config: IasmConfig, door: bool) -> (Mapper, Vec<Pose>, Vec<Vec<f64>>) {
    let mapper = ghost_mapper_on(
        |[x, y]| {
            let in_door = door && (2.5..5.5).contains(&x);
            match y {
                y if !(2.0..3.5).contains(&y) => Cell::Free,
                y if !(2.1..3.4).contains(&y) && !in_door => Cell::Occupied,
                _ if in_door => Cell::Free,
                _ => Cell::Unknown,
            }
        },
        config,
    );
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let heard = rows(&poses, [4.0, 1.2], [4.0, 2.9], |_| true)
        .into_iter()
        .map(|mut row| {
            row.push(-std::f64::consts::FRAC_PI_2);
            row
        })
        .collect();
    (mapper, poses, heard)
}

/// The ray from `from` (stop `stop`) towards `to`, turned by `off_deg`.
pub(super) fn ray_towards(stop: usize, from: [f64; 2], to: [f64; 2], off_deg: f64) -> Ray {
    Ray {
        stop,
        from,
        bearing: (to[1] - from[1]).atan2(to[0] - from[0]) + off_deg.to_radians(),
        twin: None,
        shared: false,
    }
}

mod history;
mod plausibility;
pub(in crate::mapper) mod reflection;
mod room;
mod rounds;
mod vote;
