//! The plausibility rules and reassociation: ghosts of reflections refused, real sources
//! kept.

use super::*;
use crate::mapper::rules::mirror_in_line;

/// A source heard from three stops whose rows the SSL cut at `N` is clutter; from
/// five cut stops, or two cut and two that heard all they reported (3/5 each: 3.2), a
/// source; from three stops the SSL said nothing about (a published table's full rows)
/// or with the vote off (the paper profile), a source as before.
#[test]
fn stops_the_ssl_cut_count_at_the_votes_rate() {
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let talker = [4.0, -3.0];
    // Each stop's strongest DoA another source's, across the path: the talker's is its
    // second (a cut row's strongest counts in full).
    let heard: Vec<Vec<f64>> = poses
        .iter()
        .map(|p| vec![p.bearing_to([4.0, 3.0]), p.bearing_to(talker)])
        .collect();
    // No row is complete: no stop speaks against the talker.
    let complete = vec![false; poses.len()];
    let kept = |mapper: &Mapper, stops: &[usize], cut: &[usize]| {
        let mut sources = vec![heard_from(talker, &poses, stops)];
        let said_cut: Vec<bool> = (0..poses.len()).map(|k| cut.contains(&k)).collect();
        let mut left = vec![Vec::new(); poses.len()];
        mapper.drop_implausible(
            &mut sources,
            &stops_with(&poses, &heard, &complete, &said_cut),
            &mut left,
        );
        sources.len()
    };
    let robust = ghost_mapper(IasmConfig::default());
    assert_eq!(kept(&robust, &[2, 4, 6], &[2, 4, 6]), 0);
    assert_eq!(kept(&robust, &[2, 4, 6], &[]), 1);
    assert_eq!(kept(&robust, &[0, 2, 4, 6, 8], &[0, 2, 4, 6, 8]), 1);
    assert_eq!(kept(&robust, &[0, 2, 4, 6], &[0, 2]), 1);
    assert_eq!(kept(&robust, &[0, 2, 4, 6], &[0, 2, 4]), 0);
    let paper = ghost_mapper(IasmConfig::profile(Profile::Paper));
    assert_eq!(kept(&paper, &[2, 4, 6], &[2, 4, 6]), 1);
}

#[test]
fn nearer_stops_that_heard_nothing_unmake_a_source_of_three_stops() {
    let (mapper, poses, heard, mut sources) = ghost_survey(&[]);
    let mut left: Vec<Vec<f64>> = vec![Vec::new(); poses.len()];
    // Stops 1-3 speak against the ghost; the first is forgiven, two remain.
    let others = [[sources[0].x, sources[0].y]];
    assert_eq!(against_the_ghost(&mapper, &poses, &heard, &others).len(), 3);
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        1
    );
    assert_eq!(sources.len(), 1);
    assert_eq!((sources[0].x, sources[0].y), (4.0, -3.0));
    // The ghost's DoAs are unexplained again.
    assert_eq!(
        left.iter().map(Vec::len).collect::<Vec<_>>(),
        [1, 0, 0, 0, 1, 1, 0, 0, 0]
    );
}

