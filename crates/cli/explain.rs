//! Why a map holds what it holds: the DoAs each source explains, the DoAs no source took,
//! and, when the truth is known, what the stops heard of each true source the map missed.
//!
//! I-ASM never labels a DoA before mapping; the implicit association does (see
//! [`asm::assoc`]). So when a source is missing or misplaced, the question a user asks is
//! where its DoAs went: never heard (the SSL's recall), heard but taken by another source
//! (the association), or heard and left unexplained, too few or too scattered to make a
//! source (the mapper's evidence rules, e.g. [`asm::IasmConfig::min_observations`] and
//! the vote's quorums), or made into a source that a rule then refused (on the robot's
//! path, beyond the map, too thinly heard, or contradicted by nearer stops that heard
//! nothing there: [`asm::MapResult::refused`]). [`explain`] answers it from one map,
//! without a debugger: it is what every hand-built tracer of this project's sessions
//! printed.

use asm::{MapResult, Pose};
use serde::Serialize;

use crate::dataset::Table;

/// One DoA a source explains.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RayNote {
    /// The stop (from 0, in the poses' order).
    pub stop: usize,
    /// Azimuth in the array frame (degrees), as the DoA table holds it.
    pub azimuth_deg: f64,
    /// How far the DoA misses the bearing from its stop to the source (degrees).
    pub miss_deg: f64,
    /// Whether the source takes it as one peak of its direct sound and its image in a wall
    /// near it, which does not move it ([`asm::Source::blends`]).
    pub blend: bool,
    /// Whether the source takes it as its image in a wall near it, heard instead of its
    /// direct sound: the DoA passes the image ([`asm::Source::images`]).
    pub image: bool,
}

/// A mapped source and the DoAs it explains.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SourceRays {
    /// Its number in the map's table (from 1).
    pub source: usize,
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// Its DoAs, in stop order.
    pub rays: Vec<RayNote>,
}

/// The DoAs of one stop that no source explains.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StopLeft {
    /// The stop (from 0).
    pub stop: usize,
    /// Their azimuths in the array frame (degrees), in the row's order.
    pub azimuths_deg: Vec<f64>,
    /// Whether the SSL cut the row at N (it found more peaks there than it reported);
    /// `None` for a DoA table, whose rows do not say.
    pub cut: Option<bool>,
}

/// A DoA near a true source's bearing, and what became of it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Heard {
    /// The stop (from 0).
    pub stop: usize,
    /// Azimuth in the array frame (degrees).
    pub azimuth_deg: f64,
    /// Its error against the bearing to the true source (degrees, signed).
    pub error_deg: f64,
    /// The mapped source that explains it (its number, from 1); `None` when no source
    /// does.
    pub taken_by: Option<usize>,
}

/// A true source that no mapped source stands for.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Missed {
    /// Its number in the truth (from 1).
    pub truth: usize,
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// The DoAs within `tol_deg` of its bearing, in stop order (at most one per stop,
    /// the nearest).
    pub heard: Vec<Heard>,
    /// The nearest of the sources the mapper found and refused within `c` of it, if any:
    /// its DoAs were there, and this rule kept them out.
    pub refused: Option<asm::Refused>,
}

/// Why a map holds what it holds (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Explanation {
    /// Every mapped source with its DoAs.
    pub sources: Vec<SourceRays>,
    /// The stops with DoAs that no source explains.
    pub unexplained: Vec<StopLeft>,
    /// What the mapper found and refused, and why ([`asm::MapResult::refused`]).
    pub refused: Vec<asm::Refused>,
    /// With the truth: the true sources that the optimal assignment of the OSPA metric
    /// leaves without a mapped source within its cutoff `c`.
    pub missed: Vec<Missed>,
    /// A missed source's DoAs are those within this many degrees of its bearing.
    pub tol_deg: f64,
}

