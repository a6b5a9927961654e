//! When each source was heard: the stops that heard it, the stops that could have, and
//! its state at the run's end (the paper's own next step, a map of a room that changes).
//!
//! A map of I-ASM is a list of places. A talker who leaves is still one of them, and one
//! who walks to another desk is two. What tells the three apart is time: which stops heard
//! the source, and which could have heard it and did not.
//!
//! **Heard.** A stop heard a source when the source explains one of its DoAs
//! ([`Source::rays`]) and that DoA misses it by no more than [`HEARD_SIGMAS`] times the
//! DoA's spread ([`IasmConfig::sigma_deg`]): the paper's implicit association gives each
//! DoA to one source, within a wide gate, and a stray DoA near the bearing (a reflection,
//! another source's peak on the same line) must not keep a silent source alive.
//!
//! **Could have heard.** A stop could have heard it when the map holds no wall between
//! them (leaving out [`IasmConfig::room_margin_m`] at the source: its own wall), it lies
//! no further than [`REACH_FACTOR`] times the furthest stop that did hear it (how far the
//! source carries is measured, not assumed), no other mapped source is [`MASKING_RATIO`]
//! times nearer, or nearer within the gate of the same bearing (either would mask it),
//! and its row had room for it: complete (every peak the SSL let through; an empty row,
//! a stop that heard nothing standing out, is complete), or holding another mapped source
//! at least as far (a row cut at `N` keeps the strongest peaks, and by spreading alone
//! that one is no louder). A DoA table's rows say nothing of what was cut: a row of `N`
//! DoAs counts as cut.
//!
//! **Silent since.** Stray hearings, fewer than [`STRAY_RUN`] more than [`STRAY_GAP`] stops
//! from the others (a reflection or another source's DoA near its bearing), are left out.
//! Between its first and last hearing a source is heard at a share `p`
//! of the stops that could have heard it: the front end's recall of it. After its last
//! hearing, `m` stops that could have heard it missed it. Were it still sounding, that
//! happens with probability `(1 - p)^m`; below [`SILENT_P`] it fell silent at the first of
//! them. A sequential test, so a source the front end hears at every stop is called silent
//! after three misses and one it hears at every other stop after seven; `p` is held within
//! [`RECALL_RANGE`], so that one lucky run of hearings does not make a single miss
//! decisive. The same test before its first hearing says it **appeared** there.
//!
//! **Moved.** A source that fell silent and another that appeared within [`MOVE_STOPS`]
//! stops of it are one source that moved: the old place is retired and linked to the new
//! one (pairs nearest in time first). From time alone a talker who leaves while another
//! arrives looks the same; what each sounds like would tell them apart.

use super::*;

/// A DoA that a source explains heard it when it misses it by at most this many times the
/// DoA's spread: two, as a DoA of the source itself does 95 % of the time, where the
/// association's gate ([`IasmConfig::gamma_sigmas`], three) also takes in reflections
/// near it.
pub const HEARD_SIGMAS: f64 = 2.0;

/// The chance (that a source still sounding is missed by every stop since its last
/// hearing) below which it is called silent, or, before its first hearing, absent.
pub const SILENT_P: f64 = 0.01;

/// The range the front end's recall of a source is held within for the test: at least
/// three misses (`0.2^3`) before a source is called silent (the front end's recall of a
/// source drops for a stop or two where a louder one comes near), and at most about 90 for
/// one heard at one stop in twenty.
pub const RECALL_RANGE: (f64, f64) = (0.05, 0.8);

/// Another mapped source this many times nearer a stop than a source masks it there: 6 dB
/// louder by spreading alone. The absence rule's 1.5 ([`IasmConfig::absence_ratio`]) kept
/// a talker who had stopped active in `fixtures/changes/stopstart_box` (the other
/// talker, 1.5-1.9 times nearer at the stops after, masked every test); at 2 that change
/// is dated in every map (docs/decisions/0015).
pub const MASKING_RATIO: f64 = 2.0;

