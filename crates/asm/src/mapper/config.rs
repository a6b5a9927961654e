//! The mapper's settings: the paper's parameters, the plausibility rules' and the
//! refinement's, the paper's ablation variants and the two profiles.

use super::*;

mod validate;

/// The paper's ablation variants.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Variant {
    /// Cluster average: the full I-ASM.
    #[default]
    Ca,
    /// Weighted sum: the particles' weighted mean instead of the largest cluster's centroid.
    Ws,
    /// Without distance penalty: the likelihood drops `exp(-d / beta)`.
    Wdp,
}

impl Variant {
    /// All variants, in the paper's order.
    pub const ALL: [Variant; 3] = [Variant::Ca, Variant::Ws, Variant::Wdp];

    /// Short name (`ca`, `ws`, `wdp`).
    pub fn name(self) -> &'static str {
        match self {
            Variant::Ca => "ca",
            Variant::Ws => "ws",
            Variant::Wdp => "wdp",
        }
    }
}

impl std::str::FromStr for Variant {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s.to_ascii_lowercase().as_str() {
            "ca" => Ok(Variant::Ca),
            "ws" => Ok(Variant::Ws),
            "wdp" => Ok(Variant::Wdp),
            _ => Err(ConfigError::UnknownVariant(s.to_owned())),
        }
    }
}