/// Explains `result`, a map of the survey with `poses` and DoA table `doas` (degrees,
/// array frame; `cut` per stop when the SSL said), against `truth` when it is known:
/// a true source counts as mapped when the OSPA assignment pairs it with a source within
/// `c` metres.
///
/// # Panics
/// If `poses`, `doas` and `result`'s unexplained rows (or `cut`) differ in length: they
/// come from one survey.
pub fn explain(
    result: &MapResult,
    poses: &[Pose],
    doas: &Table,
    cut: Option<&[bool]>,
    truth: Option<&[[f64; 2]]>,
    c: f64,
    tol_deg: f64,
) -> Explanation {
    assert_eq!(poses.len(), doas.len(), "one DoA row per pose");
    assert_eq!(
        poses.len(),
        result.unexplained_bearings.len(),
        "one unexplained row per pose"
    );
    let azimuth = |stop: usize, world: f64| ssl::wrap_deg((world - poses[stop].theta).to_degrees());
    let sources: Vec<SourceRays> = result
        .sources
        .iter()
        .enumerate()
        .map(|(i, s)| SourceRays {
            source: i + 1,
            x: s.x,
            y: s.y,
            rays: s
                .rays
                .iter()
                .map(|r| RayNote {
                    stop: r.stop,
                    azimuth_deg: azimuth(r.stop, r.bearing),
                    miss_deg: r.miss([s.x, s.y]).to_degrees(),
                    blend: s.blends.contains(&r.stop),
                    image: s.images.contains(&r.stop),
                })
                .collect(),
        })
        .collect();
    let unexplained: Vec<StopLeft> = result
        .unexplained_bearings
        .iter()
        .enumerate()
        .filter(|(_, row)| !row.is_empty())
        .map(|(stop, row)| StopLeft {
            stop,
            azimuths_deg: row.iter().map(|&b| azimuth(stop, b)).collect(),
            cut: cut.map(|c| c[stop]),
        })
        .collect();
    let missed = truth.map_or_else(Vec::new, |truth| {
        let mapped = mapped_truth(&result.positions(), truth, c);
        truth
            .iter()
            .enumerate()
            .filter(|&(k, _)| !mapped[k])
            .map(|(k, &q)| Missed {
                truth: k + 1,
                x: q[0],
                y: q[1],
                heard: heard_of(q, result, poses, doas, tol_deg),
                refused: refused_near(result, q, c).cloned(),
            })
            .collect()
    });
    Explanation {
        sources,
        unexplained,
        refused: result.refused.clone(),
        missed,
        tol_deg,
    }
}

/// Of the sources `result` refused, the nearest within `c` of `q`.
fn refused_near(result: &MapResult, q: [f64; 2], c: f64) -> Option<&asm::Refused> {
    result
        .refused
        .iter()
        .map(|r| (r, (r.x - q[0]).hypot(r.y - q[1])))
        .filter(|&(_, d)| d < c)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(r, _)| r)
}

/// How the true sources a map missed were lost: how many the OSPA assignment left without
/// a mapped source within `c`, and of those, how many the mapper made and refused (a
/// refused source within `c`), by rule. The rest it never made a source of. Averaged over
/// runs by `iasm eval` and `iasm compare` (see [`crate::pipeline::VariantStats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MissedTally {
    /// True sources missed.
    pub missed: f64,
    /// Of those, refused for stops that heard nothing there ([`asm::IasmConfig::absence_ratio`]).
    pub spoken_against: f64,
    /// Refused as too thinly heard ([`asm::IasmConfig::vote_min_thresholded_stops`]).
    pub thinly_heard: f64,
    /// Refused as on the robot's path, beyond the map, outside the room, behind a wall,
    /// or another's reflections ([`asm::IasmConfig::min_range_m`],
    /// [`asm::IasmConfig::beyond_map_m`], [`asm::IasmConfig::room_margin_m`],
    /// [`asm::IasmConfig::wall_clearance_m`], [`asm::IasmConfig::reflections`]).
    pub misplaced: f64,
    /// Refused because its DoAs fit other mapped sources better
    /// ([`asm::IasmConfig::reassociate`]).
    pub reassigned: f64,
}

