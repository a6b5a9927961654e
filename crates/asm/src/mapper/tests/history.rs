//! A room that changes while the robot drives: each source's stops and state at the end.

use super::*;
use crate::MapRng;

/// 30 stops along y = 0 (as [`scene`]); a talker at `A` who walks to `B` before stop 15,
/// 2.5 m away, and a machine at `C` that runs throughout, missed by the front end at every
/// third stop. Three stops after the move could have heard `A` (nearer than 1.5 times its
/// furthest hearing, and not masked by `B` or `C`: [`MASKING_RATIO`]), and three before it
/// `B`: just enough for the test of [`SILENT_P`] at the front end's full recall.
const A: [f64; 2] = [1.5, 1.2];
const B: [f64; 2] = [4.0, 1.5];
const C: [f64; 2] = [3.0, -1.5];
const MOVE: usize = 15;

fn changing_room() -> (OccupancyMap, Vec<Pose>, Vec<Vec<f64>>) {
    let (map, poses, _) = scene(&[], 30);
    let doas = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let talker = if k < MOVE { A } else { B };
            let mut row = vec![wrap_rad(p.bearing_to(talker) - p.theta)];
            if k % 3 != 2 {
                row.push(wrap_rad(p.bearing_to(C) - p.theta));
            }
            row
        })
        .collect();
    (map, poses, doas)
}

fn nearest(map: &MapResult, q: [f64; 2]) -> (usize, &Source) {
    map.sources
        .iter()
        .enumerate()
        .min_by(|a, b| {
            let d = |s: &Source| (s.x - q[0]).hypot(s.y - q[1]);
            d(a.1).total_cmp(&d(b.1))
        })
        .unwrap()
}

#[test]
fn a_talker_who_walks_away_is_retired_where_he_stood_and_linked_to_where_he_went() {
    let (map, poses, doas) = changing_room();
    let mapper = Mapper::new(&map, &IasmConfig::default()).unwrap();
    let result = mapper
        .run(&poses, &doas, &mut MapRng::seed_from_u64(SEED))
        .unwrap();
    assert_eq!(result.sources.len(), 3, "{:?}", result.positions());
    let (a, at_a) = nearest(&result, A);
    let (b, at_b) = nearest(&result, B);
    let (_, at_c) = nearest(&result, C);
    for (s, q) in [(at_a, A), (at_b, B), (at_c, C)] {
        assert!((s.x - q[0]).hypot(s.y - q[1]) < 0.1, "{q:?}: {s:?}");
    }
    // The first place: heard up to the move, silent from it on, moved to the second.
    let h = at_a.history;
    assert_eq!((h.first_stop, h.last_stop), (0, MOVE - 1));
    assert_eq!(h.state, SourceState::Silent { since: MOVE });
    assert_eq!(h.moved_to, Some(b), "{:?}", at_b.history);
    // The second: appeared at the move (the stops before it that could hear it did not),
    // sounding at the end.
    let h = at_b.history;
    assert_eq!((h.first_stop, h.appeared_at), (MOVE, Some(MOVE)));
    assert!(h.is_active());
    assert_eq!(h.moved_from, Some(a));
    // The machine: heard at two stops in three all along, active, never appeared. Its
    // recall is two in three, or a little more where the talker, much nearer some stops,
    // may have masked it (those stops are left out of the share).
    let h = at_c.history;
    assert!(h.is_active(), "{h:?}");
    assert_eq!(h.appeared_at, None);
    assert!((0.66..0.85).contains(&h.heard_share), "{h:?}");
    assert_eq!(h.heard_stops, 20);
}

#[test]
fn the_online_mapper_dates_its_sources_as_the_batch_map_does() {
    let (map, poses, doas) = changing_room();
    let mapper = Mapper::new(&map, &IasmConfig::default()).unwrap();
    let batch = mapper
        .run(&poses, &doas, &mut MapRng::seed_from_u64(SEED))
        .unwrap();
    let mut online = crate::online::OnlineMapper::new(mapper, SEED);
    for (p, row) in poses.iter().zip(&doas) {
        online.add_stop(*p, row).unwrap();
    }
    online.consolidate();
    let live = online.map();
    assert_eq!(live.sources.len(), batch.sources.len());
    for q in [A, B, C] {
        let (b, l) = (nearest(&batch, q).1.history, nearest(&live, q).1.history);
        assert_eq!(
            (b.first_stop, b.last_stop, b.state, b.appeared_at),
            (l.first_stop, l.last_stop, l.state, l.appeared_at),
            "{q:?}"
        );
    }
}

#[test]
fn a_stray_hearing_far_from_the_others_does_not_date_a_source() {
    // Heard at stops 0-6 and, by a reflection near its bearing, at 20 and 21: it fell
    // silent after 6, and the two late hearings (fewer than three, more than five stops
    // from the rest) say nothing of when. Heard at 0-6 and 12-14 (three, a second pass):
    // both stretches count.
    let dated = super::super::history::dating(&[0, 1, 2, 3, 4, 5, 6, 20, 21]);
    assert_eq!(dated, vec![0, 1, 2, 3, 4, 5, 6]);
    let dated = super::super::history::dating(&[0, 1, 2, 3, 4, 5, 6, 12, 13, 14]);
    assert_eq!(dated.len(), 10);
    // A gap of five stops is within one stretch (five misses are the fewest that call a
    // source heard at 60 % silent); every stretch stray: all of them count.
    assert_eq!(
        super::super::history::dating(&[0, 1, 2, 7]),
        vec![0, 1, 2, 7]
    );
    assert_eq!(super::super::history::dating(&[0, 1, 2, 8]), vec![0, 1, 2]);
    assert_eq!(super::super::history::dating(&[3, 15]), vec![3, 15]);
}
