//! Which of the SSL's rules left a near source out of a stop's DoAs, and which let in the
//! DoAs that found no source: `iasm ssl --dataset DIR --score --rules`.
//!
//! A stop's DoAs are the peaks of its pooled spectrum that pass every rule of
//! [`ssl::SslConfig`] (prominence, height or block dominance or incoherence, sidelobes,
//! significance), strongest first, at most `N`. When a source within 3 m is not among them
//! (the pairs that [`crate::score::Diagnostics::recall_3m`] counts as missed), the census
//! asks the localizer again with one rule off at a time, and with `N` raised so that the
//! rules, not `N`, decide: the rule whose absence alone lets a DoA within the tolerance
//! through is the one that left the source out. A source that no run reports, though the
//! spectrum has a peak there, was left out by two rules at once; one with no peak there
//! at all is beyond what thresholds can do (the spectrum does not show it).
//!
//! The rules are taken off one at a time rather than read from the localizer's decisions
//! so that the census runs the localizer as it is, with nothing added to its hot path; it
//! costs six localisations per recording instead of one.
//!
//! A missed source with no peak within the tolerance is told apart further: with a peak
//! within twice the tolerance (heard, but displaced: a reflection's pull, the near field,
//! a pose error), or with another true source within `min_sep_deg` (one peak for two).
//!
//! Why: every rule trades the sources it lets in against the clutter it keeps out, and a
//! recall figure alone does not say which trade to revisit on a data set. Measured on
//! the regression suite, the held-out scenes, surveys
//! rendered by pyroomacoustics and the authors' recordings, the height and coherence rules
//! left out 4-23 % of the missed near sources; about half to two thirds of the misses had
//! no peak within 5 degrees (48-70 %), and where more sources sound at once than `N`, `N`
//! cut a fifth to a third of them (19-37 %).

use std::path::PathBuf;

use anyhow::{Result, ensure};
use asm::Pose;
use serde::Serialize;
use ssl::{Doa, MicArray, SslConfig, fold_azimuth, wrap_deg};

use crate::pipeline::{FileDoas, localise_files};

/// A rule of [`SslConfig`] that the census takes off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// `min_relative` (with the block dominance and incoherence exceptions): height.
    Height,
    /// `min_prominence`.
    Prominence,
    /// `sidelobe_ratio`.
    Sidelobe,
    /// `min_significance`.
    Significance,
}

impl Rule {
    /// Every rule, in the order a miss is attributed when more than one releases it.
    pub const ALL: [Rule; 4] = [
        Rule::Height,
        Rule::Prominence,
        Rule::Sidelobe,
        Rule::Significance,
    ];
}

/// `N` for the runs that let the rules, not `N`, decide: four times `N`, at least 12.
pub fn wide_n(config: &SslConfig) -> usize {
    (4 * config.num_peaks).max(12)
}

/// Sources nearer than this to a stop (m) are the ones it should hear: the pairs of
/// [`crate::score::Diagnostics::recall_3m`].
pub const NEAR_M: f64 = 3.0;

/// `config` with `N` raised to [`wide_n`] and the rules `off` taken off (none: `N` alone
/// raised; [`Rule::ALL`]: every resolved peak of the spectrum).
pub fn without(config: &SslConfig, off: &[Rule]) -> SslConfig {
    let mut c = config.clone();
    c.num_peaks = wide_n(config);
    for rule in off {
        match rule {
            Rule::Height => {
                c.min_relative = 0.0;
                c.incoherent_relative = 0.0;
            }
            Rule::Prominence => c.min_prominence = 0.0,
            Rule::Sidelobe => c.sidelobe_ratio = 0.0,
            Rule::Significance => c.min_significance = 0.0,
        }
    }
    c
}

/// One stop as the census sees it (azimuths in degrees, array frame, folded for a linear
/// array as the score folds them).
#[derive(Clone, Debug, Default)]
pub struct Stop {
    /// The true sources within 3 m.
    pub near: Vec<Near>,
    /// The bearings of every true source.
    pub all: Vec<f64>,
    /// The DoAs (the first `N`), each with its height and block votes.
    pub doas: Vec<Doa>,
    /// The octave votes' DoAs beyond `N` ([`ssl::Located::extra`]).
    pub extra: Vec<f64>,
    /// The DoAs with `N` raised ([`wide_n`]), every rule on.
    pub wide: Vec<f64>,
    /// The DoAs with `N` raised and each rule of [`Rule::ALL`] off in turn.
    pub released: Vec<Vec<f64>>,
    /// Every resolved peak of the spectrum (every rule off), with its height.
    pub peaks: Vec<Doa>,
}