impl std::fmt::Display for Variant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// I-ASM parameters. The defaults are the robust profile ([`Profile::Robust`]): the
/// paper's parameters (or its authors' code's) with the rules beyond the paper on, each
/// field saying what the paper profile ([`Profile::Paper`], the paper's algorithm
/// exactly) sets instead.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IasmConfig {
    /// Particle density divisor `D` (known cells per particle): `M = floor(known cells / D)`,
    /// at most [`crate::mapper::MAX_PARTICLES`]. Default 9; 1 to 1e6. The paper's.
    pub density_d: f64,
    /// Random-walk standard deviation `sigma_p` of the prediction step (m). Default 0.01; 1e-6
    /// to 1. The paper's.
    pub sigma_p_m: f64,
    /// DoA standard deviation `sigma` of the likelihood (degrees). Default 5; 0.01 to 90. The
    /// paper's.
    pub sigma_deg: f64,
    /// Distance decay `beta` of the likelihood's `exp(-d / beta)` (m): the authors' code's 50
    /// pixels at 0.05 m. Default 2.5; 0.001 to 10000.
    pub beta_m: f64,
    /// A round's filtering stops once the cloud's largest covariance eigenvalue is below this
    /// (m^2). Default 0.1; 1e-9 to 10000. The paper's.
    pub lambda_thresh_m2: f64,
    /// DBSCAN radius `eps` (m). Default 0.1; 0.001 to 100. The paper's.
    pub dbscan_eps_m: f64,
    /// DBSCAN `MinPts` as a fraction of `M`. Default 0.1; in `(0, 1]`. The paper's.
    pub min_pts_frac: f64,
    /// Resample when `N_eff < ceil(frac M)` (`1 / C`). Default 0.1; in `(0, 1]`. The paper's.
    pub resample_frac: f64,
    /// Association gate `gamma`, in units of `sigma`. Default 3; 0.01 to 100. The paper's.
    pub gamma_sigmas: f64,
    /// Traversals of the stops per round (the paper's `2K` steps). Default 2; 1 to 100.
    pub passes: usize,
    /// Estimates closer than this (m) are merged into their mean at the end. Default 0.5; 0 to
    /// 10000. The paper's.
    pub merge_dist_m: f64,
    /// Most filtering rounds (each finds at most one source): a guard on the cost. Default 64;
    /// 1 to 10000.
    pub max_rounds: usize,
    /// DoAs per stop `N`; a row with more is an error. Default 4; 1 to 64.
    pub num_doas: usize,
    /// Rounds retried from a fresh particle draw after a round that finds no cluster or whose
    /// estimate explains no DoA, before the mapping ends. Default 2 (both profiles); 0 to 100.
    /// Why: the paper ends at the first such round, but a round is one random draw, and with a
    /// few sources left among clutter a fresh cloud often settles on one (module docs).
    pub retries: usize,
    /// The paper's ablation variant. Default [`Variant::Ca`], the full I-ASM.
    pub variant: Variant,
    /// Each new source moves to the least-squares crossing of the bearings it explains (rays
    /// beyond `2 sigma` given back to the next rounds); merged sources are refitted. Default
    /// true (paper profile: false). Why: once the association is known this is the
    /// maximum-likelihood position under Gaussian DoA noise, and a cloud stopped at
    /// `lambda_thresh` is coarser than the bearings it came from. Measured:
    /// `docs/decisions/0014-mapper-settings.md`, `refine`.
    pub refine: bool,
    /// The refinement leaves out of the position (not of the source) the rays that miss it by
    /// more than this many of the source's own robust standard deviations (1.4826 times the
    /// median miss), or by [`IasmConfig::trim_floor_deg`] where that is wider; four rays or
    /// more, and only if every ray kept still lies within `2 sigma`. Dimensionless; default 3
    /// (paper profile: 0, off); 0 to 10000. Why: the three-sigma rule with the spread measured
    /// on the source's own rays, so that one flank peak cannot pull a source whose rays agree
    /// to a degree. Measured: `docs/decisions/0014-mapper-settings.md`, `trim_mads`.
    pub trim_mads: f64,
    /// The narrowest trim of [`IasmConfig::trim_mads`] (degrees). Default 2; 0 to 180. Why:
    /// rays that agree more closely than the 1-degree grid and the far-field model's error give
    /// a median miss too small to judge by.
    pub trim_floor_deg: f64,
    /// A source must explain DoAs of at least this many stops; a cluster that explains fewer is
    /// clutter. Stops; default 3 (paper profile: 1); 1 to 100000. Why: two bearings always
    /// cross; three are the fewest whose agreement is evidence.
    pub min_observations: usize,
    /// After the rounds, the crossing of two remaining DoAs that at least this many stops
    /// support (a remaining DoA within `2 sigma`, weighted as the particles are) is a source
    /// the rounds missed; the most likely is taken, refined, and kept if it still explains this
    /// many; repeated until none. Stops; default 5 (paper profile: 0, off); 0 to 100000. Why:
    /// the rounds' clouds split between sources that a handful of DoAs each support, and the
    /// retries run out while they remain; the vote is deterministic. Measured:
    /// `docs/decisions/0014-mapper-settings.md`, `vote_min_stops`.
    pub vote_min_stops: usize,
    /// The vote's smaller quorum: stops whose row holds every peak the SSL's thresholds let
    /// through (not cut at `N`; [`Mapper::run_rows`]), then a third quorum counting cut rows at
    /// `vote_min_thresholded_stops / vote_min_stops` each. Stops; default 3 (paper profile: 0,
    /// off); never below [`IasmConfig::min_observations`]; 0 to 100000. Why: a row cut at `N`
    /// holds `N` DoAs whatever was heard, so three full rows agree somewhere by chance; a row
    /// that was not cut reports only peaks that stood out. Measured:
    /// `docs/decisions/0014-mapper-settings.md`, `vote_min_thresholded_stops`.
    pub vote_min_thresholded_stops: usize,
    /// Stops that heard nothing towards a source speak against it: a stop whose row holds every
    /// peak the SSL let through, none within `gamma` of the source (or only another source's),
    /// no further from it than its furthest hearing stop, and with no other mapped source
    /// nearer than the source's distance divided by this ratio (which may mask it). The first
    /// is forgiven; each further one cancels a stop the source explains. Dimensionless; default
    /// 1.5 (paper profile: 0, off); 0 to 10000. Why: in a room nothing hides a source from the
    /// array, and a source 1.5 times further than every other is at most 3.5 dB weaker.
    /// Measured: `docs/decisions/0014-mapper-settings.md`, `absence_ratio`.
    pub absence_ratio: f64,
    /// No source lies nearer than this (m) to a stop. Default 0.3 (paper profile: 0, off); 0 to
    /// 10000. Why: the robot stood there, and DoAs along its direction of travel meet anywhere
    /// on its line. Measured: `docs/decisions/0014-mapper-settings.md`, `min_range_m`.
    pub min_range_m: f64,
    /// A source whose own DoAs meet further than this (m) beyond the bounding box of the map's
    /// known cells is removed. Default 0.5 (paper profile: 0, off); 0 to 10000. Why: such a
    /// crossing is a mirror image in a wall, or something the map does not hold. Measured:
    /// `docs/decisions/0014-mapper-settings.md`, `beyond_map_m`.
    pub beyond_map_m: f64,
    /// A source in unknown space whose rays from every stop but one cross occupied cells
    /// further than this (m) from it, and which, mirrored in the line of those crossings, lands
    /// on another mapped source, is that source's image in the wall and is removed. Default 0.3
    /// (paper profile: 0, off); 0 to 10000. Why: a reflection's DoAs cross behind the wall as a
    /// source's would, where the range sensor, stopped by the wall, saw nothing. Measured:
    /// `docs/decisions/0014-mapper-settings.md`, `wall_clearance_m`.
    pub wall_clearance_m: f64,
    /// The map is the room: a source must lie in a free cell or within this (m) of one, or in
    /// unknown space that a stop which heard it sees through cells that are not occupied; one
    /// that does not moves to the nearest free place where its own DoAs still fit, or is
    /// refused. Only on a surveyed map. Default 0.3 (paper profile: 0, off); 0 to 100. Why: a
    /// sound heard in a room comes from the room. Measured:
    /// `docs/decisions/0014-mapper-settings.md`, `room_margin_m`.
    pub room_margin_m: f64,
    /// The vote lets a DoA a source already explains support a second source too, within this
    /// many `sigma` of the bearing to it and from a row that was not cut, counted at the cut
    /// rows' rate. Sigmas; default 0.5 (paper profile: 0, off); 0 to 100. Why: from a stop with
    /// two sources in one direction the array hears one peak, which is both sources' evidence.
    /// Measured: `docs/decisions/0014-mapper-settings.md`, `share_gate_sigmas`.
    pub share_gate_sigmas: f64,
    /// Once the rules have run, every DoA moves to the mapped source it fits best (within
    /// `gamma`, no DoA of that stop there yet), the sources refitted, and one left with fewer
    /// than [`IasmConfig::min_observations`] stops removed. Default true (paper profile:
    /// false). Why: implicit association is greedy; this is the assignment step of any
    /// clustering. Measured: `docs/decisions/0014-mapper-settings.md`, `reassociate`.
    pub reassociate: bool,
    /// A source whose DoAs are another mapped source's reflections in the map's walls (first
    /// order, traced on the occupancy map) is removed, and a source's own blends with its image
    /// do not move it. Default true (paper profile: false); only on a surveyed map. Why: the
    /// map holds the walls, so the image-source model says where each source's reflections are
    /// heard. Measured: `docs/decisions/0014-mapper-settings.md`, `reflections`.
    pub reflections: bool,
    /// For DoAs from a linear array: the azimuth of its line (degrees, array frame; the `ssl`
    /// crate's `MicArray::mirror_axis_deg`); each DoA `a` is taken with its mirror `2 axis -
    /// a`, and only a change of heading tells them apart ([`Source::mirror`]). Default `None`
    /// (not linear, and left out of JSON); finite. Why: a linear array hears only the angle to
    /// its line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mirror_axis_deg: Option<f64>,
    /// A stop's DoA behind `r` stronger DoAs still unexplained counts in the likelihood as a
    /// source with probability `rank_gain^r`, as clutter otherwise. In `(0, 1]`; default 0.5
    /// (paper profile: 1, every DoA alike). Why: a stop's strongest peak is a source's direct
    /// path more often than the next (98-100 % of the simulated rows' first DoAs, 75-80 % of
    /// their second). Measured: `docs/decisions/0014-mapper-settings.md`, `rank_gain`.
    pub rank_gain: f64,
}