impl MissedTally {
    /// The tally of one map against `truth`.
    pub fn of(result: &MapResult, truth: &[[f64; 2]], c: f64) -> Self {
        let mapped = mapped_truth(&result.positions(), truth, c);
        let mut t = Self::default();
        for (&q, _) in truth.iter().zip(&mapped).filter(|(_, m)| !**m) {
            t.missed += 1.0;
            match refused_near(result, q, c).map(|r| &r.rule) {
                Some(asm::Refusal::SpokenAgainst { .. }) => t.spoken_against += 1.0,
                Some(asm::Refusal::ThinlyHeard) => t.thinly_heard += 1.0,
                Some(
                    asm::Refusal::Misplaced | asm::Refusal::OutsideRoom | asm::Refusal::Reflection,
                ) => t.misplaced += 1.0,
                Some(asm::Refusal::Reassigned) => t.reassigned += 1.0,
                None => {}
            }
        }
        t
    }

    /// The mean of `tallies` (zero for none).
    pub fn mean(tallies: impl ExactSizeIterator<Item = Self>) -> Self {
        let n = tallies.len().max(1) as f64;
        let sum = tallies.fold(Self::default(), |a, b| Self {
            missed: a.missed + b.missed,
            spoken_against: a.spoken_against + b.spoken_against,
            thinly_heard: a.thinly_heard + b.thinly_heard,
            misplaced: a.misplaced + b.misplaced,
            reassigned: a.reassigned + b.reassigned,
        });
        Self {
            missed: sum.missed / n,
            spoken_against: sum.spoken_against / n,
            thinly_heard: sum.thinly_heard / n,
            misplaced: sum.misplaced / n,
            reassigned: sum.reassigned / n,
        }
    }

    /// Missed sources the mapper never made a source of.
    pub fn never_made(&self) -> f64 {
        (self.missed - self.spoken_against - self.thinly_heard - self.misplaced - self.reassigned)
            .max(0.0)
    }
}

/// Which true sources the OSPA assignment pairs with an estimate within `c`.
fn mapped_truth(est: &[[f64; 2]], truth: &[[f64; 2]], c: f64) -> Vec<bool> {
    let mut mapped = vec![false; truth.len()];
    for (_, k) in asm::ospa::pairs(est, truth, c) {
        mapped[k] = true;
    }
    mapped
}

/// At each stop, the DoA nearest the bearing to `q` if within `tol_deg`, and which source
/// (if any) explains it.
fn heard_of(
    q: [f64; 2],
    result: &MapResult,
    poses: &[Pose],
    doas: &Table,
    tol_deg: f64,
) -> Vec<Heard> {
    let mut heard = Vec::new();
    for (stop, (pose, row)) in poses.iter().zip(doas).enumerate() {
        let to = pose.bearing_to(q);
        let nearest = row
            .iter()
            .flatten()
            .map(|&az| {
                let world = pose.world_bearing(az.to_radians());
                (az, world, asm::wrap_rad(world - to).to_degrees())
            })
            .min_by(|a, b| a.2.abs().total_cmp(&b.2.abs()));
        let Some((az, world, err)) = nearest.filter(|n| n.2.abs() <= tol_deg) else {
            continue;
        };
        let same = |b: f64| asm::wrap_rad(b - world).abs() < 1e-9;
        let taken_by = result
            .sources
            .iter()
            .position(|s| s.rays.iter().any(|r| r.stop == stop && same(r.bearing)))
            .map(|i| i + 1);
        heard.push(Heard {
            stop,
            azimuth_deg: az,
            error_deg: err,
            taken_by,
        });
    }
    heard
}

#[cfg(test)]
mod tests {
    use super::*;
    use asm::map::{Cell, OccupancyMap};
    use asm::{IasmConfig, Mapper};

    /// Exact DoAs of the sources in `heard_by[k]` at stop `k` (array frame, degrees).
    fn table(poses: &[Pose], sources: &[[f64; 2]], heard_by: &[Vec<usize>]) -> Table {
        poses
            .iter()
            .zip(heard_by)
            .map(|(p, who)| {
                who.iter()
                    .map(|&s| {
                        Some(ssl::wrap_deg(
                            (p.bearing_to(sources[s]) - p.theta).to_degrees(),
                        ))
                    })
                    .collect()
            })
            .collect()
    }