#[test]
fn a_map_leaves_out_the_ghost_that_no_absence_check_keeps() {
    // The stops of `ghost_survey`, the talker heard from all; a ghost at (4, 1) heard
    // from stops 0-2, 7 and 8 (3-4 m away) and missed by stops 3-6 (1-2.2 m away),
    // whose rows hold one DoA of N = 3.
    let (mapper, poses, _, _) = ghost_survey(&[]);
    let (talker, ghost) = ([4.0, -3.0], [4.0, 1.0]);
    let doas = rows(&poses, talker, ghost, |k| !(3..7).contains(&k));
    let unchecked = ghost_mapper(IasmConfig {
        absence_ratio: 0.0,
        ..IasmConfig::default()
    });
    for seed in 0..5 {
        // Headings are 0: the DoAs are the world bearings.
        let robust = mapper
            .run(&poses, &doas, &mut StdRng::seed_from_u64(seed))
            .unwrap();
        let found = robust.positions();
        assert_eq!(found.len(), 1, "seed {seed}: {found:?}");
        assert!(
            (found[0][0] - 4.0).hypot(found[0][1] + 3.0) < 0.05,
            "{found:?}"
        );
        // The vote proposes the ghost and, the stops between contradicting it, leaves
        // its DoAs unexplained: nothing is found to be removed.
        assert_eq!((robust.removed, robust.unexplained), (0, 5), "seed {seed}");
        let p = unchecked
            .run(&poses, &doas, &mut StdRng::seed_from_u64(seed))
            .unwrap();
        let near = |q: &[f64; 2]| (q[0] - ghost[0]).hypot(q[1] - ghost[1]) < 0.3;
        assert!(
            p.positions().iter().any(near),
            "seed {seed}: {:?}",
            p.positions()
        );
        assert_eq!(p.removed, 0);
    }
}

#[test]
fn full_rows_and_a_single_miss_speak_against_nothing() {
    // Rows of N DoAs say nothing about what else was there (the authors' tables).
    let (mapper, poses, heard, mut sources) = ghost_survey(&[1, 2, 3]);
    let mut left = vec![Vec::new(); poses.len()];
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        0
    );
    // One stop's miss is forgiven (a pause, a louder moment of another source).
    let (mapper, poses, heard, mut sources) = ghost_survey(&[1, 3]);
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        0
    );
    // The paper's algorithm knows no absences.
    let (_, poses, heard, mut sources) = ghost_survey(&[]);
    let paper = ghost_mapper(IasmConfig::profile(Profile::Paper));
    assert_eq!(
        paper
            .drop_implausible(&mut sources, &by_length(&paper, &poses, &heard), &mut left)
            .len(),
        0
    );
    assert_eq!(sources.len(), 2);
}

#[test]
fn each_removed_source_carries_the_rule_that_removed_it() {
    // The ghost survey's ghost (2, 1.5), spoken against by stops 1-3; a source 0.1 m
    // from stop 7 (nearer than `min_range_m`); and one at (6, 2) heard from stops 6-8
    // only, whose rows the SSL cut (three cut stops are 1.8 of the three a source
    // needs). The talker stays.
    let (mapper, poses, heard, mut sources) = ghost_survey(&[]);
    sources.push(heard_from([7.0, 0.1], &poses, &[4, 5, 6]));
    sources.push(heard_from([6.0, 2.0], &poses, &[6, 7, 8]));
    let said_cut: Vec<bool> = (0..poses.len()).map(|k| k >= 6).collect();
    let complete: Vec<bool> = mapper
        .complete_by_length(&heard)
        .iter()
        .zip(&said_cut)
        .map(|(&c, &cut)| c && !cut)
        .collect();
    let mut left = vec![Vec::new(); poses.len()];
    let refused = mapper.drop_implausible(
        &mut sources,
        &stops_with(&poses, &heard, &complete, &said_cut),
        &mut left,
    );
    assert_eq!(sources.len(), 1);
    assert_eq!((sources[0].x, sources[0].y), (4.0, -3.0));
    let got: Vec<([f64; 2], Vec<usize>, Refusal)> = refused
        .into_iter()
        .map(|r| ([r.x, r.y], r.stops, r.rule))
        .collect();
    assert_eq!(
        got,
        vec![
            (
                [2.0, 1.5],
                vec![0, 4, 5],
                Refusal::SpokenAgainst {
                    against: vec![1, 2, 3]
                }
            ),
            ([7.0, 0.1], vec![4, 5, 6], Refusal::Misplaced),
            ([6.0, 2.0], vec![6, 7, 8], Refusal::ThinlyHeard),
        ]
    );
    // Their DoAs went back: nine, three per removed source.
    assert_eq!(left.iter().map(Vec::len).sum::<usize>(), 9);
}