/// Named sets of I-ASM parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// The paper's algorithm exactly, as its authors coded it (Table I).
    Paper,
    /// The paper's, plus bearing refinement, a minimum of three observing stops, a vote
    /// for the sources the rounds missed (in which a DoA two sources lie on supports
    /// both), and no source where the robot stood, that stops which heard nothing
    /// contradict, outside the map's room, or made of another source's images in the
    /// walls (see [`IasmConfig::refine`],
    /// [`IasmConfig::min_observations`], [`IasmConfig::vote_min_stops`],
    /// [`IasmConfig::share_gate_sigmas`], [`IasmConfig::min_range_m`],
    /// [`IasmConfig::absence_ratio`], [`IasmConfig::room_margin_m`],
    /// [`IasmConfig::wall_clearance_m`] and [`IasmConfig::reflections`]).
    #[default]
    Robust,
}

impl Profile {
    /// Short name (`paper`, `robust`).
    pub fn name(self) -> &'static str {
        match self {
            Profile::Paper => "paper",
            Profile::Robust => "robust",
        }
    }
}

impl std::str::FromStr for Profile {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s.to_ascii_lowercase().as_str() {
            "paper" => Ok(Profile::Paper),
            "robust" => Ok(Profile::Robust),
            _ => Err(ConfigError::UnknownProfile(s.to_owned())),
        }
    }
}

impl std::fmt::Display for Profile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Default for IasmConfig {
    fn default() -> Self {
        Self {
            density_d: 9.0,
            sigma_p_m: 0.01,
            sigma_deg: 5.0,
            beta_m: 2.5,
            lambda_thresh_m2: 0.1,
            dbscan_eps_m: 0.1,
            min_pts_frac: 0.1,
            resample_frac: 0.1,
            gamma_sigmas: 3.0,
            passes: 2,
            merge_dist_m: 0.5,
            max_rounds: 64,
            num_doas: 4,
            retries: 2,
            variant: Variant::Ca,
            refine: true,
            trim_mads: 3.0,
            trim_floor_deg: 2.0,
            min_observations: 3,
            vote_min_stops: 5,
            vote_min_thresholded_stops: 3,
            absence_ratio: 1.5,
            min_range_m: 0.3,
            beyond_map_m: 0.5,
            wall_clearance_m: 0.3,
            room_margin_m: 0.3,
            share_gate_sigmas: 0.5,
            reassociate: true,
            reflections: true,
            rank_gain: 0.5,
            mirror_axis_deg: None,
        }
    }
}

impl IasmConfig {
    /// The parameters of a profile: [`IasmConfig::default`] is [`Profile::Robust`].
    pub fn profile(profile: Profile) -> Self {
        match profile {
            Profile::Robust => Self::default(),
            Profile::Paper => Self {
                refine: false,
                trim_mads: 0.0,
                min_observations: 1,
                vote_min_stops: 0,
                vote_min_thresholded_stops: 0,
                absence_ratio: 0.0,
                min_range_m: 0.0,
                beyond_map_m: 0.0,
                wall_clearance_m: 0.0,
                room_margin_m: 0.0,
                share_gate_sigmas: 0.0,
                reassociate: false,
                reflections: false,
                rank_gain: 1.0,
                ..Self::default()
            },
        }
    }
}
