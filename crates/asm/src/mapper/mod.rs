//! I-ASM (Algorithm 1 of the paper): filtering, clustering and implicit association,
//! repeated until clustering finds nothing; and what the default profile adds to it.
//!
//! ## The rooms of this module
//!
//! | file | the step |
//! |---|---|
//! | `config.rs` | [`IasmConfig`]: the paper's parameters, the rules', the profiles |
//! | `stops.rs` | [`Stops`]: the stops a map is made from, built once |
//! | `rounds.rs` | the paper's rounds: filter, cluster, associate ([`Mapper::run`], [`Mapper::round`]) |
//! | `vote.rs` | the vote after the rounds ([`Mapper::vote`]) |
//! | `stages.rs` | what runs after the rounds, as one list ([`Stage`], [`IasmConfig::stages`]) |
//! | `rules.rs` | what cannot be a source ([`Mapper::drop_implausible`]), thin sources, merging |
//! | `reassociation.rs` | each DoA to the source it fits best ([`Mapper::reassociate`]) |
//! | `room.rs` | the map is the room: no source behind a wall ([`IasmConfig::room_margin_m`]) |
//! | `reflection/` | a source's reflections in the map's walls are no source ([`IasmConfig::reflections`]); `own.rs`: its own blends and its image place it where its direct sound is heard |
//! | `refine.rs` | bearing least squares with trimmed rays ([`refine_by_bearings`], [`fit_bearings`]) |
//! | `tests/` | the claims, on scenes whose answer is known |
//!
//! ## Algorithm
//! 1. Turn every DoA into a world bearing, `wrap(azimuth + theta_k)`.
//! 2. **Filter**: draw `M = floor(n / D)` particles from the map's `n` known cells; visit the
//!    stops `1..K` `passes` times (twice in the paper), each time predicting (random walk),
//!    weighting with the stop's remaining DoAs, resampling when `N_eff < ceil(M / C)`, and
//!    stopping early once the cloud's largest covariance eigenvalue is below
//!    `lambda_thresh`.
//! 3. **Cluster** the particles with DBSCAN (`eps`, `MinPts = 0.1 M`); if the adaptive
//!    resampling never ran in the round (few stops), resample once first, since the
//!    uniform initial cloud has no cluster and its weights would be lost. The largest
//!    cluster's centroid is the new source (the WS variant takes the weighted mean of all
//!    particles instead).
//! 4. **Associate** ([`crate::assoc`]): at every stop, the DoA nearest the source's bearing,
//!    if within `gamma = 3 sigma`, is explained by it and removed.
//! 5. Finally, merge estimates closer than 0.5 m into their mean.
//!
//! The paper stops at the first round whose clustering finds nothing. That round is one
//! random draw, though: with a few sources left that are each seen by a handful of DoAs
//! among clutter, a fresh cloud often settles on one of them. So a round with no cluster,
//! like a round whose source explains no DoA (its cloud settled where DoAs of different
//! sources cross), is dropped and the next starts from a new draw; after `retries + 1`
//! failed rounds in a row the mapping ends, as it does after `max_rounds` rounds.
//!
//! Every angle difference is wrapped to `(-pi, pi]` (the authors' code compares unwrapped
//! angles, so a DoA near ±180 degrees can miss its source).
//!
//! ## Profiles: the paper's, and the default
//!
//! [`Profile::Paper`] is the algorithm above, exactly (with the retry rule). The default,
//! [`Profile::Robust`], keeps it and adds, in each round:
//!
//! - **Refine** ([`IasmConfig::refine`]): the source moves to the least-squares
//!   intersection of the bearings it explains; rays further than `2 sigma` from the fit are
//!   given back to the next rounds (a 15-degree gate lets one source take a neighbour's
//!   DoAs), and a ray far beyond the source's own spread stays its but no longer moves it
//!   ([`IasmConfig::trim_mads`]).
//! - **Three stops at least** ([`IasmConfig::min_observations`]): a single bearing fixes no
//!   point, and a cluster explaining fewer stops is clutter where that draw settled; its
//!   DoAs leave the rounds (so that the next draws do not settle there again) and are given
//!   back to the vote, so that a talker's ray a reflection crossed is not lost with it.
//! - **The strongest DoA first** ([`IasmConfig::rank_gain`]): a stop's DoA behind a
//!   stronger one still unexplained counts as a source with probability one half, so that
//!   a place where second peaks (reflections) cross a talker's ray does not win for lying
//!   nearer the robot.
//!
//! and after the rounds:
//!
//! - **Vote** ([`Mapper::vote`]): where remaining DoAs cross, a place that enough stops
//!   agree on ([`IasmConfig::vote_min_stops`]; fewer if their rows hold every peak the SSL
//!   let through, [`IasmConfig::vote_min_thresholded_stops`]) is a source the rounds missed:
//!   in sparse scenes the clouds split between sources and the retries run out while they
//!   remain.
//! - **What cannot be** ([`Mapper::drop_implausible`]): a source where the robot stood
//!   ([`IasmConfig::min_range_m`]: DoAs along the direction of travel meet anywhere on its
//!   line), one that nearer stops which heard other sources and nothing there speak against
//!   ([`IasmConfig::absence_ratio`]), one whose DoAs meet beyond the map or behind a wall as
//!   the wall's mirror image of another source ([`IasmConfig::beyond_map_m`],
//!   [`IasmConfig::wall_clearance_m`]), and one with too little evidence once rows cut at
//!   `N` count for less ([`Mapper::drop_implausible`]). What they remove is reported
//!   with the rule and the stops ([`MapResult::refused`]), so that a user can see which
//!   rule, and which setting, kept a source out.
//! - **Each DoA to the source it fits best** ([`Mapper::reassociate`]): implicit
//!   association is greedy, so once every source is known each DoA moves to the one nearest
//!   its bearing, and a source left with fewer than three stops was made of others' DoAs.
//!
//! The steps after the paper's merge run from one list, [`IasmConfig::stages`]
//! (`stages.rs`): a stage whose settings are off is not in it, and the paper profile's is
//! empty. What each of these changed, measured, is in
//! `docs/decisions/0007-robust-mapper-profile.md` and `docs/decisions/0014-mapper-settings.md`.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::Pose;
use crate::assoc::Ray;
use crate::dbscan::{Dbscan, DbscanParams, Label};
use crate::error::{ConfigError, Error, Result};
use crate::map::{Cell, OccupancyMap};
use crate::pf::{Likelihood, ParticleFilter, covariance, mean};
use crate::wrap_rad;