/// A cloud that settled on a talker's rays, short of it, took the talker's DoAs of
/// stops 4-8 (what the rounds' greedy association does): once the talker is mapped,
/// every DoA it fits better goes to it, and the "ghost", left with the one stop whose
/// ray passes through it, is refused as reassigned and gives that DoA back. A second
/// source keeps its own DoAs.
#[test]
fn doas_go_to_the_source_they_fit_best_and_a_ghost_made_of_them_is_refused() {
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let (talker, other) = ([2.0, 3.0], [6.0, -2.5]);
    // 60 % of the way from stop 5 to the talker: on stop 5's ray, off the others'.
    let ghost = [5.0 + 0.6 * (talker[0] - 5.0), 0.6 * talker[1]];
    let mut mapped = vec![
        heard_from(talker, &poses, &[0, 1, 2, 3]),
        holding(ghost, talker, &poses, &[4, 5, 6, 7, 8]),
        heard_from(other, &poses, &[2, 4, 5, 6, 7]),
    ];
    let mapper = ghost_mapper(IasmConfig::default());
    let mut left = vec![Vec::new(); poses.len()];
    let refused = mapper.reassociate(&mut mapped, &mut left);
    assert_eq!(
        refused,
        vec![Refused {
            x: ghost[0],
            y: ghost[1],
            stops: vec![5],
            rule: Refusal::Reassigned
        }]
    );
    assert_eq!(mapped.len(), 2);
    let stops = |s: &Source| s.rays.iter().map(|r| r.stop).collect::<Vec<_>>();
    assert_eq!(stops(&mapped[0]), vec![0, 1, 2, 3, 4, 6, 7, 8]);
    assert_eq!(mapped[0].observations, 8);
    assert!((mapped[0].x - talker[0]).hypot(mapped[0].y - talker[1]) < 1e-6);
    assert_eq!(stops(&mapped[1]), vec![2, 4, 5, 6, 7]);
    assert_eq!((mapped[1].x, mapped[1].y), (other[0], other[1]));
    // Stop 5's DoA went back to be explained by nothing.
    let back: Vec<usize> = (0..poses.len()).filter(|&k| !left[k].is_empty()).collect();
    assert_eq!(back, vec![5]);
    assert!((left[5][0] - poses[5].bearing_to(talker)).abs() < 1e-12);

    // The paper's algorithm keeps its greedy association (Table I).
    assert!(!IasmConfig::profile(Profile::Paper).reassociate);
}

/// A cloud that settled on a talker's rays passes the absence check with the talker's
/// DoAs; once they go to the talker, it is judged again on what it keeps.
#[test]
fn a_source_is_judged_again_on_the_doas_reassociation_leaves_it() {
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let talker = [2.0, 3.0];
    // 60 % of the way from stop 5 to the talker: on stop 5's ray, and within 4-6
    // degrees of the talker's bearing from stops 6-8.
    let ghost = [5.0 + 0.6 * (talker[0] - 5.0), 0.6 * talker[1]];
    // Every stop hears the talker; stops 0 and 1 hear a reflection through the ghost.
    let heard = rows(&poses, talker, ghost, |k| k < 2);
    let mut ghost_source = heard_from(ghost, &poses, &[0, 1]);
    ghost_source
        .rays
        .extend(holding(ghost, talker, &poses, &[4, 5, 6, 7, 8]).rays);
    ghost_source.observations = ghost_source.rays.len();
    let mapper = ghost_mapper(IasmConfig::default());
    let complete = mapper.complete_by_length(&heard);
    // Stops 2 and 3 hear the talker 25-34 degrees from the ghost's bearing, stop 4
    // 9.7 degrees from it and on the talker's: three absences, the first forgiven,
    // against seven stops.
    let reach = 5.2;
    let others = [talker];
    assert_eq!(
        mapper.absences(
            ghost,
            reach,
            &stops_with(&poses, &heard, &complete, &vec![false; poses.len()]),
            &others
        ),
        vec![2, 3, 4]
    );
    let mut sources = vec![heard_from(talker, &poses, &[0, 1, 2, 3]), ghost_source];
    let mut left = vec![Vec::new(); poses.len()];
    let said_cut = vec![false; poses.len()];
    let refused = mapper.settle(
        &mut sources,
        &stops_with(&poses, &heard, &complete, &said_cut),
        &mut left,
    );
    // Reassociated, the ghost keeps stops 0, 1 and 5 (where the two bearings are one):
    // three stops against the same three absences is too few.
    assert_eq!(
        sources.len(),
        1,
        "{:?}",
        sources.iter().map(|s| (s.x, s.y)).collect::<Vec<_>>()
    );
    assert!((sources[0].x - talker[0]).hypot(sources[0].y - talker[1]) < 1e-6);
    assert_eq!(refused.len(), 1);
    assert_eq!(refused[0].stops, vec![0, 1, 5]);
    assert!(
        matches!(refused[0].rule, Refusal::SpokenAgainst { .. }),
        "{:?}",
        refused[0]
    );
}

