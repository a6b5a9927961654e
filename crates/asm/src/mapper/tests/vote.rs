//! The vote: sources that enough stops agree on, and nothing else.

use super::*;

#[test]
fn the_vote_finds_a_source_that_enough_stops_agree_on_and_nothing_else() {
    // Source A heard from 7 stops, source B from the 4 nearest it, and one clutter DoA at every
    // other stop.
    let truth = [[1.5, 1.5], [4.0, -1.2]];
    let (map, poses, _) = scene(&truth, 14);
    let mapper = Mapper::new(&map, &IasmConfig::default()).unwrap();
    let mut bearings: Vec<Vec<f64>> = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            // Strongest first: B's DoA is never its stop's strongest (a cut row's
            // strongest counts in full; see `a_cut_rows_strongest_doa_counts_its_stop_in_full`).
            let mut row = Vec::new();
            if k % 2 == 0 {
                row.push(p.bearing_to(truth[0]) + 0.01);
            }
            if k % 2 == 1 {
                // Away from both sources, and from one another's crossings.
                row.push(crate::wrap_rad(
                    p.bearing_to(truth[0]) + 2.0 + 0.25 * k as f64,
                ));
            }
            if (7..11).contains(&k) {
                row.push(p.bearing_to(truth[1]) - 0.01);
            }
            row
        })
        .collect();
    // Rows as the SSL gave them: every one shorter than N = 4, so none was cut at N
    // (complete); and the same stops had they reported N DoAs each, cut at N (a table
    // of N columns).
    let heard = bearings.clone();
    let no_cut = vec![false; poses.len()];
    let thresholded = vec![true; poses.len()];
    let full = vec![false; poses.len()];
    let before: usize = bearings.iter().map(Vec::len).sum();
    let s = mapper
        .vote(
            &stops_with(&poses, &heard, &full, &no_cut),
            &mut bearings,
            &[],
            1,
        )
        .expect("A has 7 agreeing stops");
    assert!(
        (s.x - 1.5).abs() < 0.05 && (s.y - 1.5).abs() < 0.05,
        "{s:?}"
    );
    assert_eq!(s.observations, 7);
    assert!(s.refined && !s.cluster.is_empty());
    assert_eq!(bearings.iter().map(Vec::len).sum::<usize>(), before - 7);
    // B's 4 stops are fewer than the 5 the vote asks for when rows are full: nothing,
    // and nothing taken.
    let left = bearings.clone();
    assert!(
        mapper
            .vote(
                &stops_with(&poses, &heard, &full, &no_cut),
                &mut bearings,
                &[],
                2
            )
            .is_none()
    );
    assert_eq!(bearings, left);
    // Nor when one of B's stops was thresholded and three cut: at the exchange rate
    // of the two quorums (five cut stops for three thresholded) that is 1 + 3 x 3/5 =
    // 2.8 stops' worth of evidence, short of 3.
    let mut one = full.clone();
    one[7] = true;
    assert!(
        mapper
            .vote(
                &stops_with(&poses, &heard, &one, &no_cut),
                &mut bearings,
                &[],
                2
            )
            .is_none()
    );
    assert_eq!(bearings, left);
    // B, from its four stops.
    let is_b =
        |b: &Source| (b.x - 4.0).abs() < 0.05 && (b.y + 1.2).abs() < 0.05 && b.observations == 4;
    // Two thresholded and two cut are 3.2: B is a source.
    let mut two = one.clone();
    two[8] = true;
    let b = mapper
        .vote(
            &stops_with(&poses, &heard, &two, &no_cut),
            &mut bearings.clone(),
            &[],
            2,
        )
        .expect("B has 2 thresholded and 2 cut agreeing stops");
    assert!(is_b(&b), "{b:?}");
    // But four thresholded stops agreeing on B are a source.
    let b = mapper
        .vote(
            &stops_with(&poses, &heard, &thresholded, &no_cut),
            &mut bearings,
            &[],
            2,
        )
        .expect("B has 4 agreeing thresholded stops");
    assert!(is_b(&b), "{b:?}");
    // With the second quorum off, B is not found.
    let strict = Mapper::new(
        &map,
        &IasmConfig {
            vote_min_thresholded_stops: 0,
            ..IasmConfig::default()
        },
    )
    .unwrap();
    assert!(
        strict
            .vote(
                &stops_with(&poses, &heard, &thresholded, &no_cut),
                &mut left.clone(),
                &[],
                2
            )
            .is_none()
    );
    // The paper profile does not vote.
    let paper = Mapper::new(&map, &IasmConfig::profile(Profile::Paper)).unwrap();
    assert!(
        paper
            .vote(
                &stops_with(&poses, &heard, &thresholded, &no_cut),
                &mut left.clone(),
                &[],
                2
            )
            .is_none()
    );
}