    /// The default mapper's map of `doas` in a free 8 x 6 m room.
    fn map_of(poses: &[Pose], doas: &Table, seed: u64) -> MapResult {
        let map = OccupancyMap::new(160, 120, 0.05, [0.0, 0.0], vec![Cell::Free; 160 * 120]);
        let rad: Vec<Vec<f64>> = doas
            .iter()
            .map(|r| r.iter().flatten().map(|a| a.to_radians()).collect())
            .collect();
        Mapper::new(&map, &IasmConfig::default())
            .unwrap()
            .run_seeded(poses, &rad, None, seed)
            .unwrap()
    }

    #[test]
    fn a_source_heard_by_two_stops_is_missed_and_its_doas_are_shown_unexplained() {
        // Source 0 heard by all six stops, source 1 by stops 4 and 5 only: two bearings
        // always meet, so the mapper (three stops at least) leaves them, and the
        // explanation says where they are.
        let poses: Vec<Pose> = (0..6)
            .map(|k| Pose::new(1.0 + 0.8 * k as f64, 2.0, 0.3))
            .collect();
        let sources = [[3.0, 4.5], [6.0, 0.5]];
        let heard_by = [vec![0], vec![0], vec![0], vec![0], vec![0, 1], vec![0, 1]];
        let doas = table(&poses, &sources, &heard_by);
        let result = map_of(&poses, &doas, 1);
        assert_eq!(result.sources.len(), 1);
        let e = explain(&result, &poses, &doas, None, Some(&sources), 1.0, 5.0);
        // The mapped source explains one DoA per stop, each within a hair of its bearing.
        assert_eq!(e.sources.len(), 1);
        let stops: Vec<usize> = e.sources[0].rays.iter().map(|r| r.stop).collect();
        assert_eq!(stops, vec![0, 1, 2, 3, 4, 5]);
        assert!(
            e.sources[0]
                .rays
                .iter()
                .all(|r| r.miss_deg < 0.1 && !r.blend && !r.image)
        );
        // A DoA the source takes as a blend with its image, or as its image, is noted so.
        let noted = |mark: &dyn Fn(&mut asm::Source), is: fn(&RayNote) -> bool| {
            let mut marked = result.clone();
            mark(&mut marked.sources[0]);
            let e = explain(&marked, &poses, &doas, None, Some(&sources), 1.0, 5.0);
            let rays = &e.sources[0].rays;
            rays.iter()
                .filter(|r| is(r))
                .map(|r| r.stop)
                .collect::<Vec<usize>>()
        };
        assert_eq!(noted(&|s| s.blends = vec![2], |r| r.blend), vec![2]);
        assert_eq!(noted(&|s| s.images = vec![4], |r| r.image), vec![4]);
        // The two DoAs of source 1 are left, at the azimuths the table holds.
        let left: Vec<(usize, Vec<f64>)> = e
            .unexplained
            .iter()
            .map(|s| (s.stop, s.azimuths_deg.clone()))
            .collect();
        assert_eq!(left.len(), 2);
        for (stop, az) in left {
            assert_eq!(az.len(), 1);
            approx::assert_abs_diff_eq!(az[0], doas[stop][1].unwrap(), epsilon = 1e-9);
        }
        // Source 1 is the one missed, heard exactly by stops 4 and 5, taken by nobody.
        assert_eq!(e.missed.len(), 1);
        assert_eq!(e.missed[0].truth, 2);
        let heard: Vec<(usize, Option<usize>)> = e.missed[0]
            .heard
            .iter()
            .map(|h| (h.stop, h.taken_by))
            .collect();
        assert_eq!(heard, vec![(4, None), (5, None)]);
        assert!(e.missed[0].heard.iter().all(|h| h.error_deg.abs() < 1e-6));
        // Tallied as never made: no rule refused anything. Averaged with a run that
        // missed nothing: half a source per run, never made.
        assert!(result.refused.is_empty(), "{:?}", result.refused);
        assert_eq!(e.missed[0].refused, None);
        let t = MissedTally::of(&result, &sources, 1.0);
        assert_eq!((t.missed, t.never_made()), (1.0, 1.0));
        let none = MissedTally::of(&result, &sources[..1], 1.0);
        assert_eq!(none, MissedTally::default());
        let mean = MissedTally::mean([t, none].into_iter());
        assert_eq!((mean.missed, mean.never_made()), (0.5, 0.5));
        assert_eq!(
            MissedTally::mean(std::iter::empty()),
            MissedTally::default()
        );
    }

