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
    /// Particle density divisor `D`: `M = floor(known cells / D)`, at most
    /// [`crate::mapper::MAX_PARTICLES`]. Default: 9.
    pub density_d: f64,
    /// Random-walk standard deviation `sigma_p` (m). Default: 0.01.
    pub sigma_p_m: f64,
    /// DoA standard deviation `sigma` (degrees). Default: 5.
    pub sigma_deg: f64,
    /// Distance decay `beta` (m): the code's 50 pixels at 0.05 m. Default: 2.5.
    pub beta_m: f64,
    /// Early-exit threshold on the covariance's largest eigenvalue (m^2). Default: 0.1.
    pub lambda_thresh_m2: f64,
    /// DBSCAN radius (m). Default: 0.1.
    pub dbscan_eps_m: f64,
    /// DBSCAN `MinPts` as a fraction of `M`, in `(0, 1]`. Default: 0.1.
    pub min_pts_frac: f64,
    /// Resample when `N_eff < ceil(frac M)` (`1 / C`, in `(0, 1]`). Default: 0.1.
    pub resample_frac: f64,
    /// Association range `gamma` in units of `sigma`. Default: 3.
    pub gamma_sigmas: f64,
    /// Traversals of the stops per round (the paper's `2K` steps). Default: 2.
    pub passes: usize,
    /// Estimates closer than this (m) are merged at the end. Default: 0.5.
    pub merge_dist_m: f64,
    /// Upper bound on filtering rounds (a guard; each round finds at most one source).
    /// Default: 64.
    pub max_rounds: usize,
    /// DoAs per stop `N`: a row with more is an error. Default: 4.
    pub num_doas: usize,
    /// Rounds retried, each from a fresh particle draw, after a round that finds no
    /// cluster or whose estimate explains no DoA, before the mapping ends (the paper ends
    /// at the first round without a cluster; see the module documentation). Default: 2.
    pub retries: usize,
    /// Ablation variant. Default: [`Variant::Ca`].
    pub variant: Variant,
    /// Move each new source to the least-squares intersection of the bearings it explains
    /// (Gauss-Newton on the angular residuals: the maximum-likelihood position under
    /// Gaussian DoA noise once the association is known), dropping rays beyond `2 sigma`
    /// one at a time and giving the dropped DoAs back to the next rounds; after merging,
    /// merged sources are refitted on all their rays. Not in the paper: I-ASM's
    /// association makes it possible, and the centroid of a cloud stopped at
    /// `lambda_thresh` is coarser than the bearings it came from. Default: true (the paper
    /// profile: false).
    pub refine: bool,
    /// The refinement's position leaves out the rays that miss it by more than this many
    /// of the source's own robust standard deviations (1.4826 times the median of its
    /// rays' misses, the Gaussian-consistent median absolute deviation), or by more than
    /// [`IasmConfig::trim_floor_deg`] where that is wider: the three-sigma rule, with the
    /// spread measured on the source's rays instead of assumed. Such a ray stays the
    /// source's (association is the `2 sigma` gate's: its DoA is still explained, not
    /// given back to make a ghost) but does not move it. Needs four rays or more (with
    /// three, the median is one ray's miss); and the trimmed fit is taken only if every
    /// ray the source keeps still lies within `2 sigma` of it (otherwise the rays left out
    /// were the ones that fixed the source's range, across a line of nearly collinear
    /// rays). 0 turns it off. Not in the paper. Default: 3 (the paper profile: 0, and it
    /// needs `refine`).
    ///
    /// Why: `sigma` (5 degrees) is the DoA error the particles and the association must
    /// allow for over every source and stop; a source whose rays agree to a degree tells
    /// more. Its `2 sigma` gate keeps a ray that misses by 7-9 degrees, typically a weak
    /// peak on the flank of a stronger one or the far end of a reverberant talker's DoAs,
    /// and least squares lets that one ray pull the source by 5-10 cm:
    /// `speech_two_rt08`'s far talker (MVDR) took a DoA 8 degrees off its bearing from
    /// 4.1 m, beside eight rays within 2 degrees, and moved 6 cm away from the truth.
    /// Measured (the suite and `fixtures/heldout`, 3
    /// renderings x 3 maps, both methods): summed mean OSPA 2.046 -> 2.004 m (suite; 5
    /// rows better by more than 2 mm, 1 worse) and 2.535 -> 2.467 m (held-out; 10 better,
    /// 4 worse), no source count changed; `speech_one_rt08` 0.034 / 0.024 -> 0.015 /
    /// 0.010, `speech_two_snr15` MVDR 0.073 -> 0.043; the worst row `speech_two_rt05`
    /// GCC-PHAT 0.048 -> 0.061. Five-talker surveys rendered by pyroomacoustics (another
    /// simulator; 20 runs each): MVDR 0.115 -> 0.103 and 0.159 -> 0.140 m, the rest within
    /// 0.003. Arrangement II (50 runs) unchanged: its rays' spread is per-source bias, not
    /// single outliers. Without the `2 sigma` check, one survey's source across an L of
    /// stops slid 0.5 m (MVDR 0.151 -> 0.246 m). Dropping the trimmed rays instead (given
    /// back) made ghosts of them (`speech_one_silence_snr12` GCC-PHAT 0.039 -> 0.094 m).
    /// Trims of 2.5 and 4, and floors of 1 and 3 degrees, gain alike.
    ///
    /// The deviations are judged first from where most of the rays meet (the least median
    /// of the misses over the points where two rays cross, with Rousseeuw's small-sample
    /// factor), and only then from the least-squares fit, when that point's trim is not
    /// taken: a talker a metre from a wall is heard from the far stops in one peak with its
    /// image, several degrees off, and least squares spreads two such rays' pull over all,
    /// so that none stands out from it (`l_wing`'s wing talker, GCC-PHAT: rays 6 degrees
    /// off from two of six stops, the fit 0.4 m off the talker). Taken only if it keeps
    /// half the information the rays give on the position in its worst direction: rays
    /// that agree because their stops lie on a line towards the source say nothing of its
    /// range. Measured (3 renderings x 10 maps, both methods): the suite's
    /// summed mean OSPA 2.643 -> 2.599 m, `fixtures/heldout` 4.269 -> 4.197 m, no right
    /// count lower; `l_wing` GCC-PHAT 0.134 -> 0.074, `three_talkers_fan` 0.118 / 0.133 ->
    /// 0.075 / 0.112, `speech_two_snr15` GCC-PHAT 0.117 -> 0.071; the worst rows
    /// `notched_hall_respeaker6` GCC-PHAT 0.540 -> 0.564, `dogleg_uma8` GCC-PHAT 0.318 ->
    /// 0.339, `reverberant_low_snr` MVDR 0.054 -> 0.072 (a clean ray trimmed with an 8-degree
    /// one among seven noisy ones). Arrangement II (50 runs): from raw audio MVDR unchanged
    /// (0.147 m), GCC-PHAT 0.152 -> 0.155 against the published truth but 0.037 -> 0.035 m
    /// once each map is fitted to it (the poses' frame); the authors' tables 0.158 -> 0.160
    /// and 0.172 -> 0.173.
    pub trim_mads: f64,
    /// The narrowest trim of [`IasmConfig::trim_mads`] (degrees): rays that agree more
    /// closely than the DoAs can be told apart (a 1-degree azimuth grid, the far-field
    /// steering model's error at a robot's ranges) give a median miss too small to judge
    /// by. Default: 2.
    pub trim_floor_deg: f64,
    /// A source must explain DoAs from at least this many stops (after refinement); a
    /// cluster that explains fewer is clutter: its DoAs are used up and no source is
    /// reported. Two bearings always intersect, so two stops prove nothing; three are the
    /// fewest whose agreement is evidence. Default: 3 (the paper profile: 1).
    pub min_observations: usize,
    /// When DBSCAN finds no cluster, take the particles of the densest square of side
    /// `2 eps` and its eight neighbours instead of ending the round (the paper ends it):
    /// with broad DoAs (a small array, many sources) the cloud settles without `MinPts`
    /// particles within `eps`, and rounds that end so stop the mapping with most DoAs
    /// unexplained. A source found so must explain at least five stops (a diffuse cloud's
    /// densest cell is weaker evidence than a cluster). Default: false, in both profiles:
    /// measured (3 seeds, N = 3-4), it takes `sparse_ten` from 0.62-0.68 to 0.40-0.44 m
    /// and `rows_ten` heard by the 4-microphone ReSpeaker from 0.45-0.53 to 0.22-0.29 m,
    /// but arrangement II from GCC-PHAT DoAs from 0.164 to 0.193 m (ours) and 0.171 to
    /// 0.197 m (the authors' table). Since the vote ranks its proposals by likelihood
    /// (see [`IasmConfig::vote_min_stops`]) the default does better on those rows without
    /// it (GCC-PHAT 0.293 -> 0.166 m, MVDR 0.230 -> 0.163 m, 3 seeds): it is kept to
    /// reproduce those measurements, not as a setting for small arrays.
    pub densest_fallback: bool,
    /// When the filtering rounds end, look for sources they missed by voting: every two
    /// remaining DoAs of different stops that cross (in front of both stops, at more than
    /// 10 degrees) propose their crossing; among the proposals that at least this many
    /// stops have a remaining DoA within `2 sigma` of, the most likely (each such stop
    /// weighted by the Gaussian of its miss, as the particles are) is associated and
    /// refined like a round's source, and kept if it then explains at least this many
    /// stops; repeated until none does.
    /// The rounds' particle clouds split between sources seen by a handful of DoAs each
    /// (a sparse scene, few DoAs per stop), and the retries run out while they are still
    /// there; the vote is deterministic and finds them. The DoAs of the rounds' clutter
    /// (clusters of fewer than [`IasmConfig::min_observations`] stops) are given back to
    /// it first (see the module documentation). 0 turns it off. Not in the paper.
    /// Default: 5 (the paper profile: 0).
    pub vote_min_stops: usize,
    /// A second, smaller quorum for the vote (after [`IasmConfig::vote_min_stops`] finds
    /// nothing more): a proposal that at least this many *thresholded* stops agree on
    /// (stops whose row holds every peak the SSL's thresholds let through, as the `ssl`
    /// crate's `min_relative` does, rather than the strongest `N` of more: a row of fewer
    /// than `N` DoAs, or a full one that `N` did not cut, when the SSL says so; see
    /// [`Mapper::run_rows`]) is a source, when they are still among its rays after the
    /// refinement. Never fewer than
    /// [`IasmConfig::min_observations`]; 0 turns it off; it does nothing when the vote is
    /// off. Not in the paper. Default: 3 (the paper profile: 0).
    ///
    /// Why: in a sparse scene a source 1.5-2 m beside the path is heard by the three or
    /// four stops that pass it (and by far stops, whose DoAs the rounds' 15-degree gate
    /// often gives to other sources), fewer than the five the vote asks for. Five guard
    /// against chance: a full row holds `N` DoAs whatever was heard, and with every row
    /// full three stops agree by chance somewhere (measured with the authors' tables of
    /// arrangement II, where every row is full: a quorum of 3 over every stop takes
    /// GCC-PHAT from 0.170 to 0.320 m with 12.3 sources per map; counting only
    /// thresholded stops it stays at 0.170). A thresholded row reports only peaks that
    /// stood out, so three of them agreeing is evidence. Measured (3 seeds, N = 4):
    /// `sparse_ten` GCC-PHAT 0.337 -> 0.211 m, MVDR 0.460 -> 0.331 m; every other scene of
    /// the suite and of `fixtures/heldout`, and arrangement II (50 runs, ours and the
    /// authors' tables), unchanged. A quorum of 3 over every stop instead (full rows
    /// too) gains more on `sparse_ten` (0.18 / 0.21 m) but makes ghosts of reverberation
    /// in `reverberant_low_snr` (0.27 / 0.20 -> 0.45 / 0.40 m) and of the authors' tables.
    /// What tells the rows apart is not whether they are full but whether `N` cut them:
    /// with N = 3 and two talkers at RT60 0.8 s most rows hold four to ten peaks above the
    /// thresholds, while where ten sources stand beside the path a row of four is often
    /// all there was. Counting the full rows that `N` did not cut (the SSL reports it),
    /// measured with 3 seeds: `sparse_ten` MVDR 0.331 -> 0.239 m (GCC-PHAT 0.211 ->
    /// 0.210), the ReSpeaker rows 0.166 / 0.163 -> 0.142 / 0.135 m (10 of 10 in every
    /// seed), `sparse_eight_speech` 0.338 / 0.302 -> 0.311 / 0.267 m; no other scene of
    /// the suite or of `fixtures/heldout` moves, nor arrangement II (where 33 of 40 rows
    /// are cut at N = 4, both methods).
    ///
    /// A third quorum follows when the second finds nothing: thresholded stops count one
    /// each and cut ones `vote_min_thresholded_stops / vote_min_stops` (3/5: the two
    /// quorums' own exchange rate, five stops of any kind being as good as three
    /// thresholded), and a proposal needs `vote_min_thresholded_stops` in all. With the
    /// defaults it adds one case: four stops of which two are thresholded. Why: a source
    /// heard by the four stops that pass it, two of them crowded by louder sources (their
    /// rows cut at `N`), met neither quorum. Measured: five talkers in a room rendered by
    /// pyroomacoustics (another simulator than ours; 13 stops, RT60 0.5 s, N = 4, 20 seeds),
    /// MVDR 0.473 -> 0.359 m (3 -> 4 of 5 sources); `sparse_ten` MVDR 0.239 -> 0.206 m; no
    /// other scene of the suite or of `fixtures/heldout` moves, nor arrangement II (50
    /// runs, ours and the authors' tables in both profiles).
    ///
    /// A cut row's strongest DoA counts its stop in full, in this quorum and in the
    /// thinly-heard rule ([`Mapper::drop_implausible`]): the rate is for what a row of
    /// many peaks holds beside its sources (reflections, which rank below the direct paths
    /// that make them), and a row's first DoA is a source's in 98-100 % of the synthetic
    /// scenes' rows (see [`IasmConfig::rank_gain`]). Why: with three stops one cut row
    /// made any source thinly heard (2.6 stops' worth): `speech_one_rt08` rendered with
    /// its stops 1.6 m apart lost its talker, heard by all three within 4 degrees, in
    /// every seed. Measured (CA, N = 3 or 4): the
    /// sparse-stop set 0.353 -> 0.338 m (5 rows better, none worse; that talker found in
    /// every seed, 1.000 -> 0.115 m); the pyroomacoustics surveys 0.339 -> 0.328 (RT60
    /// 0.8 s and SNR 10 dB, N = 4, GCC-PHAT: 0.47 / 0.48 -> 0.29 / 0.30 m, five sources in
    /// 95 / 100 % of maps instead of none; but RT60 0.8 s at N = 8 0.49 / 0.25 -> 0.60 /
    /// 0.27, a ghost more, where rows cut at eight peaks are the room's own); the suite,
    /// `fixtures/heldout`, two more draws of each of their scenes and arrangement II
    /// unchanged.
    pub vote_min_thresholded_stops: usize,
    /// Stops that heard nothing count against a source. A stop *speaks against* a source
    /// when its row holds at least one DoA and every peak the SSL's thresholds let through
    /// (fewer than `N` DoAs, or `N` not cut at `N`: the thresholded rows of
    /// [`IasmConfig::vote_min_thresholded_stops`]; the SSL found no further peak worth
    /// reporting, as the `ssl` crate's `min_relative` threshold does), none of them lies
    /// within `gamma` of the bearing to the source (but another source's: a DoA that
    /// misses this one by [`TAKEN_MISS_SIGMAS`] `sigma` or more and another mapped source
    /// by less than one excuses nothing), it is no further from the source than
    /// the furthest stop that heard it, and no other mapped source is nearer to the stop
    /// than the source's distance divided by this ratio (a nearer source may mask it).
    /// The first such stop is forgiven; each further one cancels a stop that the source
    /// explains, and a source left with fewer than [`IasmConfig::min_observations`] is
    /// clutter, removed (its DoAs returned) before the merge. 0 turns it off. Not in the
    /// paper. Default: 1.5 (the paper profile: 0).
    ///
    /// Why: in a room nothing hides a source from the array, so a source that is heard
    /// from three stops but missed, with room to spare, by stops at least as close to it
    /// is where reflections and sidelobes of other stops happen to cross (the one-talker
    /// scenes' ghosts: `one_source`, GCC-PHAT, 0.34 -> 0.009 m; `speech_one_rt05` 0.17-0.18
    /// -> 0.008-0.015 m; `speech_two_rt05` 0.15 -> 0.04 m). Why the first is forgiven: one
    /// stop can miss a real source by chance (a talker's pause, a louder moment of
    /// another); on the authors' recordings one stop of 40 reports three GCC-PHAT DoAs,
    /// and without the pardon a near source seen from three stops is lost in 2 runs of 50.
    /// Why 1.5: a source 1.5 times further than every other is at most 3.5 dB weaker by
    /// its direct path (equal powers); further away it is often lost under a louder one's
    /// peak, and measured, a ratio of 2 loses real sources of the ten-source rows
    /// (`rows_ten` 0.04 -> 0.07-0.11 m) while 1 (only where it would be the nearest)
    /// keeps the speech scenes' ghosts. Rows cut at `N` (a table's full rows, or N below
    /// the number of sources heard) never speak against anything; counting the full rows
    /// that `N` did not cut changed no map measured (the suite, `fixtures/heldout`,
    /// arrangement II), and keeps one meaning of a row that holds all it heard. Only sources that
    /// stay mask: the check repeats until none falls, so that one ghost beside a few stops
    /// does not excuse their silence towards another (measured on the held-out one-talker
    /// scenes of `fixtures/heldout`: two ghosts of three seeds gone, 0.23 -> 0.07 m and
    /// 0.20 -> 0.04 m; the suite and arrangement II unchanged). Why an empty row says
    /// nothing: a stop where the SSL found nothing significant at all (the `ssl` crate's
    /// `min_significance`) heard silence, and silence says nothing about any one source:
    /// everything may have paused, or left (a talker heard from six stops is mapped,
    /// whatever the stops after it heard).
    pub absence_ratio: f64,
    /// No source lies nearer than this (m) to a stop: the robot stood there, and the
    /// array is on it. A cluster that close to the path is where DoAs along the direction
    /// of travel meet (every bearing from collinear stops passes through every point of
    /// their line), not a source; it is removed before the merge. (Giving such particles
    /// the likelihood's floor instead moves the cloud just beyond the limit, where it
    /// takes the same DoAs: measured, `rows_ten` heard by the ReSpeaker 0.20 -> 0.28 m.)
    /// 0 turns it off. Not in
    /// the paper. Default: 0.3 (a small robot's radius and a source's own size; the
    /// nearest loudspeakers of the authors' recordings stand 0.6 m from the path) (the
    /// paper profile: 0).
    pub min_range_m: f64,
    /// A source whose own DoAs meet further than this beyond the bounding box of the
    /// map's known cells is removed before the merge: it is a talker's mirror image in a
    /// wall (a reflection's DoAs, consistent from stop to stop, cross where the image is),
    /// or something beyond the map; the particles, drawn on the known cells, settle by
    /// the wall instead and make a ghost there. Where they meet: bearing least squares at
    /// any distance, dropping the worst ray while one misses by more than `sigma` (half
    /// [`fit_bearings`]' gate, so that one stray DoA cannot pull the image's rays to a
    /// compromise inside the map). 0 turns it off. Not in the paper. Default: 0.5 m (a
    /// DoA error of a few degrees moves a real source by less at the ranges a robot maps;
    /// an image lies twice the talker's distance from the wall beyond it) (the paper
    /// profile: 0). Measured: the last ghost of the held-out one-talker scenes
    /// (`speech_one_rt03_moved`, GCC-PHAT: 0.206 -> 0.047 m), the suite and arrangement II
    /// unchanged.
    pub beyond_map_m: f64,
    /// A source whose DoAs meet where the map holds nothing the robot saw (an unknown cell,
    /// or beyond the map), whose rays from every stop that heard it but one pass through an
    /// occupied cell further than this (m) from it, and which, mirrored in the line of
    /// those crossings, lands within [`IasmConfig::merge_dist_m`] of another mapped source,
    /// is removed before the merge: it is that source's image in the wall. A wall mirrors a
    /// talker in front of it into an image behind it, and the reflection's DoAs cross there
    /// from stop to stop as a source's would; but a reflection exists only where its ray
    /// meets the wall, so every ray to an image crosses the wall's cells, the robot's range
    /// sensor, stopped by the wall, never saw the space behind it, and the talker stands
    /// where the wall mirrors the image back. A source in free or occupied space (a
    /// loudspeaker on a table) is never removed, nor one heard through a gap (a door), nor
    /// one behind an obstacle with no source at its mirror place (a talker behind a
    /// counter, which a 2-D map cannot tell from a wall). Occupied cells within this
    /// distance of the source are its own (its body, the furniture it stands on) and block
    /// nothing; one ray may pass (a wall's gap in the map's raster, a doorway's edge). The
    /// beyond-the-map rule ([`IasmConfig::beyond_map_m`]) catches images far beyond the
    /// map; this one those within it, as in the unknown block behind the wall by
    /// arrangement II's loudspeakers (an image 0.85 m beyond the wall, inside the map's
    /// bounding box). 0 turns it off; without a surveyed map (an open region around the
    /// stops) there is no wall and it removes nothing. Not in the paper. Default: 0.3 m (a
    /// talker's or a loudspeaker's own size, as [`IasmConfig::min_range_m`]) (the paper
    /// profile: 0). Measured: see the module docs.
    pub wall_clearance_m: f64,
    /// The map is the room: a source must lie in a cell the map marks free, or within this
    /// distance (m) of one (a source may stand at a wall, on a table, in a vent's grille),
    /// or in unknown space that a stop which heard it sees through cells that are not
    /// occupied (a corner the robot's range sensor never surveyed, a doorway's far side),
    /// unless a wall lies between it and the free cell nearest it within
    /// [`IasmConfig::merge_dist_m`] (it is then just behind the wall's face: the unknown
    /// the wall hid, not a place a sound comes from). One that does not, whichever step
    /// made it, moves to the free place nearest it
    /// where its own DoAs still fit (as many of its stops within the vote's gate, 2
    /// `sigma`, as before, less one, and never fewer than
    /// [`IasmConfig::min_observations`]), or is refused ([`Refusal::OutsideRoom`]). Only
    /// on a surveyed map (one with occupied cells): around the stops of an open region the
    /// unknown is merely unsurveyed ([`IasmConfig::beyond_map_m`] still holds there). 0
    /// turns it off. Not in the paper.
    ///
    /// Why: an occupancy map's unknown cells beyond a wall are space the robot's range
    /// sensor never reached, because the wall stopped it, and a sound heard in the room
    /// comes from the room (or through an opening into free space). Where DoAs meet beyond
    /// a wall they meet at a mirror image, or they fit a source at the wall within their
    /// error (a vent high on a wall, whose bearings a far-field array bends by its
    /// elevation), and the vote's place, made of crossings with a 2-sigma of a metre, may
    /// fall anywhere along them. Default: 0.3 m, as [`IasmConfig::wall_clearance_m`]
    /// (a talker's or a loudspeaker's own size; a wall in a map is 0.1-0.3 m thick, so
    /// that the cells just behind a wall's face are the wall, not the space beyond it)
    /// (the paper profile: 0). Why a source just behind a wall's face moves to the face
    /// although a stop sees it "in the open": the stop's view is shortened by this margin,
    /// which ends it in front of the wall; a talker in an alcove whose rays meet 0.3 m
    /// behind its back wall (its image there pulls its DoAs) stood in the unknown, 0.6 m
    /// from the talker, and moved to the wall's face stands 0.35 m from it. Moving a
    /// point onto the region that holds the truth (a half-plane, locally) never takes it
    /// further from the truth. An occupied cell near free space (a table, a
    /// loudspeaker's own cells) is not moved from. Measured (`docs/decisions/0010` and its
    /// history in git):
    /// `corridor_alcoves` 0.202 / 0.262 -> 0.186 / 0.231 m (GCC-PHAT / MVDR),
    /// `l_west_wing` (held out) GCC-PHAT 0.202 -> 0.126; `dogleg_uma8` (held out) MVDR
    /// kept the right count in 27 % of maps, not 47 (a vent's estimate 1 m off, beyond the
    /// wall, had stood there; moved to the face, its rays' own crossing was found behind
    /// the wall and refused); every other scene of the suite and arrangement II unchanged.
    pub room_margin_m: f64,
    /// The vote lets a DoA that a source already explains support a second source too,
    /// where the DoA lies within this many `sigma` of the bearing to it and its stop's row
    /// is thresholded (the rows of [`IasmConfig::vote_min_thresholded_stops`]: every peak
    /// the SSL's thresholds let through, none a filler); such a stop counts at the cut
    /// rows' rate, `vote_min_thresholded_stops / vote_min_stops`, in the vote's quorums and
    /// in the three stops' worth a source needs ([`Mapper::drop_implausible`]), and
    /// the DoA stays with the source that explained it first ([`Ray::shared`]). 0 turns it
    /// off. Not in the paper. Default: 0.5 (the paper profile: 0, and it needs the vote).
    ///
    /// Why: implicit association gives every DoA to one source, but from a stop that has
    /// two sources in one direction (one behind the other, a few degrees apart) the array
    /// hears one peak, which is both sources' evidence. A source beside the path whose
    /// other rays are few then lacks the stop: `sparse_ten`'s (5.0, 1.2) and (1.5, 8.5)
    /// were each heard within 3 degrees from four stops, but two of the four DoAs had gone
    /// to sources further along the same rays. Why only thresholded rows: a row filled up
    /// to `N` (a published table's, whatever its stop heard) holds reflections too;
    /// measured, sharing them made ghosts from the authors' tables (arrangement II, 50
    /// runs: MVDR 0.166 -> 0.194 m, GCC-PHAT 0.170 -> 0.234). Why half a sigma: the DoA
    /// already has an explanation, so a second one must fit it more closely than an
    /// unexplained DoA must; at 0.75 and 1 sigma, `reverberant_low_snr` gains a ghost
    /// (GCC-PHAT 0.312 -> 0.352 m, MVDR 0.193 -> 0.241) next to its louder talker, made of
    /// that talker's own DoAs. Measured at 0.5 (the suite and
    /// `fixtures/heldout`, 3 renderings x 3 maps): `sparse_ten` GCC-PHAT 0.200 -> 0.139 m
    /// (8-9 -> 9-10 of 10 found), `rows_ten_respeaker4` MVDR 0.160 -> 0.151 (worst 0.312 ->
    /// 0.231), `sparse_eight_speech` GCC-PHAT 0.282 -> 0.266 (worst 0.443 -> 0.305); every
    /// other scene, and arrangement II (50 runs, from raw audio and from the authors'
    /// tables), unchanged.
    pub share_gate_sigmas: f64,
    /// Once the rounds and the vote are done and the implausible sources removed, every
    /// DoA goes to the mapped source it fits best ([`Mapper::reassociate`]): a DoA that a
    /// source explains moves to another that lies nearer its bearing (within `gamma` and
    /// with no DoA of that stop yet), the sources that gained or lost DoAs are refined
    /// again, and a source left with fewer than [`IasmConfig::min_observations`] stops
    /// is removed ([`Refusal::Reassigned`]; its DoAs given back); repeated until nothing
    /// moves. Not in the paper. Default: true (the paper profile: false).
    ///
    /// Why: implicit association is greedy. A round's source takes, at every stop, the
    /// nearest DoA within `gamma = 3 sigma` (15 degrees) of its bearing, whatever source
    /// made it, and a source found later cannot take it back. A cloud that settles short
    /// of a talker, on the talker's rays (from stops on one side of it, every point along
    /// the rays lies near its bearing), takes the talker's DoAs and makes a ghost, and
    /// the talker is left with the few stops nobody took (`three_talkers_rt06`, held
    /// out, MVDR, third rendering: a ghost 1.4 m in front of the talker at (1.2, 4.8)
    /// held five of the talker's DoAs that miss it by 2-6 degrees and the talker by
    /// 0.2-1.7; reassociated, the ghost keeps two stops and is gone). This is the
    /// assignment step of any clustering (k-means, EM): given the sources, each datum to
    /// the one that explains it best, with the paper's own rule (the nearest bearing
    /// within `gamma`; a gate of one `sigma` instead keeps `rows_ten` GCC-PHAT at 0.032 m
    /// but loses the ReSpeaker rows' gain, whose DoAs miss by more). Each DoA moves once
    /// (two sources whose refits move them would otherwise pass a DoA back and forth:
    /// `sparse_ten`, MVDR, 8 maps of 30 still moving after 8 passes), and sources closer
    /// than [`IasmConfig::merge_dist_m`] are merged first (two estimates of one source
    /// would split its DoAs and move apart into a source and a ghost). Why after the
    /// removals: a ghost about to be
    /// removed would take a talker's stray DoA first and move the talker's fit
    /// (`speech_two_snr15`, GCC-PHAT, first rendering: 0.059 -> 0.103 m when it ran
    /// before them). Measured (the suite and
    /// `fixtures/heldout`, 3 renderings x 3 maps, N as a user sets it):
    /// `three_talkers_rt06` MVDR 0.145 -> 0.079 m (worst 0.375 -> 0.080; 3 sources in
    /// every map), `reverberant_low_snr` GCC-PHAT 0.304 -> 0.294 (worst 0.705 -> 0.677),
    /// `rows_ten_respeaker4` GCC-PHAT 0.124 -> 0.116 (worst 0.168 -> 0.144), `rows_ten`
    /// MVDR 0.042 -> 0.039 and GCC-PHAT 0.033 -> 0.035; arrangement II (50 runs) MVDR
    /// 0.154 -> 0.152 m, GCC-PHAT 0.151 -> 0.148, the authors' tables 0.165 -> 0.163
    /// (MVDR) and 0.170 -> 0.167 (GCC-PHAT); five-talker surveys rendered by
    /// pyroomacoustics within 0.004 m either way. Every other scene unchanged.
    pub reassociate: bool,
    /// A source whose DoAs, each mirrored about its stop's array axis (azimuth `a` to
    /// `-a`), all but one fit another source within the vote's gate (2 `sigma`) at stops
    /// that heard that source too (a mirror is heard in the same recording as its source)
    /// and meet within [`IasmConfig::merge_dist_m`] of it, which is heard from more stops,
    /// is that source's mirror image in the array, and is removed
    /// ([`Refusal::ArrayMirror`]), when two or more of that source's stops, at headings 20
    /// degrees or more from every heading at which the mirror fitted, heard nothing
    /// towards the first but the walls' reflections of the other sources (each DoA within
    /// the gate of its bearing, traced through the wall it meets, passes another source
    /// within the gate), and the map does not hide it from them. Not in the paper.
    /// Default: on (the paper profile: off).
    ///
    /// Why: an array that is nearly symmetric about its axis hears a source off the axis
    /// and high above it also at the mirrored azimuth, as strongly at some stops (the
    /// paper's array: its lower triangle is symmetric about x, and its small upper one is
    /// what tells the two sides apart; a vent 2.3 m high, 1.5 m away, is heard at +149
    /// and -147 degrees). While the robot drives straight the mirrored DoAs cross at the
    /// source's mirror image across its path as consistently as the true ones; once it
    /// turns, the true place keeps being heard and the mirror is silent. Two real sources
    /// mirrored across a straight path are kept: no turn tells them apart. Why silence
    /// and not only the turn: a real source mirrored across the robot's line by another
    /// is heard after the turn too, though its DoAs there may go to a third source on the
    /// same line (arrangement II, MVDR from raw audio: a loudspeaker so refused in one
    /// run of 50, 0.147 -> 0.149 m, when the rule asked only that the first source had no
    /// DoA at the turned headings). Why the walls' reflections are no voice for it: the
    /// L of `l_wing` sends a talker's reflection in the hall's wall from where the vent's
    /// mirror lies to the stops after the turn. Why headings of the fitting DoAs only: the
    /// one DoA that is not a mirror (there, that reflection) may come from any stop.
    /// Measured (3 renderings x 10 maps per method): `l_wing` GCC-PHAT 0.283 -> 0.134 m,
    /// MVDR 0.252 -> 0.173 (the right count 33 / 67 -> 100 / 100 %); the rest of the
    /// suite, `fixtures/heldout` and arrangement II from raw audio (50 runs per method)
    /// identical; the authors' GCC-PHAT table (50 runs) 0.172 m either way, the right count
    /// 98 -> 100 %. What it cannot tell: a real source the robot no longer hears after a
    /// turn (a talker who fell silent as the robot turned, mirrored by another across its
    /// earlier path), at two stops or more.
    pub array_mirror: bool,
    /// A source whose DoAs are another mapped source's reflections in the map's walls is
    /// removed ([`Refusal::Reflection`]): each of its DoAs but one is the other's direct
    /// bearing or, traced through the wall its line meets, passes the other (within the
    /// vote's gate, 2 `sigma`, and within one `sigma` of how well the source itself fits
    /// it), as many of them as a source needs stops ([`IasmConfig::min_observations`])
    /// and half of them or more reflections, and each stop that heard such a reflection
    /// heard the other's direct sound too or has it hidden by a wall. A DoA counts as a
    /// reflection too where it blends the other's direct sound with its image in a wall
    /// near it (one peak between them, the image within 60 degrees and its path at most
    /// twice the direct one, the source no farther from that wall than the other), and a
    /// DoA from a stop the map hides the source from is no evidence for it. Only on a
    /// surveyed map (one with occupied cells). Not in the paper. Default: on (the paper
    /// profile: off). See `mapper/reflection/`.
    ///
    /// Why: a talker in an alcove is heard from the corridor's far stops only by its
    /// reflections in the alcove's side walls, and those heard from either side cross at
    /// the alcove's mouth as consistently as a source's own rays meet (`corridor_alcoves`:
    /// a ghost 0.9 m in front of the talker in most GCC-PHAT maps). The map holds the
    /// walls, so the image-source model says where each mapped source's reflections are
    /// heard (reflection-aware localisation, An et al., ICRA 2018). Why the conditions
    /// beyond the gate: a reflection is weaker than its direct sound and not heard
    /// without it where nothing hides the source; with eight or ten sources some image
    /// lies within 10 degrees of a real source's bearings by chance (`sparse_ten`: a
    /// talker whose own rays fitted it within 0.6 degrees, its "images" 9 off;
    /// `sparse_eight_speech`: a talker heard from three stops, two of them near images),
    /// and a ghost of reflections is made of as many reflections as a source of stops.
    ///
    /// A source's own DoAs that blend it with its image in a wall near it, judged from
    /// where most of its DoAs meet, do not move it: it stands where its other DoAs meet
    /// when that explains all of them better (a blend taken as a peak anywhere between the
    /// source and its image) and those DoAs still fix its position. And a source heard
    /// from some stops by its image in a wall near it instead of its direct sound stands
    /// where its other DoAs and those, unfolded in the wall, meet, when that explains all
    /// of them better by the Bayesian information criterion (each DoA taken as the image
    /// one more parameter) and moves it away from the wall more than along it.
    ///
    /// Measured, rule by rule (the suite, `fixtures/heldout` and arrangement II): the
    /// history of `docs/decisions/0010` in git; on scenes drawn at random, the decision
    /// itself.
    pub reflections: bool,
    /// For DoAs from a linear array: the azimuth of its line (degrees, array frame; the
    /// `ssl` crate's `MicArray::mirror_axis_deg`). Such an array hears the angle to its
    /// line only, so each DoA `a` is as much `2 * axis - a`, its mirror image, and the
    /// mapper takes both: the particles weigh both bearings, a source that explains one
    /// takes the other out of the row with it ([`crate::assoc::associate_mirrored`]), and
    /// only a robot whose heading changes between stops tells the source from its image
    /// (from one line of stops along the array's line the two are alike: such a source is
    /// reported with [`Source::mirror`]). `None` (the default, both profiles): the array
    /// is not linear, and a DoA is one bearing (and the field is left out of JSON).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mirror_axis_deg: Option<f64>,
    /// How a stop's DoA counts in the particles' likelihood behind the stronger DoAs of
    /// the same stop still unexplained: one behind `r` of them is a source with
    /// probability `rank_gain^r` and clutter otherwise, so it lifts a particle above the
    /// likelihood's floor `rank_gain^r` times as far as the stop's strongest
    /// ([`crate::pf::ParticleFilter::update_gained`]). The ranks are the order of each
    /// row as given (strongest first, as the `ssl` crate and MBSS Locate give them). In
    /// `(0, 1]`; 1 is the paper's likelihood, where every DoA counts alike. Not in the
    /// paper. Default: 0.5 (the paper profile: 1).
    ///
    /// Why: the paper's `exp(-d / beta)` favours the nearer of two places that explain as
    /// many stops, and with few stops a place where weaker peaks cross one of a talker's
    /// rays can be nearer. `one_source` rendered with its stops 2 m apart (three stops,
    /// GCC-PHAT) hears the talker as each stop's strongest DoA, within a degree of its
    /// bearings, yet the second DoAs of two stops (reflections) cross the first stop's
    /// ray at a place 1.0 m nearer the stops in sum: the first round's cloud settled
    /// there, took the first stop's DoA, and left the talker two stops (0.75 m mean OSPA
    /// over 10 seeds). A stop's strongest peak is a source's direct path more often
    /// than the next: over the suite's and held-out scenes rendered with sparse stops
    /// (N = 4), 98-100 % of the rows' first DoAs lie within 5 degrees of a source's
    /// bearing, 75-80 % of the second, 58-61 % of the third; on arrangement II the
    /// ranks score alike (65-90 %: there every DoA is one of ten sources, the first's
    /// misses are near sources' bias). As a mixture with the floor, a DoA of any rank
    /// still lifts the particles on it, which a multiplied gain did not (0.5 put the
    /// third DoA at 2.5 m under the floor and lost sources of ten-source scenes).
    /// Measured (CA, N = 3 or 4): the sparse-stop set (108
    /// rows, 10 seeds) 0.366 -> 0.353 m (10 rows better, 4 worse; `one_source` with 3
    /// stops, GCC-PHAT, 0.747 -> 0.131, two talkers in a fan with 3 stops 0.359 ->
    /// 0.122, three talkers at RT60 0.6 s with 6 stops 0.20 -> 0.12 and the right count
    /// in 80 -> 100 % of maps); arrangement II from the authors' tables (200 runs)
    /// GCC-PHAT 0.179 -> 0.169 m, MVDR 0.164 -> 0.157, the right count in 90.5 -> 96 %
    /// and 86.5 -> 99 % of runs; from raw audio unchanged (0.152 / 0.147 m); the
    /// pyroomacoustics surveys (20 rows) 0.351 -> 0.339; two more draws of every
    /// suite and held-out scene (116 rows, 20 seeds) 0.0685 -> 0.0678; the suite and
    /// `fixtures/heldout` 0.0656 -> 0.0656 and 0.0692 -> 0.0695 (map seeds: the one row
    /// that moved, `speech_two_snr15` GCC-PHAT, is 0.140 -> 0.138 over 100 seeds). A
    /// gain of 0.3 loses sources of the ReSpeaker's ten-source scene (right count 100
    /// -> 75 %) and gains less on arrangement II; 0.75 keeps half the sparse set's gain.
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
    /// contradict, outside the map's room, or made of another source's images (in the
    /// walls, or the array's mirror) (see [`IasmConfig::refine`],
    /// [`IasmConfig::min_observations`], [`IasmConfig::vote_min_stops`],
    /// [`IasmConfig::share_gate_sigmas`], [`IasmConfig::min_range_m`],
    /// [`IasmConfig::absence_ratio`], [`IasmConfig::room_margin_m`],
    /// [`IasmConfig::wall_clearance_m`], [`IasmConfig::reflections`] and
    /// [`IasmConfig::array_mirror`]).
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
            densest_fallback: false,
            vote_min_stops: 5,
            vote_min_thresholded_stops: 3,
            absence_ratio: 1.5,
            min_range_m: 0.3,
            beyond_map_m: 0.5,
            wall_clearance_m: 0.3,
            room_margin_m: 0.3,
            share_gate_sigmas: 0.5,
            reassociate: true,
            array_mirror: true,
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
                array_mirror: false,
                reflections: false,
                rank_gain: 1.0,
                ..Self::default()
            },
        }
    }
}