mod config;
mod history;
mod reassociation;
mod refine;
mod reflection;
mod room;
mod rounds;
mod rules;
mod stages;
mod stops;
#[cfg(test)]
mod tests;
mod vote;

pub use config::*;
pub use history::{
    HEARD_SIGMAS, History, MASKING_RATIO, MOVE_STOPS, REACH_FACTOR, RECALL_RANGE, SILENT_P,
    SourceState,
};
pub use refine::*;
pub use rounds::*;
pub use stages::Stage;
pub use stops::Stops;
use vote::*;

/// One mapped source.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Source {
    /// x (m, world frame).
    pub x: f64,
    /// y (m, world frame).
    pub y: f64,
    /// DoAs explained by it (removed by implicit association).
    pub observations: usize,
    /// Particles in its cluster.
    pub particles: usize,
    /// Covariance of its cluster's particles (m^2): an uncertainty ellipse. For a source
    /// the vote made (no particles), of the crossings of its DoAs' rays near it, or, with
    /// fewer than two there, the spread its DoAs allow at `sigma` (the bearing fit's
    /// Cramer-Rao bound), never a point's zero.
    pub covariance: [[f64; 2]; 2],
    /// The filtering round (from 1) that found it.
    pub round: usize,
    /// Its cluster's particles (for pictures; not serialised).
    #[serde(skip)]
    pub cluster: Vec<[f64; 2]>,
    /// The DoAs it explains: robot position (m) and world bearing (rad) (not serialised).
    #[serde(skip)]
    pub rays: Vec<Ray>,
    /// Whether the position was refined by bearing least squares (see
    /// [`IasmConfig::refine`]).
    pub refined: bool,
    /// For a linear array's DoAs ([`IasmConfig::mirror_axis_deg`]): where the mirror images
    /// of its DoAs meet, when they fit nearly as well as its own (the robot's headings did
    /// not change enough between the stops that heard it to tell the two apart). The
    /// source may be there instead. `None` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mirror: Option<[f64; 2]>,
    /// The stops whose DoAs it explains as one peak of its direct sound and its image in a
    /// wall near it (with [`IasmConfig::reflections`]): they do not move it, and miss it
    /// towards the wall by more than the others. Empty for most sources.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub blends: Vec<usize>,
    /// The stops whose DoAs it explains as its image in a wall near it, heard instead of
    /// its direct sound (with [`IasmConfig::reflections`]): it stands where their rays,
    /// unfolded in that wall, meet its others, or, from stops the map hides it from, where
    /// its others meet. Empty for most sources.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub images: Vec<usize>,
    /// When it was heard, and its state at the end of the run (see [`History`]).
    #[serde(flatten)]
    pub history: History,
}