    #[test]
    fn a_doa_taken_by_another_source_is_named() {
        // A missed source's DoA that lies near another source's bearing is reported as
        // taken by that source.
        let poses: Vec<Pose> = (0..5)
            .map(|k| Pose::new(1.0 + 0.8 * k as f64, 2.0, 0.0))
            .collect();
        let sources = [[3.0, 4.5]];
        let doas = table(&poses, &sources, &vec![vec![0]; 5]);
        let result = map_of(&poses, &doas, 2);
        assert_eq!(result.sources.len(), 1);
        // A second true source 1.5 m beyond the first along stop 2's bearing: stop 2's
        // DoA points at both, and the mapped source has it.
        let p = poses[2].position();
        let b = poses[2].bearing_to(sources[0]);
        let hidden = [p[0] + 4.0 * b.cos(), p[1] + 4.0 * b.sin()];
        let truth = [sources[0], hidden];
        let e = explain(
            &result,
            &poses,
            &doas,
            Some(&[false; 5]),
            Some(&truth),
            1.0,
            5.0,
        );
        assert_eq!(e.missed.len(), 1);
        assert_eq!(e.missed[0].truth, 2);
        let stop2: Vec<&Heard> = e.missed[0].heard.iter().filter(|h| h.stop == 2).collect();
        assert_eq!(stop2.len(), 1);
        assert_eq!(stop2[0].taken_by, Some(1));
        assert!(e.unexplained.is_empty());
    }

    #[test]
    fn a_source_that_nearer_stops_did_not_hear_is_refused_and_the_stops_are_named() {
        // Talker A heard from all nine stops along y = 2; source B (2.5, 0.5) only from
        // stops 0, 5 and 6 (2.5-3.7 m away), while stops 1-4, 1.5-2.2 m from it, report A
        // alone. The mapper makes B of its three stops and refuses it: four stops no
        // further than B's furthest hearer heard nothing there (the first forgiven, B
        // keeps too few). The explanation names the rule and those stops, on the missed
        // true source too.
        let poses: Vec<Pose> = (0..9)
            .map(|k| Pose::new(0.5 + 0.9 * k as f64, 2.0, 0.0))
            .collect();
        let sources = [[4.5, 5.0], [2.5, 0.5]];
        let heard_by: Vec<Vec<usize>> = (0..9)
            .map(|k| {
                if [0, 5, 6].contains(&k) {
                    vec![0, 1]
                } else {
                    vec![0]
                }
            })
            .collect();
        let doas = table(&poses, &sources, &heard_by);
        let result = map_of(&poses, &doas, 3);
        assert_eq!(result.positions().len(), 1, "{:?}", result.positions());
        let e = explain(&result, &poses, &doas, None, Some(&sources), 1.0, 5.0);
        assert_eq!(e.refused.len(), 1, "{:?}", e.refused);
        let r = &e.refused[0];
        assert!((r.x - 2.5).hypot(r.y - 0.5) < 0.05, "{r:?}");
        assert_eq!(r.stops, vec![0, 5, 6]);
        assert_eq!(
            r.rule,
            asm::Refusal::SpokenAgainst {
                against: vec![1, 2, 3, 4]
            }
        );
        assert_eq!(e.missed.len(), 1);
        assert_eq!(e.missed[0].refused.as_ref(), Some(r));
        // In JSON the rule is named and its stops listed beside the refused source's.
        let v = serde_json::to_value(r).unwrap();
        assert_eq!(v["rule"], "spoken_against");
        assert_eq!(v["against"], serde_json::json!([1, 2, 3, 4]));
        assert_eq!(v["stops"], serde_json::json!([0, 5, 6]));
        // The tally of the map: one source missed, made and refused for the absences.
        let t = MissedTally::of(&result, &sources, 1.0);
        assert_eq!(
            t,
            MissedTally {
                missed: 1.0,
                spoken_against: 1.0,
                ..MissedTally::default()
            }
        );
        assert_eq!(t.never_made(), 0.0);
    }
}