/// Within `gamma` of a ghost's bearing lies another source's DoA: it excuses the stop
/// only if it could be the ghost's own (a miss under 1.5 `sigma`) or fits no other
/// source within a `sigma`.
#[test]
fn a_doa_that_another_source_fits_does_not_excuse_a_miss() {
    let (mapper, poses, heard0, _) = ghost_survey(&[]);
    let ghost = [2.0, 1.5];
    // A source 5 m from stop k (1-3) seen `deg` degrees from the ghost's bearing.
    let beside = |k: usize, deg: f64| {
        let b = poses[k].bearing_to(ghost) + deg.to_radians();
        [poses[k].x + 5.0 * b.cos(), poses[k].y + 5.0 * b.sin()]
    };
    for (deg, mapped, against) in [
        (10.0, true, vec![1, 2, 3]),
        // Half a sigma within the ghost's own reach: the ghost's DoA as likely.
        (5.0, true, vec![]),
        // Nobody else's: the stop may have heard the ghost 10 degrees off.
        (10.0, false, vec![]),
    ] {
        let mut heard = heard0.clone();
        let mut others = vec![[4.0, -3.0]];
        for k in 1..4 {
            let q = beside(k, deg);
            heard[k].push(poses[k].bearing_to(q));
            if mapped {
                others.push(q);
            }
        }
        assert_eq!(
            against_the_ghost(&mapper, &poses, &heard, &others),
            against,
            "{deg} degrees off, mapped: {mapped}"
        );
    }
    // The degrees above are 2, 1 and 2 sigma.
    assert_eq!(IasmConfig::default().sigma_deg, 5.0);
}

/// Two clouds that split a talker's cut stops between them are each too thinly heard
/// and together one source; two that hold different talkers' stops are not joined.
#[test]
fn a_talkers_stops_split_between_two_thin_sources_are_joined() {
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let (talker, other) = ([2.0, 3.0], [6.0, -2.5]);
    // Each row's strongest DoA a louder source's, across the path.
    let loud = [8.0, 4.0];
    let heard: Vec<Vec<f64>> = poses
        .iter()
        .map(|p| {
            vec![
                p.bearing_to(loud),
                p.bearing_to(talker),
                p.bearing_to(other),
            ]
        })
        .collect();
    // Every row cut at N: four stops are 2.4 of the three stops' worth a source needs.
    let said_cut = vec![true; poses.len()];
    let complete = vec![false; poses.len()];
    let mapper = ghost_mapper(IasmConfig::default());
    let run = |mut sources: Vec<Source>| {
        let mut left = vec![Vec::new(); poses.len()];
        let refused = mapper.drop_implausible(
            &mut sources,
            &stops_with(&poses, &heard, &complete, &said_cut),
            &mut left,
        );
        (sources, refused)
    };
    // Either side of the talker, each holding four of its stops (one in common).
    let (kept, refused) = run(vec![
        holding([1.8, 2.5], talker, &poses, &[0, 1, 2, 3]),
        holding([2.3, 3.6], talker, &poses, &[3, 4, 5, 6]),
    ]);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(kept.len(), 1);
    assert!(
        (kept[0].x - talker[0]).hypot(kept[0].y - talker[1]) < 1e-6,
        "{:?}",
        kept[0]
    );
    assert_eq!(stops_of(&kept[0].rays), (0..7).collect::<Vec<_>>());
    // Four stops of one talker and four of another meet nowhere: both refused.
    let (kept, refused) = run(vec![
        holding([1.8, 2.5], talker, &poses, &[0, 1, 2, 3]),
        holding([6.2, -2.0], other, &poses, &[4, 5, 6, 7]),
    ]);
    assert!(kept.is_empty(), "{kept:?}");
    assert_eq!(refused.len(), 2);
    assert!(
        refused.iter().all(|r| r.rule == Refusal::ThinlyHeard),
        "{refused:?}"
    );
}

