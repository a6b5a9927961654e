//! A map of a scene that changed, judged against what changed: the sources sounding at the
//! end, and the stop of each change.
//!
//! A scene's sources may play over a range of stops and move ([`sim::scene::Place`]). A
//! map made after the last stop says of each source whether it still sounds and, if not,
//! since when ([`asm::History`]). Two figures follow:
//!
//! - the OSPA of the map's active sources against the places sounding at the last stop
//!   (what the room holds now);
//! - for each change (a place whose source stops playing there before the last stop, or
//!   starts after the first), whether the map's source nearest that place (within
//!   [`MATCH_M`]) dates it within [`CHANGE_TOLERANCE_STOPS`] of the first stop that could
//!   tell: a place left is `silent since`, a place taken `appeared at`, the first stop at
//!   or after the change with a line of sight to the place.
//!
//! A change the robot could not hear happen is not judged: one that no stop before it and
//! none after it sees (a talker who leaves a side room the robot looked into only before,
//! or starts in one it reaches only after). The map cannot know of it, and the time the
//! robot next looks is the earliest it could say. `ChangeScore::unseen` counts them.

use asm::MapResult;
use sim::scene::Place;

/// A mapped source further than this from a place is not that place's (m): half the
/// OSPA's cut-off, the distance beyond which a source is counted missed.
pub const MATCH_M: f64 = 0.5;

/// A change dated within this many stops of the truth is found.
pub const CHANGE_TOLERANCE_STOPS: usize = 2;

/// A change of a scene: a source left a place or took one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// A place (an index of the places) is silent from stop `since` on.
    Left {
        /// The place.
        place: usize,
        /// The first stop at which it is silent.
        since: usize,
    },
    /// A place sounds from stop `at` on.
    Took {
        /// The place.
        place: usize,
        /// The first stop at which it sounds.
        at: usize,
    },
}

/// The changes of a run of `n_stops` stops over `places`.
pub fn changes(places: &[Place], n_stops: usize) -> Vec<Change> {
    let last = n_stops.saturating_sub(1);
    let mut out = Vec::new();
    for (i, p) in places.iter().enumerate() {
        if p.stops[0] > 0 {
            out.push(Change::Took {
                place: i,
                at: p.stops[0],
            });
        }
        if p.stops[1] < last {
            out.push(Change::Left {
                place: i,
                since: p.stops[1] + 1,
            });
        }
    }
    out
}

/// How a map made after the last of `n_stops` stops meets a scene's changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangeScore {
    /// OSPA (m, p = 1, c = 1) of the map's active sources against the places sounding at
    /// the last stop.
    pub ospa_now: f64,
    /// The scene's changes that some stop before and some stop after could see.
    pub changes: usize,
    /// Changes no stop could see happen (not judged).
    pub unseen: usize,
    /// Those the map dates within [`CHANGE_TOLERANCE_STOPS`].
    pub found: usize,
}

impl ChangeScore {
    /// Whether every change was found.
    pub fn all_found(&self) -> bool {
        self.found == self.changes
    }
}