/// A source the mapper found and did not keep ([`MapResult::refused`]): where it was, the
/// stops whose DoAs it explained, and the rule that refused it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Refused {
    /// x (m, world frame).
    pub x: f64,
    /// y (m, world frame).
    pub y: f64,
    /// The stops (from 0) whose DoAs it explained; those DoAs count as unexplained.
    pub stops: Vec<usize>,
    /// Why it was refused.
    #[serde(flatten)]
    pub rule: Refusal,
}

/// The rule that refused a source ([`Refused`]); see [`Mapper::drop_implausible`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "rule", rename_all = "snake_case")]
pub enum Refusal {
    /// Nearer a stop than [`IasmConfig::min_range_m`], or its rays meet further than
    /// [`IasmConfig::beyond_map_m`] beyond the map, or behind a wall as another source's
    /// image in it ([`IasmConfig::wall_clearance_m`]).
    Misplaced,
    /// Too few stops once the rows the SSL cut at `N` count at the vote's exchange rate
    /// ([`IasmConfig::vote_min_thresholded_stops`]).
    ThinlyHeard,
    /// Stops that heard other sources and nothing near its bearing, no further from it
    /// than the stops that heard it and not masked by a nearer source
    /// ([`IasmConfig::absence_ratio`]; the first of them is forgiven), and, before the
    /// first stop that heard it or after the last, nearer it than every stop that did.
    SpokenAgainst {
        /// Those stops (from 0).
        against: Vec<usize>,
    },
    /// Its DoAs fit other mapped sources better and went to them, leaving it fewer than
    /// [`IasmConfig::min_observations`] stops ([`IasmConfig::reassociate`]).
    Reassigned,
    /// Outside the room: in a cell the map marks occupied or unknown, further than
    /// [`IasmConfig::room_margin_m`] from a free one, and no free place near it fits its
    /// DoAs.
    OutsideRoom,
    /// Its DoAs are another mapped source's reflections in the map's walls, blends of that
    /// source with its reflection, or that source's own bearing, each but one
    /// ([`IasmConfig::reflections`]).
    Reflection,
}

/// The result of one I-ASM run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapResult {
    /// The sources, in the order found (merged ones at the first's place).
    pub sources: Vec<Source>,
    /// Filtering rounds run.
    pub rounds: usize,
    /// Particles per round, `M`.
    pub particles: usize,
    /// DoAs that no source explained.
    pub unexplained: usize,
    /// Those DoAs, per stop: world bearings (rad), in each row's order (not serialised).
    /// Where a source was missed, they show what the stops heard of it that no source
    /// took.
    #[serde(skip)]
    pub unexplained_bearings: Vec<Vec<f64>>,
    /// Sources that the rounds or the vote found and [`Mapper::drop_implausible`] removed
    /// (on the robot's path, or contradicted by stops that heard nothing), or
    /// [`Mapper::reassociate`] left with too few stops; their DoAs count as unexplained.
    pub removed: usize,
    /// What the mapper found and did not keep, and why: the sources
    /// [`Mapper::drop_implausible`] removed and the vote's proposals it refused for the
    /// same rules, one per place (within [`IasmConfig::merge_dist_m`]; the last reason
    /// given there), none within that distance of a mapped source. Where a source was
    /// missed although its DoAs were there, this says which rule, and which stops, kept it
    /// out.
    pub refused: Vec<Refused>,
}