/// A source the rounds left with too few of its stops takes the remaining DoAs that
/// fit its refitted place (within the vote's gate, 2 `sigma`) before it is judged, and
/// keeps none that miss it by more; without them it is refused as before.
#[test]
fn a_thinly_heard_source_takes_the_remaining_doas_that_fit_it() {
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let talker = [2.0, 3.0];
    let loud = [8.0, 4.0];
    let heard: Vec<Vec<f64>> = poses
        .iter()
        .map(|p| vec![p.bearing_to(loud), p.bearing_to(talker)])
        .collect();
    // Every row cut at N: four stops are 2.4 of the three stops' worth a source needs.
    let said_cut = vec![true; poses.len()];
    let complete = vec![false; poses.len()];
    let mapper = ghost_mapper(IasmConfig::default());
    let gate = 2.0 * mapper.sigma;
    let off = |k: usize, deg: f64| poses[k].bearing_to(talker) + deg.to_radians();
    let run = |mut left: Vec<Vec<f64>>| {
        // Where the round left it: 0.54 m short of the talker, on its rays from 0-3.
        let mut sources = vec![holding([1.8, 2.5], talker, &poses, &[0, 1, 2, 3])];
        let refused = mapper.drop_implausible(
            &mut sources,
            &stops_with(&poses, &heard, &complete, &said_cut),
            &mut left,
        );
        (sources, refused, left)
    };
    // Stops 4 and 5 heard it 1 degree off; stop 6, 12 degrees off, within the gate
    // of where the round left it (5.9 degrees) but not of where its rays meet.
    let mut left = vec![Vec::new(); poses.len()];
    left[4].push(off(4, 1.0));
    left[5].push(off(5, -1.0));
    left[6].push(off(6, 12.0));
    let q = [1.8, 2.5];
    assert!(wrap_rad(poses[6].bearing_to(q) - left[6][0]).abs() < gate);
    let (kept, refused, left) = run(left);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(stops_of(&kept[0].rays), vec![0, 1, 2, 3, 4, 5]);
    // Four exact rays and two 1 degree off, 3.6 and 4.2 m away: within 0.03 m.
    let err = (kept[0].x - talker[0]).hypot(kept[0].y - talker[1]);
    assert!(err < 0.03, "{:?} is {err} m off", kept[0]);
    assert!(left[4].is_empty() && left[5].is_empty());
    assert_eq!(left[6].len(), 1, "the stray DoA stays unexplained");
    // The same DoAs 12 degrees off: nothing fits, and the source is refused.
    let mut left = vec![Vec::new(); poses.len()];
    left[4].push(off(4, 12.0));
    left[5].push(off(5, -12.0));
    let (kept, refused, _) = run(left);
    assert!(kept.is_empty(), "{kept:?}");
    assert_eq!(refused.len(), 1);
    assert_eq!(refused[0].rule, Refusal::ThinlyHeard);
}