/// How much further than the furthest stop that heard a source a stop may lie and still
/// count as one that could have heard it: 1.5 times as far is 3.5 dB fainter by spreading
/// alone, within the few dB a source's level varies from stop to stop in a room, and a
/// robot that drives away from a source that fell silent still tests it.
pub const REACH_FACTOR: f64 = 1.5;

/// A source that fell silent and one that appeared at most this many stops apart are one
/// source that moved.
pub const MOVE_STOPS: usize = 3;

/// Hearings of a source more than this many stops apart belong to different stretches of
/// the run: five stops in a row that could have heard it and did not would call it silent
/// at any recall above 60 % (`0.4^5 = 0.01`, [`SILENT_P`]).
pub const STRAY_GAP: usize = 5;

/// A stretch of fewer hearings than this, apart from the others by more than
/// [`STRAY_GAP`], is stray (a reflection or another source's DoA near its bearing) and does
/// not date the source: the paper's fewest observing stops of a source
/// ([`IasmConfig::min_observations`]'s default).
pub const STRAY_RUN: usize = 3;

/// The stops of `heard` (sorted, each once) that date a source: all but the stray
/// stretches ([`STRAY_GAP`], [`STRAY_RUN`]), or all of them when every stretch is stray.
pub(super) fn dating(heard: &[usize]) -> Vec<usize> {
    let mut runs: Vec<&[usize]> = Vec::new();
    let mut start = 0;
    for i in 1..=heard.len() {
        if i == heard.len() || heard[i] - heard[i - 1] > STRAY_GAP {
            runs.push(&heard[start..i]);
            start = i;
        }
    }
    let kept: Vec<usize> = runs
        .iter()
        .filter(|r| r.len() >= STRAY_RUN)
        .flat_map(|r| r.iter().copied())
        .collect();
    if kept.is_empty() {
        heard.to_vec()
    } else {
        kept
    }
}

/// Whether `misses` stops that could have heard a source sounding, heard at each with
/// probability `p`, would all have missed it with a chance of at most [`SILENT_P`]: then it
/// did not sound.
fn all_missed_unlikely(p: f64, misses: usize) -> bool {
    (1.0 - p).powi(i32::try_from(misses).unwrap_or(i32::MAX)) <= SILENT_P
}

/// A source's state at the end of the run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "state")]
pub enum SourceState {
    /// Heard at the last stops that could hear it (or no stop since could).
    #[default]
    Active,
    /// Missed by the stops that could have heard it from stop `since` on.
    Silent {
        /// The first stop (from 0) that could have heard it and did not.
        since: usize,
    },
}

/// When a source was heard ([`Source::history`]; see the module docs). Stops count from 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct History {
    /// The first stop that heard it.
    pub first_stop: usize,
    /// The last stop that heard it.
    pub last_stop: usize,
    /// Stops that heard it.
    pub heard_stops: usize,
    /// Of the stops from its first to its last hearing that could have heard it, the share
    /// that did (the front end's recall of it).
    pub heard_share: f64,
    /// Its state at the end of the run.
    #[serde(flatten)]
    pub state: SourceState,
    /// The stop at which it appeared, when the stops before that could have heard it
    /// missed it (it started then, or was brought in).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub appeared_at: Option<usize>,
    /// For a source that fell silent where another appeared: that source (its index in
    /// the map) and the stop from which it stands there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moved_to: Option<usize>,
    /// For a source that appeared where another fell silent: that source's index.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moved_from: Option<usize>,
}

impl History {
    /// Whether the source sounds at the end of the run.
    pub fn is_active(&self) -> bool {
        self.state == SourceState::Active
    }

    /// The stop at which it went silent, if it did.
    pub fn silent_since(&self) -> Option<usize> {
        match self.state {
            SourceState::Active => None,
            SourceState::Silent { since } => Some(since),
        }
    }
}

impl Mapper {
    /// Sets each source's [`Source::history`] over `stops`.
    pub fn date(&self, sources: &mut [Source], stops: &Stops) {
        let histories = self.histories(sources, stops);
        for (s, h) in sources.iter_mut().zip(histories) {
            s.history = h;
        }
    }