impl MapResult {
    /// Source positions (m).
    pub fn positions(&self) -> Vec<[f64; 2]> {
        self.sources.iter().map(|s| [s.x, s.y]).collect()
    }
}

/// A validated I-ASM mapper for one occupancy map: the parameters checked, the map's known
/// cells collected and everything derived from the parameters computed once.
#[derive(Clone, Debug)]
pub struct Mapper {
    config: IasmConfig,
    /// The map: its walls for [`IasmConfig::wall_clearance_m`], its free cells for
    /// [`IasmConfig::room_margin_m`].
    map: OccupancyMap,
    /// Whether the map was surveyed (has occupied cells): where the room rule applies.
    surveyed: bool,
    cells: Vec<[f64; 2]>,
    /// The known cells' bounding box `(x0, x1, y0, y1)` (m): where the vote looks.
    bounds: (f64, f64, f64, f64),
    m: usize,
    lik: Likelihood,
    dbscan: Dbscan,
    /// Resample when `N_eff` falls below this.
    resample_below: f64,
    /// Association range (rad).
    gamma: f64,
    /// DoA standard deviation (rad).
    sigma: f64,
    /// What of a bearing fit's spread is left out ([`IasmConfig::trim_mads`]).
    trim: Trim,
    /// A linear array's line (rad, array frame; [`IasmConfig::mirror_axis_deg`]).
    mirror: Option<f64>,
}

/// What one filtering round ends with.
#[derive(Clone, Debug, PartialEq)]
pub enum Round {
    /// A source, with the DoAs it explains (already removed from the bearings); boxed, as
    /// it is ten times the size of the other variants.
    Found(Box<Source>),
    /// DBSCAN found no cluster in the round's cloud.
    NoCluster,
    /// The largest cluster's estimate explains no remaining DoA: the cloud settled where
    /// DoAs of different sources cross.
    NothingExplained,
    /// The estimate explains DoAs of fewer than [`IasmConfig::min_observations`] stops:
    /// they are taken out of the rounds as clutter (here) and no source is reported.
    Clutter(Vec<Ray>),
}

/// The most particles a round may have. The paper's one particle per nine 5-cm cells
/// covers 1,100 m^2 of known cells with this many (arrangement II's map needs 4,203); on
/// a larger map the first cloud is spread thinner (one particle per `known cells / M`
/// cells) instead of growing without bound: a round's clustering costs about `M^2`, and
/// 440,000 particles (a 100-m square of free cells) took five minutes a map.
pub const MAX_PARTICLES: usize = 50_000;

impl Mapper {
    /// Validates `config` and collects the map's known cells.
    ///
    /// # Errors
    /// [`Error::Config`] for a refused parameter, [`Error::EmptyMap`] if the map has no
    /// known cell or too few for one particle.
    pub fn new(map: &OccupancyMap, config: &IasmConfig) -> Result<Self> {
        config.validate()?;
        let cells: Vec<[f64; 2]> = map.known_cells().collect();
        let m = ((cells.len() as f64 / config.density_d).floor() as usize).min(MAX_PARTICLES);
        if m == 0 {
            return Err(Error::EmptyMap);
        }
        let mut bounds = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for c in &cells {
            bounds = (
                bounds.0.min(c[0]),
                bounds.1.max(c[0]),
                bounds.2.min(c[1]),
                bounds.3.max(c[1]),
            );
        }
        let sigma = config.sigma_deg.to_radians();
        let beta = (config.variant != Variant::Wdp).then_some(config.beta_m);
        let dbscan = DbscanParams {
            eps: config.dbscan_eps_m,
            min_pts: ((config.min_pts_frac * m as f64).round() as usize).max(1),
        }
        .check()?;
        Ok(Self {
            config: config.clone(),
            map: map.clone(),
            surveyed: map.has_occupied(),
            cells,
            bounds,
            m,
            lik: Likelihood::new(sigma, beta),
            dbscan,
            resample_below: (config.resample_frac * m as f64).ceil(),
            gamma: config.gamma_sigmas * sigma,
            sigma,
            trim: Trim::of(config),
            mirror: config.mirror_axis_deg.map(f64::to_radians),
        })
    }