#[test]
fn stops_that_heard_nothing_at_all_speak_against_nothing() {
    // The ghost survey, with the three stops that missed the ghost silent instead
    // (empty rows: nothing significant at all): silence says nothing of any source.
    let (mapper, poses, mut heard, mut sources) = ghost_survey(&[]);
    for row in &mut heard[1..4] {
        row.clear();
    }
    let others = [[sources[0].x, sources[0].y]];
    assert_eq!(against_the_ghost(&mapper, &poses, &heard, &others).len(), 0);
    let mut left = vec![Vec::new(); poses.len()];
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        0
    );
}

#[test]
fn a_much_nearer_source_masks_a_miss() {
    // A third source 0.5-1.1 m from stops 1-3, heard there: beside it the ghost, 1.5
    // times further or more, may be lost under its peak, so those stops say nothing.
    let (mapper, poses, mut heard, mut sources) = ghost_survey(&[]);
    let near = [2.0, -0.5];
    for k in 1..4 {
        heard[k].push(poses[k].bearing_to(near));
    }
    sources.push(heard_from(near, &poses, &[1, 2, 3]));
    let others = [[4.0, -3.0], near];
    assert_eq!(against_the_ghost(&mapper, &poses, &heard, &others).len(), 0);
    let mut left = vec![Vec::new(); poses.len()];
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        0
    );
}

#[test]
fn a_removed_ghost_masks_no_stop() {
    // As above, but the source beside stops 1-3 is itself a ghost: heard only from
    // stops 6-8, 4-6 m away, and missed by every nearer stop. It is removed, and then
    // stops 1-3 speak against the first ghost too.
    let (mapper, poses, mut heard, mut sources) = ghost_survey(&[]);
    let near = [2.0, -0.5];
    for k in 6..9 {
        heard[k].push(poses[k].bearing_to(near));
    }
    sources.push(heard_from(near, &poses, &[6, 7, 8]));
    let mut left = vec![Vec::new(); poses.len()];
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        2
    );
    assert_eq!(sources.len(), 1);
    assert_eq!((sources[0].x, sources[0].y), (4.0, -3.0));
}

#[test]
fn a_mirror_image_beyond_the_map_is_no_source() {
    // The map of `ghost_mapper` ends at y = 4. Stops 0-5 hear the talker and a
    // reflection whose bearings meet at its image (4, 6), beyond the map; the cloud,
    // drawn on the map, settled by the wall at (4, 3.5). Rows are full (N = 3), so no
    // absence speaks.
    let (mapper, poses, mut heard, mut sources) = ghost_survey(&[]);
    let image = [4.0, 6.0];
    sources.truncate(1);
    for (k, row) in heard.iter_mut().enumerate() {
        row.truncate(1);
        if k < 6 {
            row.push(poses[k].bearing_to(image));
        }
        while row.len() < 3 {
            row.push(-std::f64::consts::FRAC_PI_2 * (1.0 + 0.1 * row.len() as f64));
        }
    }
    let mut ghost = heard_from(image, &poses, &[0, 1, 2, 3, 4, 5]);
    (ghost.x, ghost.y) = (4.0, 3.5);
    sources.push(ghost);
    let mut left = vec![Vec::new(); poses.len()];
    let kept = ghost_mapper(IasmConfig {
        beyond_map_m: 0.0,
        ..IasmConfig::default()
    });
    assert_eq!(
        kept.drop_implausible(
            &mut sources.clone(),
            &by_length(&kept, &poses, &heard),
            &mut left
        )
        .len(),
        0
    );
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        1
    );
    assert_eq!(sources.len(), 1);
    assert_eq!((sources[0].x, sources[0].y), (4.0, -3.0));
}