/// Judges `map` against `places` heard from `stops` (the robot's positions, m), `sees`
/// saying whether a stop has a line of sight to a place (see the module docs).
pub fn judge(
    map: &MapResult,
    places: &[Place],
    stops: &[[f64; 2]],
    sees: &dyn Fn([f64; 2], [f64; 2]) -> bool,
) -> ChangeScore {
    let n_stops = stops.len();
    let last = n_stops.saturating_sub(1);
    let now: Vec<[f64; 2]> = places
        .iter()
        .filter(|p| p.plays_at(last))
        .map(|p| [p.pos[0], p.pos[1]])
        .collect();
    let active: Vec<[f64; 2]> = map
        .sources
        .iter()
        .filter(|s| s.history.is_active())
        .map(|s| [s.x, s.y])
        .collect();
    let ospa_now = asm::ospa::ospa(&active, &now, 1.0, 1.0).total;
    let nearest = |place: usize| {
        let q = places[place].pos;
        map.sources
            .iter()
            .map(|s| ((s.x - q[0]).hypot(s.y - q[1]), s))
            .filter(|(d, _)| *d <= MATCH_M)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, s)| s.history)
    };
    let within = |a: usize, b: usize| a.abs_diff(b) <= CHANGE_TOLERANCE_STOPS;
    // The first stop at or after `k` that sees `place`, if a stop before `k` sees it too.
    let first_seen = |place: usize, k: usize| {
        let q = [places[place].pos[0], places[place].pos[1]];
        let seen = |j: usize| sees(stops[j], q);
        ((0..k).any(seen))
            .then(|| (k..n_stops).find(|&j| seen(j)))
            .flatten()
    };
    let all = changes(places, n_stops);
    let (mut judged, mut found) = (0, 0);
    for c in &all {
        let (place, at) = match *c {
            Change::Left { place, since } => (place, since),
            Change::Took { place, at } => (place, at),
        };
        let Some(due) = first_seen(place, at) else {
            continue;
        };
        judged += 1;
        let dated = match c {
            Change::Left { .. } => nearest(place).and_then(|h| h.silent_since()),
            Change::Took { .. } => nearest(place).and_then(|h| h.appeared_at),
        };
        found += usize::from(dated.is_some_and(|k| within(k, due)));
    }
    ChangeScore {
        ospa_now,
        changes: judged,
        unseen: all.len() - judged,
        found,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asm::{History, SourceState};

    fn place(source: usize, x: f64, stops: [usize; 2]) -> Place {
        Place {
            source,
            pos: [x, 1.0, 1.2],
            stops,
        }
    }

    fn mapped(x: f64, history: History) -> asm::Source {
        asm::Source {
            x,
            y: 1.0,
            observations: 5,
            particles: 0,
            covariance: [[0.0; 2]; 2],
            round: 1,
            cluster: Vec::new(),
            rays: Vec::new(),
            refined: false,
            mirror: None,
            blends: Vec::new(),
            images: Vec::new(),
            history,
        }
    }

    fn map(sources: Vec<asm::Source>) -> MapResult {
        MapResult {
            sources,
            rounds: 1,
            particles: 0,
            unexplained: 0,
            unexplained_bearings: Vec::new(),
            removed: 0,
            refused: Vec::new(),
        }
    }

    #[test]
    fn a_move_is_two_changes_and_the_map_now_holds_only_the_new_place() {
        // A talker at x = 1 who walks to x = 4 at stop 10 of 20, and a machine at x = 7.
        let places = [
            place(0, 1.0, [0, 9]),
            place(0, 4.0, [10, 19]),
            place(1, 7.0, [0, 19]),
        ];
        assert_eq!(
            changes(&places, 20),
            vec![
                Change::Left {
                    place: 0,
                    since: 10
                },
                Change::Took { place: 1, at: 10 }
            ]
        );
        let silent = |since| History {
            state: SourceState::Silent { since },
            ..History::default()
        };
        let appeared = |at| History {
            appeared_at: Some(at),
            ..History::default()
        };
        // Dated at stops 11 and 9: both found; the map's active sources are the two that
        // sound at the end, 0.05 m off one of them.
        let good = map(vec![
            mapped(1.0, silent(11)),
            mapped(4.05, appeared(9)),
            mapped(7.0, History::default()),
        ]);
        let stops: Vec<[f64; 2]> = (0..20).map(|k| [0.5 * k as f64, 0.0]).collect();
        let open = |_: [f64; 2], _: [f64; 2]| true;
        let s = judge(&good, &places, &stops, &open);
        assert_eq!((s.changes, s.found), (2, 2));
        assert!((s.ospa_now - 0.025).abs() < 1e-9, "{s:?}");
        // The old place still active (a static map): its change missed, and it counts
        // against the map of now as an extra source (c = 1 m, one of three).
        let stale = map(vec![
            mapped(1.0, History::default()),
            mapped(4.0, appeared(13)),
            mapped(7.0, History::default()),
        ]);
        let s = judge(&stale, &places, &stops, &open);
        assert_eq!((s.changes, s.found), (2, 0));
        assert!((s.ospa_now - 1.0 / 3.0).abs() < 1e-9, "{s:?}");
        assert!(!s.all_found());
        // Behind a wall from stop 8 to 14 (x 4-7 m): the talker's leaving (stop 10) is due
        // when stop 15 first sees its old place, and the map dating it at 11 is off by 4;
        // at 14, within two.
        let wall = |a: [f64; 2], _: [f64; 2]| !(4.0..7.0).contains(&a[0]);
        let s = judge(&good, &places, &stops, &wall);
        assert_eq!((s.changes, s.unseen, s.found), (2, 0, 0));
        let late = map(vec![
            mapped(1.0, silent(14)),
            mapped(4.05, appeared(15)),
            mapped(7.0, History::default()),
        ]);
        assert_eq!(judge(&late, &places, &stops, &wall).found, 2);
        // Seen only after the change (from stop 10 on): not judged.
        let after = |a: [f64; 2], _: [f64; 2]| a[0] >= 5.0;
        let s = judge(&good, &places, &stops, &after);
        assert_eq!((s.changes, s.unseen), (0, 2));
        assert!(s.all_found());
    }
}
