//! An array nearly symmetric about its axis hears a high source also at the mirrored
//! azimuth ([`IasmConfig::array_mirror`]): the mirror is no source once the robot has
//! turned and heard nothing towards it but the walls' reflections of other sources; two
//! real sources mirrored across a straight path both stay, and so does one that the
//! stops after the turn still heard.

use super::*;

/// Stops 0-8 along y = 0 heading east, then 9-12 up x = 8.5 heading north.
fn turning_path() -> Vec<Pose> {
    (0..9)
        .map(|i| Pose::new(i as f64, 0.0, 0.0))
        .chain((0..4).map(|i| Pose::new(8.5, 0.5 + 0.5 * i as f64, std::f64::consts::FRAC_PI_2)))
        .collect()
}

fn judged(
    poses: &[Pose],
    sources: Vec<Source>,
    heard: &[[f64; 2]],
) -> (Vec<[f64; 2]>, Vec<Refused>) {
    let rows: Vec<Vec<f64>> = poses
        .iter()
        .map(|p| heard.iter().map(|&q| p.bearing_to(q)).collect())
        .collect();
    judged_on(&ghost_mapper(IasmConfig::default()), poses, sources, &rows)
}

/// The sources `mapper` keeps of `sources` where each stop heard its row of `rows`
/// (world bearings), and those it refused.
fn judged_on(
    mapper: &Mapper,
    poses: &[Pose],
    sources: Vec<Source>,
    rows: &[Vec<f64>],
) -> (Vec<[f64; 2]>, Vec<Refused>) {
    let complete = mapper.complete_by_length(rows);
    let stops = stops_with(poses, rows, &complete, &vec![false; poses.len()]);
    let mut sources = sources;
    let mut left = vec![Vec::new(); poses.len()];
    let refused = mapper.drop_implausible(&mut sources, &stops, &mut left);
    (sources.iter().map(|s| [s.x, s.y]).collect(), refused)
}

#[test]
fn a_sources_mirror_in_the_array_is_no_source_once_the_robot_turned() {
    let poses = turning_path();
    // The vent at (4, 1.5), heard from every stop; at stops 2-6 (heading east) also at
    // the mirrored azimuth, whose DoAs meet at (4, -1.5).
    let (vent, mirror) = ([4.0, 1.5], [4.0, -1.5]);
    let all: Vec<usize> = (0..poses.len()).collect();
    let sources = vec![
        heard_from(vent, &poses, &all),
        heard_from(mirror, &poses, &[2, 3, 4, 5, 6]),
    ];
    let (kept, refused) = judged(&poses, sources.clone(), &[vent]);
    assert_eq!(kept, vec![vent]);
    assert_eq!(refused.len(), 1);
    assert_eq!(
        ([refused[0].x, refused[0].y], &refused[0].rule),
        (mirror, &Refusal::ArrayMirror)
    );
    // Off (the paper profile), the rule removes nothing.
    let mapper = ghost_mapper(IasmConfig {
        array_mirror: false,
        ..IasmConfig::default()
    });
    let rows: Vec<Vec<f64>> = poses.iter().map(|p| vec![p.bearing_to(vent)]).collect();
    let (_, refused) = judged_on(&mapper, &poses, sources, &rows);
    assert!(
        refused.iter().all(|r| r.rule != Refusal::ArrayMirror),
        "{refused:?}"
    );
}

#[test]
fn two_talkers_mirrored_across_a_straight_path_both_stay() {
    // No turn: nothing tells a talker from the other's mirror, so neither goes.
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let (a, b) = ([4.0, 1.5], [4.0, -1.5]);
    let sources = vec![
        heard_from(a, &poses, &(0..9).collect::<Vec<_>>()),
        heard_from(b, &poses, &[1, 2, 3, 4, 5, 6, 7]),
    ];
    let (kept, refused) = judged(&poses, sources, &[a, b]);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(kept, vec![a, b]);
}

#[test]
fn a_real_source_the_stops_after_the_turn_still_heard_stays() {
    // Two loudspeakers mirrored across the path; the second is heard by the stops after
    // the turn too, but those DoAs went to no source of it (another took them, or none):
    // a mirror would have been silent there.
    let poses = turning_path();
    let (b, a) = ([4.0, -1.5], [4.0, 1.5]);
    let all: Vec<usize> = (0..poses.len()).collect();
    let sources = vec![
        heard_from(b, &poses, &all),
        heard_from(a, &poses, &[2, 3, 4, 5, 6]),
    ];
    let (kept, refused) = judged(&poses, sources.clone(), &[b, a]);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(kept, vec![b, a]);
    // Heard after the turn only by the first stop of it, it goes: one stop is chance.
    let rows: Vec<Vec<f64>> = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![p.bearing_to(b)];
            if k <= 9 {
                row.push(p.bearing_to(a));
            }
            row
        })
        .collect();
    let (kept, refused) = judged_on(&ghost_mapper(IasmConfig::default()), &poses, sources, &rows);
    assert_eq!(kept, vec![b]);
    assert_eq!(refused[0].rule, Refusal::ArrayMirror);
}

#[test]
fn a_walls_reflection_towards_the_mirror_does_not_speak_for_it() {
    // A wall along y = -2. A talker at (0.625, -1): from the stop after the turn at
    // (8.5, 0.5) its reflection in the wall comes from exactly where the vent's mirror
    // (4, -1.5) would be, and from the next stops within 2-6 degrees of it. Traced
    // through the wall, those DoAs pass the talker: the turned stops heard nothing
    // towards the mirror but a reflection, and it goes. Without the wall on the map the
    // same DoAs could be a real source's, and the mirror stays.
    let poses = turning_path();
    let (vent, mirror, talker) = ([4.0, 1.5], [4.0, -1.5], [0.625, -1.0]);
    let image = [talker[0], -4.0 - talker[1]];
    let rows: Vec<Vec<f64>> = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![
                p.bearing_to(vent),
                p.bearing_to(talker),
                p.bearing_to(image),
            ];
            if (2..=6).contains(&k) {
                row.push(p.bearing_to(mirror));
            }
            row
        })
        .collect();
    let all: Vec<usize> = (0..poses.len()).collect();
    let sources = vec![
        heard_from(vent, &poses, &all),
        heard_from(mirror, &poses, &[2, 3, 4, 5, 6]),
        heard_from(talker, &poses, &all),
    ];
    let walled = ghost_mapper_on(
        |q| match q[1] {
            y if y >= -2.0 => Cell::Free,
            y if y >= -2.2 => Cell::Occupied,
            _ => Cell::Unknown,
        },
        IasmConfig::default(),
    );
    let (kept, refused) = judged_on(&walled, &poses, sources.clone(), &rows);
    assert_eq!(kept, vec![vent, talker]);
    assert_eq!(
        ([refused[0].x, refused[0].y], &refused[0].rule),
        (mirror, &Refusal::ArrayMirror)
    );
    let open = ghost_mapper(IasmConfig::default());
    let (kept, refused) = judged_on(&open, &poses, sources, &rows);
    assert!(
        refused.iter().all(|r| r.rule != Refusal::ArrayMirror),
        "{refused:?}"
    );
    assert!(kept.contains(&mirror), "{kept:?}");
}