#[test]
fn a_point_is_mirrored_in_the_line_its_wall_points_lie_on() {
    // Points on y = x + 1 (a wall at 45 degrees): (3, 0) mirrors to (-1, 4).
    let wall = [[0.0, 1.0], [1.0, 2.0], [2.5, 3.5], [-1.0, 0.0]];
    let m = mirror_in_line([3.0, 0.0], &wall, 0.5).unwrap();
    assert!(
        (m[0] + 1.0).abs() < 1e-12 && (m[1] - 4.0).abs() < 1e-12,
        "{m:?}"
    );
    // A stretch shorter than asked says nothing of the wall's direction.
    assert!(mirror_in_line([3.0, 0.0], &wall[..2], 2.0).is_none());
}

#[test]
fn a_source_heard_through_a_wall_is_its_image_in_the_wall() {
    // The image's rays meet at (4, 2.9), behind the wall and inside the map's box (no
    // further than `beyond_map_m` beyond it); its cloud, drawn on the known cells,
    // settled against the wall at (4, 1.9). Mirrored in the wall's face (y = 2.0, its
    // first cells' centres at 2.025), it lands at (4, 1.15), 0.05 m from the talker.
    let removed = |config: IasmConfig, door: bool, talker: bool| {
        let (mapper, poses, heard) = walled_room(config, door);
        let all: Vec<usize> = (0..9).collect();
        let mut image = heard_from([4.0, 2.9], &poses, &all);
        (image.x, image.y) = (4.0, 1.9);
        let mut sources = vec![image];
        if talker {
            sources.insert(0, heard_from([4.0, 1.2], &poses, &all));
        }
        let before = sources.len();
        let mut left = vec![Vec::new(); poses.len()];
        let complete = mapper.complete_by_length(&heard);
        mapper.drop_implausible(
            &mut sources,
            &stops_with(&poses, &heard, &complete, &vec![false; poses.len()]),
            &mut left,
        );
        assert!(!talker || sources.iter().any(|s| (s.x, s.y) == (4.0, 1.2)));
        sources.len() < before
    };
    assert!(removed(IasmConfig::default(), false, true));
    // With the rule off, the rays are still the talker's reflections in the wall
    // (`reflections`): removed all the same.
    let off = IasmConfig {
        wall_clearance_m: 0.0,
        ..IasmConfig::default()
    };
    assert!(removed(off.clone(), false, true));
    // Both rules off (the paper profile's values), or the wall opened by a door that
    // every ray passes through, or no source in front of the wall to be mirrored (a
    // talker behind a counter): a source.
    let off = IasmConfig {
        reflections: false,
        ..off
    };
    assert!(!removed(off, false, true));
    assert!(!removed(IasmConfig::default(), true, true));
    assert!(!removed(IasmConfig::default(), false, false));
    // A clearance of 1 m, more than the image's 0.8 m behind the wall's far face,
    // leaves the wall in the way of the slanted rays of stops 0-2 and 6-8 only: kept
    // (by this rule; `reflections` off).
    let wide = IasmConfig {
        wall_clearance_m: 1.0,
        reflections: false,
        ..IasmConfig::default()
    };
    assert!(!removed(wide, false, true));
}

#[test]
fn no_source_stands_where_the_robot_stood() {
    // A cluster 0.2 m from a stop, with DoAs of every stop along the line of travel.
    let (mapper, poses, heard, mut sources) = ghost_survey(&[1, 2, 3]);
    sources.push(heard_from([6.2, 0.0], &poses, &[0, 1, 2, 3, 4, 5]));
    let mut left = vec![Vec::new(); poses.len()];
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &by_length(&mapper, &poses, &heard), &mut left)
            .len(),
        1
    );
    assert_eq!(sources.len(), 2);
    assert_eq!(left.iter().map(Vec::len).sum::<usize>(), 6);
}