    /// Each source's [`History`] over `stops` (see the module docs), in the order of
    /// `sources`.
    pub fn histories(&self, sources: &[Source], stops: &Stops) -> Vec<History> {
        let places: Vec<[f64; 2]> = sources.iter().map(|s| [s.x, s.y]).collect();
        let hearings: Vec<Vec<usize>> = sources
            .iter()
            .map(|s| {
                let mut k: Vec<usize> = s
                    .rays
                    .iter()
                    .filter(|r| r.miss([s.x, s.y]) <= HEARD_SIGMAS * self.sigma)
                    .map(|r| r.stop)
                    .collect();
                k.sort_unstable();
                k.dedup();
                dating(&k)
            })
            .collect();
        let mut out: Vec<History> = (0..sources.len())
            .map(|i| self.history(i, &places, &hearings, stops))
            .collect();
        // Moves: pairs of a silence and an appearance, nearest in time first.
        let mut pairs: Vec<(usize, usize, usize)> = Vec::new();
        for (a, ha) in out.iter().enumerate() {
            let Some(since) = ha.silent_since() else {
                continue;
            };
            for (b, hb) in out.iter().enumerate() {
                if let Some(at) = hb.appeared_at
                    && a != b
                    && hb.last_stop > ha.last_stop
                    && since.abs_diff(at) <= MOVE_STOPS
                {
                    pairs.push((since.abs_diff(at), a, b));
                }
            }
        }
        pairs.sort_unstable();
        for (_, a, b) in pairs {
            if out[a].moved_to.is_none() && out[b].moved_from.is_none() {
                out[a].moved_to = Some(b);
                out[b].moved_from = Some(a);
            }
        }
        out
    }

    /// The history of source `me` of `places`, each heard at the stops of `hearings`.
    fn history(
        &self,
        me: usize,
        places: &[[f64; 2]],
        hearings: &[Vec<usize>],
        stops: &Stops,
    ) -> History {
        let poses = stops.poses();
        let q = places[me];
        let dist = |p: &Pose, o: [f64; 2]| (p.x - o[0]).hypot(p.y - o[1]);
        let mine = &hearings[me];
        let near = |k: usize| mine.binary_search(&k).is_ok();
        let (Some(&first), Some(&last)) = (mine.first(), mine.last()) else {
            return History::default();
        };
        let reach = REACH_FACTOR * mine.iter().map(|&k| dist(&poses[k], q)).fold(0.0, f64::max);
        let could = |k: usize| {
            let p = &poses[k];
            let d = dist(p, q);
            // A row cut at `N` lost its weaker peaks; it would have kept this source had
            // it sounded when it kept another at least as far (spreading alone makes that
            // one no louder).
            let room_in_row = stops.complete()[k]
                || places.iter().enumerate().any(|(j, &o)| {
                    j != me && dist(p, o) >= d && hearings[j].binary_search(&k).is_ok()
                });
            room_in_row
                && d <= reach
                && self.sees(p.position(), q)
                && !places.iter().enumerate().any(|(j, &o)| {
                    let dj = dist(p, o);
                    j != me
                        && (dj * MASKING_RATIO < d
                            || (dj < d
                                && wrap_rad(p.bearing_to(o) - p.bearing_to(q)).abs() < self.gamma))
                })
        };
        let between = (first..=last).filter(|&k| could(k) || near(k)).count();
        let recall = mine.len() as f64 / between.max(1) as f64;
        let p = recall.clamp(RECALL_RANGE.0, RECALL_RANGE.1);
        let missed_after: Vec<usize> = (last + 1..poses.len()).filter(|&k| could(k)).collect();
        let state = match missed_after.first() {
            Some(&since) if all_missed_unlikely(p, missed_after.len()) => {
                SourceState::Silent { since }
            }
            _ => SourceState::Active,
        };
        let missed_before = (0..first).filter(|&k| could(k)).count();
        History {
            first_stop: first,
            last_stop: last,
            heard_stops: mine.len(),
            heard_share: recall,
            state,
            appeared_at: all_missed_unlikely(p, missed_before).then_some(first),
            moved_to: None,
            moved_from: None,
        }
    }
}