/// A true source within 3 m of a stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Near {
    /// Its index in the truth (0-based, the truth file's order).
    pub source: usize,
    /// Its bearing (degrees, array frame).
    pub bearing_deg: f64,
    /// Its distance from the stop (m).
    pub distance_m: f64,
}

/// Why a near source is not among a stop's DoAs (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// The spectrum has no peak within the tolerance.
    NoPeak,
    /// `N` stronger DoAs passed the rules.
    CutAtN,
    /// Below `min_relative`, and below `incoherent_relative` (or that exception off).
    Low,
    /// Between `incoherent_relative` and `min_relative`, coherent with a stronger peak.
    Coherent,
    /// Below `min_prominence`.
    Prominence,
    /// Below `sidelobe_ratio` times a stronger peak's sidelobe.
    Sidelobe,
    /// Below `min_significance`.
    Insignificant,
    /// No single rule taken off lets it through.
    Jointly,
}

/// One missed (stop, near source) pair of [`RuleCensus::missed`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Missed {
    /// The stop (0-based, the recordings' order).
    pub stop: usize,
    /// The source (0-based, the truth's order).
    pub source: usize,
    /// Its distance from the stop (m).
    pub distance_m: f64,
    /// Its bearing (degrees, array frame).
    pub bearing_deg: f64,
    /// Why no DoA found it.
    pub reason: Reason,
    /// The height of the strongest peak within the tolerance of its bearing (every rule
    /// off; [`ssl::Doa::relative`]), if any.
    pub peak_relative: Option<f64>,
}

/// The counts of [`census`]. Each missed pair is counted under exactly one of `no_peak`,
/// `cut_at_n`, `low`, `coherent`, `prominence`, `sidelobe`, `insignificant`, `jointly`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RuleCensus {
    /// (stop, source within 3 m) pairs.
    pub pairs: usize,
    /// Pairs with a DoA within the tolerance.
    pub found: usize,
    /// Missed: the spectrum has no peak within the tolerance.
    pub no_peak: usize,
    /// Of `no_peak`, those with another true source within `min_sep_deg` of their bearing:
    /// two sources the localizer cannot tell apart there, one peak for both.
    pub no_peak_beside: usize,
    /// Of `no_peak`, those with a peak within twice the tolerance (a source heard, but
    /// displaced: a reflection's pull, or the near field).
    pub no_peak_displaced: usize,
    /// Missed: `N` stronger DoAs passed the rules.
    pub cut_at_n: usize,
    /// Of `cut_at_n`, those the octave votes report beyond `N` (the mapper takes them).
    pub cut_but_extra: usize,
    /// Missed by height: below `incoherent_relative` (or that exception off).
    pub low: usize,
    /// Missed by height: between `incoherent_relative` and `min_relative`, and coherent
    /// with a stronger peak.
    pub coherent: usize,
    /// Missed by `min_prominence`.
    pub prominence: usize,
    /// Missed by `sidelobe_ratio`.
    pub sidelobe: usize,
    /// Missed by `min_significance`.
    pub insignificant: usize,
    /// Missed though the spectrum has a peak there that no single rule taken off lets
    /// through.
    pub jointly: usize,
    /// DoAs (the first `N`).
    pub doas: usize,
    /// DoAs with no true source (at any distance) within the tolerance.
    pub false_doas: usize,
    /// Of `false_doas`, let in by their height (`min_relative`).
    pub by_height: usize,
    /// Of `false_doas`, let in by their block votes (`dominance_blocks`) though lower.
    pub by_dominance: usize,
    /// Of `false_doas`, let in as incoherent with every stronger peak though lower.
    pub by_incoherence: usize,
    /// The `N` of the census's wide runs ([`wide_n`]).
    pub wide_n: usize,
    /// DoAs that `N` raised to [`wide_n`] would add (every rule on): those of the wide run
    /// with no DoA of the row within the tolerance. What a larger `N` would give the mapper.
    pub beyond_n: usize,
    /// Of `beyond_n`, those within the tolerance of a true source (at any distance).
    pub beyond_n_on_source: usize,
    /// Every missed pair, stop by stop, with its reason.
    pub missed: Vec<Missed>,
}

impl RuleCensus {
    /// The missed pairs that some threshold left out: too low, coherent, not prominent,
    /// a sidelobe, insignificant, or two rules at once (every miss but `no_peak` and
    /// `cut_at_n`).
    pub fn by_thresholds(&self) -> usize {
        self.low
            + self.coherent
            + self.prominence
            + self.sidelobe
            + self.insignificant
            + self.jointly
    }
}