#[test]
fn a_doa_that_two_sources_lie_on_is_evidence_for_both() {
    // B at (3, 1) is heard exactly from stops 7 and 9 (thresholded rows) and 11 (a row
    // cut at N): 1 + 1 + 3/5 = 2.6 stops' worth, short of 3. From stop 5, A stands
    // 1.5 m further along the same ray and has taken that stop's one DoA.
    let b = [3.0, 1.0];
    let (map, poses, _) = scene(&[], 14);
    let from = poses[5].position();
    let a = [
        from[0] + 2.5 * (b[0] - from[0]),
        from[1] + 2.5 * (b[1] - from[1]),
    ];
    let mut bearings: Vec<Vec<f64>> = vec![Vec::new(); poses.len()];
    for k in [7, 9, 11] {
        bearings[k].push(poses[k].bearing_to(b));
    }
    let mut heard = bearings.clone();
    heard[5].push(poses[5].bearing_to(a));
    // Stop 11's strongest DoA was another source's (explained): B's is its second.
    heard[11].insert(0, crate::wrap_rad(poses[11].bearing_to(b) + 1.5));
    let mut complete = vec![true; poses.len()];
    complete[11] = false;
    let vote = |config: IasmConfig, heard: &[Vec<f64>], complete: &[bool]| {
        let said_cut = vec![false; poses.len()];
        Mapper::new(&map, &config).unwrap().vote(
            &stops_with(&poses, heard, complete, &said_cut),
            &mut bearings.clone(),
            &[a],
            2,
        )
    };
    // Shared, stop 5 counts 3/5 more: 3.2, and B is a source; the DoA stays A's.
    let s = vote(IasmConfig::default(), &heard, &complete).expect("3.2 stops' worth");
    assert!((s.x - b[0]).hypot(s.y - b[1]) < 0.05, "{s:?}");
    let shared: Vec<(usize, bool)> = s.rays.iter().map(|r| (r.stop, r.shared)).collect();
    assert_eq!(shared, [(5, true), (7, false), (9, false), (11, false)]);
    let mut back = vec![Vec::new(); poses.len()];
    s.rays[0].give_back(&mut back);
    assert!(back[5].is_empty());
    // Not with sharing off, nor where stop 5's row was filled up to N (a table's row,
    // which holds reflections too).
    let off = IasmConfig {
        share_gate_sigmas: 0.0,
        ..IasmConfig::default()
    };
    assert!(vote(off, &heard, &complete).is_none());
    let mut full_at_5 = complete.clone();
    full_at_5[5] = false;
    assert!(vote(IasmConfig::default(), &heard, &full_at_5).is_none());
    // Nor when A's ray passes B by more than half a sigma (2.5 degrees).
    heard[5][0] += 3f64.to_radians();
    assert!(vote(IasmConfig::default(), &heard, &complete).is_none());
}

#[test]
fn a_source_that_starts_while_the_robot_drives_is_not_spoken_against_by_the_stops_before() {
    // A talker at (4, -3) heard by every stop, and one at (5, 1.5) who starts talking at
    // stop 5 and is heard by stops 5-8 (1.5-3.4 m away). Stops 2-4, 1.8-3.4 m from him and
    // with room in their rows, missed him: before he spoke. They are no nearer than the
    // stops that heard him, so they say nothing (a source heard by them had it sounded
    // then would also have been heard from the nearer stops of its own time).
    let (mapper, ..) = ghost_survey(&[]);
    let poses: Vec<Pose> = (0..9).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
    let (talker, starter) = ([4.0, -3.0], [5.0, 1.5]);
    let heard = rows(&poses, talker, starter, |k| k >= 5);
    let stops = by_length(&mapper, &poses, &heard);
    let mut sources = vec![
        heard_from(talker, &poses, &(0..9).collect::<Vec<_>>()),
        heard_from(starter, &poses, &[5, 6, 7, 8]),
    ];
    // The stops that missed him are absences by place: within his reach, rows complete.
    let absent = mapper.absences(starter, 3.4, &stops, &[talker]);
    assert!([2, 3, 4].iter().all(|k| absent.contains(k)), "{absent:?}");
    let mut left = vec![Vec::new(); poses.len()];
    assert_eq!(
        mapper
            .drop_implausible(&mut sources, &stops, &mut left)
            .len(),
        0
    );
    assert_eq!(sources.len(), 2);
}
