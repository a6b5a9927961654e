//! An array nearly symmetric about its axis hears a high source also at the mirrored
//! azimuth ([`IasmConfig::array_mirror`], off by default): with the rule on, the mirror is
//! no source once the robot has turned, and two real sources mirrored across a straight
//! path both stay.

use super::*;

/// Stops 0-8 along y = 0 heading east, then 9-12 up x = 8.5 heading north.
fn turning_path() -> Vec<Pose> {
    (0..9)
        .map(|i| Pose::new(i as f64, 0.0, 0.0))
        .chain((0..4).map(|i| Pose::new(8.5, 0.5 + 0.5 * i as f64, std::f64::consts::FRAC_PI_2)))
        .collect()
}

/// The rule on (it is off by default).
fn on() -> IasmConfig {
    IasmConfig {
        array_mirror: true,
        ..IasmConfig::default()
    }
}

fn judged(
    poses: &[Pose],
    sources: Vec<Source>,
    heard: &[[f64; 2]],
) -> (Vec<[f64; 2]>, Vec<Refused>) {
    let mapper = ghost_mapper(on());
    let rows: Vec<Vec<f64>> = poses
        .iter()
        .map(|p| heard.iter().map(|&q| p.bearing_to(q)).collect())
        .collect();
    let complete = mapper.complete_by_length(&rows);
    let stops = stops_with(poses, &rows, &complete, &vec![false; poses.len()]);
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
    // Off (the default), the rule removes nothing.
    let mapper = ghost_mapper(IasmConfig::default());
    let (mut s, mut left) = (sources, vec![Vec::new(); poses.len()]);
    let rows: Vec<Vec<f64>> = poses.iter().map(|p| vec![p.bearing_to(vent)]).collect();
    let complete = mapper.complete_by_length(&rows);
    let stops = stops_with(&poses, &rows, &complete, &vec![false; poses.len()]);
    let refused = mapper.drop_implausible(&mut s, &stops, &mut left);
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