/// Counts why the near sources of `stops` were missed and what let in the DoAs that found
/// no source (see the module docs); a DoA within `tol_deg` of a bearing finds it.
/// `config` holds the thresholds the DoAs were found with.
pub fn census(stops: &[Stop], config: &SslConfig, tol_deg: f64) -> RuleCensus {
    let near = |azs: &[f64], t: f64| azs.iter().any(|a| wrap_deg(a - t).abs() <= tol_deg);
    let mut c = RuleCensus {
        wide_n: wide_n(config),
        ..RuleCensus::default()
    };
    for (k, s) in stops.iter().enumerate() {
        let doas: Vec<f64> = s.doas.iter().map(|d| d.azimuth_deg).collect();
        for n in &s.near {
            let t = n.bearing_deg;
            c.pairs += 1;
            if near(&doas, t) {
                c.found += 1;
                continue;
            }
            let peak = s
                .peaks
                .iter()
                .filter(|p| wrap_deg(p.azimuth_deg - t).abs() <= tol_deg)
                .map(|p| p.relative)
                .max_by(f64::total_cmp);
            let reason = match peak {
                None => {
                    let others = s.all.iter().enumerate().filter(|&(i, _)| i != n.source);
                    let beside = others
                        .filter(|&(_, &a)| wrap_deg(a - t).abs() < config.min_sep_deg)
                        .count();
                    c.no_peak_beside += usize::from(beside > 0);
                    let displaced = s
                        .peaks
                        .iter()
                        .any(|p| wrap_deg(p.azimuth_deg - t).abs() <= 2.0 * tol_deg);
                    c.no_peak_displaced += usize::from(displaced);
                    Reason::NoPeak
                }
                Some(_) if near(&s.wide, t) => {
                    c.cut_but_extra += usize::from(near(&s.extra, t));
                    Reason::CutAtN
                }
                Some(relative) => {
                    let rule = Rule::ALL
                        .iter()
                        .zip(&s.released)
                        .find(|(_, r)| near(r, t))
                        .map(|(rule, _)| *rule);
                    match rule {
                        Some(Rule::Height) => {
                            if config.incoherent_relative > 0.0
                                && relative >= config.incoherent_relative
                            {
                                Reason::Coherent
                            } else {
                                Reason::Low
                            }
                        }
                        Some(Rule::Prominence) => Reason::Prominence,
                        Some(Rule::Sidelobe) => Reason::Sidelobe,
                        Some(Rule::Significance) => Reason::Insignificant,
                        None => Reason::Jointly,
                    }
                }
            };
            *match reason {
                Reason::NoPeak => &mut c.no_peak,
                Reason::CutAtN => &mut c.cut_at_n,
                Reason::Low => &mut c.low,
                Reason::Coherent => &mut c.coherent,
                Reason::Prominence => &mut c.prominence,
                Reason::Sidelobe => &mut c.sidelobe,
                Reason::Insignificant => &mut c.insignificant,
                Reason::Jointly => &mut c.jointly,
            } += 1;
            c.missed.push(Missed {
                stop: k,
                source: n.source,
                distance_m: n.distance_m,
                bearing_deg: t,
                reason,
                peak_relative: peak,
            });
        }
        for &w in &s.wide {
            if !near(&doas, w) {
                c.beyond_n += 1;
                c.beyond_n_on_source += usize::from(near(&s.all, w));
            }
        }
        for d in &s.doas {
            c.doas += 1;
            if near(&s.all, d.azimuth_deg) {
                continue;
            }
            c.false_doas += 1;
            if d.relative >= config.min_relative {
                c.by_height += 1;
            } else if config.dominance_blocks > 0
                && d.dominant_blocks as usize >= config.dominance_blocks
            {
                c.by_dominance += 1;
            } else {
                c.by_incoherence += 1;
            }
        }
    }
    c
}

/// The recordings of a census and how they are localised: the files, the array, the
/// channels taken from them, the robot's noise subtracted.
pub struct Recordings<'a> {
    /// The WAV files, one per stop.
    pub files: &'a [PathBuf],
    /// The array that made them.
    pub array: &'a MicArray,
    /// The channels used (all when `None`).
    pub channels: Option<&'a [usize]>,
    /// The recording of the robot alone, subtracted when given.
    pub noise: Option<&'a crate::pipeline::RobotNoise>,
}

/// What a census scores against: each stop's pose, the true sources (m), how near a DoA
/// must be to a true bearing, and a linear array's axis (its DoAs and the bearings folded
/// as the score folds them).
pub struct Truth<'a> {
    /// The robot's pose at each stop.
    pub poses: &'a [Pose],
    /// The true sources (m).
    pub sources: &'a [[f64; 2]],
    /// A hit lies within this of a true bearing (degrees).
    pub tol_deg: f64,
    /// A linear array's axis (degrees), or `None`.
    pub mirror_axis_deg: Option<f64>,
}