    /// [`crate::assoc::associate_mirrored`] with this mapper's association range and
    /// mirror axis: removes from `bearings` the DoAs a source at `source` explains (with
    /// their mirror images, for a linear array) and returns them as rays.
    ///
    /// # Panics
    /// If `poses` and `bearings` differ in length.
    pub(crate) fn associate(
        &self,
        source: [f64; 2],
        poses: &[Pose],
        bearings: &mut [Vec<f64>],
    ) -> Vec<Ray> {
        crate::assoc::associate_mirrored(source, poses, bearings, self.gamma, self.mirror)
    }

    /// One stop's DoAs (array-frame azimuths, rad) as world bearings, non-finite ones
    /// dropped; for a linear array, each followed by its mirror image
    /// ([`IasmConfig::mirror_axis_deg`]).
    pub(crate) fn stop_bearings(&self, pose: &Pose, doas_rad: &[f64]) -> Vec<f64> {
        let mut row = Vec::with_capacity(2 * doas_rad.len());
        for &a in doas_rad.iter().filter(|a| a.is_finite()) {
            let b = pose.world_bearing(a);
            row.push(b);
            row.extend(
                self.mirror
                    .and_then(|axis| crate::assoc::mirror_bearing(pose, b, axis)),
            );
        }
        row
    }

    /// How many DoAs `rows` (world bearings, one row per pose) hold, a mirror pair
    /// counting once.
    pub(crate) fn unexplained(&self, poses: &[Pose], rows: &[Vec<f64>]) -> usize {
        poses
            .iter()
            .zip(rows)
            .map(|(p, r)| self.doas_in(p, r))
            .sum()
    }

    /// With DoAs from a linear array ([`IasmConfig::mirror_axis_deg`]), sets each source's
    /// [`Source::mirror`]: where the mirror images of its DoAs meet, when that is more than
    /// [`IasmConfig::merge_dist_m`] away, within the map, every image ray fits there
    /// within `2 sigma`, and their squared misses in units of `sigma` sum to less than
    /// [`MIRROR_CHI2`] more than the source's own. A DoA along the array's line is its own
    /// image and counts for both.
    pub(crate) fn mark_mirrors(&self, sources: &mut [Source]) {
        if self.mirror.is_none() {
            return;
        }
        for s in sources {
            let images: Vec<Ray> = s
                .rays
                .iter()
                .map(|r| Ray {
                    bearing: r.twin.unwrap_or(r.bearing),
                    twin: Some(r.bearing),
                    ..*r
                })
                .collect();
            let cost = |q: [f64; 2], rays: &[Ray]| -> f64 {
                rays.iter().map(|r| (r.miss(q) / self.sigma).powi(2)).sum()
            };
            s.mirror = least_squares_crossing(&images)
                .and_then(|start| fit_bearings(start, &images, self.sigma, self.trim))
                .filter(|(q, kept)| {
                    kept.len() == images.len()
                        && (q[0] - s.x).hypot(q[1] - s.y) > self.config.merge_dist_m
                        && self.within_bounds(*q, 0.0)
                        && cost(*q, &images) < cost([s.x, s.y], &s.rays) + MIRROR_CHI2
                })
                .map(|(q, _)| q);
        }
    }

    /// How many DoAs a row of world bearings holds: a mirror pair
    /// ([`Mapper::stop_bearings`]) counts once.
    fn doas_in(&self, pose: &Pose, row: &[f64]) -> usize {
        let Some(axis) = self.mirror else {
            return row.len();
        };
        let twins = row
            .iter()
            .filter(|&&b| {
                crate::assoc::mirror_bearing(pose, b, axis)
                    .is_some_and(|t| row.iter().any(|&o| wrap_rad(o - t).abs() <= 1e-9))
            })
            .count();
        row.len() - twins / 2
    }

    /// Particles per round, `M`: one per [`IasmConfig::density_d`] known cells, at most
    /// [`MAX_PARTICLES`].
    pub fn num_particles(&self) -> usize {
        self.m
    }

    /// The parameters.
    pub fn config(&self) -> &IasmConfig {
        &self.config
    }

    /// The DoA standard deviation (rad).
    pub(crate) fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The bearing fits' [`Trim`].
    pub(crate) fn trim(&self) -> Trim {
        self.trim
    }

    /// The particle likelihood.
    pub(crate) fn likelihood(&self) -> &Likelihood {
        &self.lik
    }
}