#[test]
fn the_vote_takes_where_rays_meet_over_where_most_rays_pass_near() {
    // Seven stops along y = 0. Five hear source A exactly. All seven hear something
    // near the bearing to a point G across the path: two exactly, five 8 degrees
    // beside it (either side, alternately). More stops pass within the vote's
    // 10-degree gate of G than of A, but at A the rays meet.
    let a = [3.0, 1.2];
    let g = [3.0, -2.5];
    let (map, poses, _) = scene(&[a], 7);
    let mapper = Mapper::new(&map, &IasmConfig::default()).unwrap();
    let mut bearings: Vec<Vec<f64>> = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let side = match k {
                0 | 1 => 0.0,
                _ if k % 2 == 0 => 8.0,
                _ => -8.0,
            };
            let mut row = vec![wrap_rad(p.bearing_to(g) + f64::to_radians(side))];
            if (1..6).contains(&k) {
                row.push(p.bearing_to(a));
            }
            row
        })
        .collect();
    let full = vec![false; poses.len()];
    let heard = bearings.clone();
    let no_cut = vec![false; poses.len()];
    let s = mapper
        .vote(
            &stops_with(&poses, &heard, &full, &no_cut),
            &mut bearings,
            &[],
            1,
        )
        .expect("A has 5 agreeing stops");
    assert!(
        (s.x - a[0]).abs() < 0.02 && (s.y - a[1]).abs() < 0.02,
        "{s:?}"
    );
    assert_eq!(s.observations, 5);
}

#[test]
fn full_rows_that_n_did_not_cut_speak_against_a_ghost() {
    // N = 2. A talker heard from every stop; a ghost G heard by stops 3, 6 and 9 only.
    // Every row is full: the talker and G, or the talker and a DoA along the path
    // (where nothing can be mapped). As a table, a full row may have been cut at N and
    // says nothing against G; told that N cut no row, stops 4, 5, 7 and 8, nearer G
    // than the furthest that heard it, speak against it and G is not a source.
    let a = [1.5, 1.5];
    let g = [6.0 * 6.0 / 13.0, -2.0];
    let (map, poses, _) = scene(&[a], 14);
    let mapper = Mapper::new(
        &map,
        &IasmConfig {
            num_doas: 2,
            ..IasmConfig::default()
        },
    )
    .unwrap();
    let doas: Vec<Vec<f64>> = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let second = if [3, 6, 9].contains(&k) {
                p.bearing_to(g)
            } else {
                0.0
            };
            [p.bearing_to(a), second]
                .iter()
                .map(|&w| wrap_rad(w - p.theta))
                .collect()
        })
        .collect();
    let near = |r: &MapResult, q: [f64; 2]| {
        r.positions()
            .iter()
            .any(|p| (p[0] - q[0]).hypot(p[1] - q[1]) < 0.1)
    };
    let uncut = vec![false; poses.len()];
    for seed in [SEED, SEED + 1, SEED + 2] {
        let mut rng = StdRng::seed_from_u64(seed);
        let table = mapper.run_rows(&poses, &doas, None, &mut rng).unwrap();
        let at = table.positions();
        assert!(near(&table, a) && near(&table, g), "seed {seed}: {at:?}");
        let mut rng = StdRng::seed_from_u64(seed);
        let told = mapper
            .run_rows(&poses, &doas, Some(&uncut), &mut rng)
            .unwrap();
        let at = told.positions();
        assert!(near(&told, a) && !near(&told, g), "seed {seed}: {at:?}");
    }
    assert!(matches!(
        mapper.run_rows(
            &poses,
            &doas,
            Some(&uncut[1..]),
            &mut StdRng::seed_from_u64(SEED)
        ),
        Err(Error::CutMismatch { poses: 14, cut: 13 })
    ));
}

/// A DoA that a vote's source shares with another (`share_gate_sigmas`) is another's
/// too; once that other is removed and gives it back, it is the sharer's own: among its
/// rays and no longer among the unexplained (the corridor's alcove talker held such a DoA
/// that `--explain` listed under both). A second sharer still shares it with the first.
#[test]
fn a_shared_doa_whose_owner_is_gone_is_the_sharers_own() {
    let poses: Vec<Pose> = (0..5).map(|i| Pose::new(f64::from(i), 0.0, 0.0)).collect();
    let mut first = heard_from([2.0, 3.0], &poses, &[0, 1, 2, 3, 4]);
    let mut second = heard_from([2.1, 3.0], &poses, &[0, 1, 2]);
    first.rays[2].shared = true;
    second.rays[2] = Ray {
        shared: true,
        ..first.rays[2]
    };
    // Given back by its owner, removed.
    let mut pool = vec![Vec::new(); poses.len()];
    pool[2].push(first.rays[2].bearing);
    let mut sources = vec![first, second];
    crate::mapper::rules::own_orphaned_shares(&mut sources, &mut pool);
    assert!(pool.iter().all(Vec::is_empty), "{pool:?}");
    assert!(!sources[0].rays[2].shared);
    assert!(sources[1].rays[2].shared);
    // Nothing else moves: a DoA that another source explains stays shared.
    let mut again = vec![Vec::new(); poses.len()];
    sources[0].rays[3].shared = true;
    crate::mapper::rules::own_orphaned_shares(&mut sources, &mut again);
    assert!(sources[0].rays[3].shared);
}