/// The census of a data set: `rows` are its recordings' DoAs found with `config` (in the
/// order of `rec.files`), scored against `truth`; each recording is localised again with
/// [`without`] no rule, each rule in turn and every rule.
///
/// # Errors
/// As [`localise_files`]; or if the rows, files and poses differ in length.
pub fn run_census(
    rec: &Recordings<'_>,
    config: &SslConfig,
    rows: &[FileDoas],
    truth: &Truth<'_>,
) -> Result<RuleCensus> {
    let Recordings {
        files,
        array,
        channels,
        noise,
    } = *rec;
    let Truth {
        poses,
        sources,
        tol_deg,
        mirror_axis_deg,
    } = *truth;
    ensure!(
        rows.len() == files.len() && rows.len() == poses.len(),
        "{} recordings, {} rows of DoAs and {} poses",
        files.len(),
        rows.len(),
        poses.len()
    );
    let fold = |a: f64| fold_azimuth(a, mirror_axis_deg);
    let folded = |d: &Doa| Doa {
        azimuth_deg: fold(d.azimuth_deg),
        ..*d
    };
    let azimuths =
        |r: &FileDoas| -> Vec<f64> { r.doas.iter().map(|d| fold(d.azimuth_deg)).collect() };
    // N raised with every rule on, then each rule off in turn, then all of them off.
    let wide = localise_files(files, array, channels, &without(config, &[]), noise)?;
    let released = Rule::ALL
        .iter()
        .map(|&rule| localise_files(files, array, channels, &without(config, &[rule]), noise))
        .collect::<Result<Vec<_>>>()?;
    let peaks = localise_files(files, array, channels, &without(config, &Rule::ALL), noise)?;
    let stops: Vec<Stop> = (0..rows.len())
        .map(|k| {
            let pose = &poses[k];
            let bearing = |s: &[f64; 2]| {
                fold(wrap_deg(
                    pose.bearing_to(*s).to_degrees() - pose.theta_deg(),
                ))
            };
            Stop {
                near: sources
                    .iter()
                    .enumerate()
                    .map(|(i, s)| Near {
                        source: i,
                        bearing_deg: bearing(s),
                        distance_m: (s[0] - pose.x).hypot(s[1] - pose.y),
                    })
                    .filter(|n| n.distance_m < NEAR_M)
                    .collect(),
                all: sources.iter().map(bearing).collect(),
                doas: rows[k].doas.iter().map(folded).collect(),
                extra: rows[k].extra.iter().map(|d| fold(d.azimuth_deg)).collect(),
                wide: azimuths(&wide[k]),
                released: released.iter().map(|r| azimuths(&r[k])).collect(),
                peaks: peaks[k].doas.iter().map(folded).collect(),
            }
        })
        .collect();
    Ok(census(&stops, config, tol_deg))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doa(azimuth_deg: f64, relative: f64, dominant_blocks: u32) -> Doa {
        Doa {
            azimuth_deg,
            elevation_deg: 0.0,
            strength: relative,
            relative,
            dominant_blocks,
            prominence: 1.0,
            significance: 50.0,
        }
    }

    /// A stop hearing a source at 0 (found), with near sources at 60, 120, -60, -120, 170,
    /// 90 and -90 missed for each reason in turn, and DoAs at 1 (the source at 0), 30 (let
    /// in by height), -30 (by its block votes) and 150 (by incoherence).
    fn stop() -> Stop {
        let all = vec![0.0, 60.0, 120.0, -60.0, -120.0, 170.0, 90.0, -90.0];
        Stop {
            near: all
                .iter()
                .enumerate()
                .map(|(source, &bearing_deg)| Near {
                    source,
                    bearing_deg,
                    distance_m: 2.0,
                })
                .collect(),
            all,
            doas: vec![
                doa(1.0, 1.0, 9),
                doa(30.0, 0.5, 0),
                doa(-30.0, 0.1, 3),
                doa(150.0, 0.2, 0),
            ],
            extra: vec![],
            // 60: cut at N; 100 lies 10 degrees from the nearest source.
            wide: vec![1.0, 30.0, -30.0, 150.0, 62.0, 100.0],
            released: vec![
                vec![118.0],  // height: 120 (0.2 high)
                vec![-58.0],  // prominence
                vec![-123.0], // sidelobe
                vec![168.0],  // significance
            ],
            peaks: [
                0.0, 60.0, 120.0, -60.0, -120.0, 170.0, 90.0, 30.0, -30.0, 150.0,
            ]
            .iter()
            .map(|&a| doa(a + 1.0, if a == 120.0 { 0.2 } else { 0.1 }, 0))
            .collect(),
        }
    }

    #[test]
    fn each_miss_goes_to_the_rule_whose_absence_releases_it() {
        let config = SslConfig::default();
        let c = census(&[stop()], &config, 5.0);
        assert_eq!((c.pairs, c.found), (8, 1));
        // -90 has no peak within 5 degrees; 90 has one that no single rule releases.
        assert_eq!((c.no_peak, c.no_peak_beside, c.jointly), (1, 0, 1));
        assert_eq!(c.no_peak_displaced, 0);
        // A peak 8 degrees from -90: displaced, not absent.
        let mut s = stop();
        s.peaks.push(doa(-82.0, 0.1, 0));
        assert_eq!(census(&[s], &config, 5.0).no_peak_displaced, 1);
        assert_eq!((c.cut_at_n, c.cut_but_extra), (1, 0));
        // 120's peak stands 0.2 high: above `incoherent_relative` (0.15), so it was the
        // coherence that kept it out.
        assert_eq!((c.low, c.coherent), (0, 1));
        assert_eq!((c.prominence, c.sidelobe, c.insignificant), (1, 1, 1));
        let missed = c.no_peak + c.cut_at_n + c.by_thresholds();
        assert_eq!(missed, c.pairs - c.found);
        assert_eq!((c.doas, c.false_doas), (4, 3));
        assert_eq!((c.by_height, c.by_dominance, c.by_incoherence), (1, 1, 1));
        // A larger N would add 62 (on the source at 60) and 100 (on none).
        assert_eq!((c.beyond_n, c.beyond_n_on_source), (2, 1));
        // Each miss is listed with its source and reason, in the truth's order.
        let listed: Vec<(usize, Reason)> = c.missed.iter().map(|m| (m.source, m.reason)).collect();
        assert_eq!(
            listed,
            [
                (1, Reason::CutAtN),
                (2, Reason::Coherent),
                (3, Reason::Prominence),
                (4, Reason::Sidelobe),
                (5, Reason::Insignificant),
                (6, Reason::Jointly),
                (7, Reason::NoPeak),
            ]
        );
        assert_eq!(c.missed[1].peak_relative, Some(0.2));
        assert_eq!(c.missed[6].peak_relative, None);
    }

    #[test]
    fn a_source_without_a_peak_beside_another_is_told_apart() {
        // A far source 8 degrees from the unresolved one at -90: within `min_sep_deg`
        // (10), the two make one peak at most.
        let mut s = stop();
        s.all.push(-98.0);
        let c = census(&[s], &SslConfig::default(), 5.0);
        assert_eq!((c.no_peak, c.no_peak_beside), (1, 1));
    }

    #[test]
    fn a_low_peak_is_low_when_the_incoherence_exception_is_off() {
        let config = SslConfig {
            incoherent_relative: 0.0,
            ..SslConfig::default()
        };
        let c = census(&[stop()], &config, 5.0);
        assert_eq!((c.low, c.coherent), (1, 0));
    }

    #[test]
    fn the_octave_votes_beyond_n_are_counted_with_the_cut() {
        let mut s = stop();
        s.extra = vec![61.0];
        let c = census(&[s], &SslConfig::default(), 5.0);
        assert_eq!((c.cut_at_n, c.cut_but_extra), (1, 1));
    }

    #[test]
    fn without_takes_off_one_rule_and_raises_n() {
        let base = SslConfig::default();
        let n = without(&base, &[]);
        assert_eq!(n.num_peaks, 16);
        assert_eq!(
            (n.min_relative, n.sidelobe_ratio),
            (base.min_relative, base.sidelobe_ratio)
        );
        let c = without(&base, &[Rule::Sidelobe]);
        assert_eq!(c.num_peaks, 16);
        assert_eq!(c.sidelobe_ratio, 0.0);
        assert_eq!(c.min_relative, base.min_relative);
        assert_eq!(c.min_significance, base.min_significance);
        let h = without(&base, &[Rule::Height]);
        assert_eq!((h.min_relative, h.incoherent_relative), (0.0, 0.0));
        let all = without(&base, &Rule::ALL);
        assert_eq!(
            (
                all.min_relative,
                all.min_prominence,
                all.sidelobe_ratio,
                all.min_significance
            ),
            (0.0, 0.0, 0.0, 0.0)
        );
    }
}
