//! Settings of the whole SSL front end, as plain data: one TOML table configures it.

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::ConfigError;
use crate::grid::ElevationRange;

/// How the spectra of successive blocks of frames are pooled into one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pooling {
    /// [`Pooling::Mean`] for a recording whose sound is steady and noise-like,
    /// [`Pooling::Max`] for any other, decided per recording from its blocks' levels and
    /// its spectrum in each octave of the band ([`crate::steady`]). A source that never
    /// pauses loses nothing to averaging, and averaging is what its noise and
    /// reverberation need; where anything starts, stops or takes turns, each source keeps
    /// its best moment.
    #[default]
    Auto,
    /// The largest value any block reached. Speech sources take turns: a talker who
    /// dominates only a few blocks keeps the peak of those blocks instead of having it
    /// averaged away by the blocks where another talker dominates.
    Max,
    /// The mean over blocks: a stationary source's peak sharpens, an intermittent one fades.
    Mean,
}

impl FromStr for Pooling {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "auto" => Ok(Pooling::Auto),
            "max" => Ok(Pooling::Max),
            "mean" | "sum" => Ok(Pooling::Mean),
            _ => Err(ConfigError::UnknownPooling(s.to_owned())),
        }
    }
}

/// Every setting of the SSL front end.
///
/// The defaults come from physics and the signals robots hear, not from one data set:
///
/// - **Band 200 Hz - 8 kHz.** Speech carries its energy there; below 200 Hz a 20-cm array
///   resolves almost nothing (the longest pair's phase changes by under 0.9 rad across the
///   whole circle) while room modes dominate.
/// - **Frame about 20 ms** (1024 samples at 48 kHz): speech is quasi-stationary over 20-30 ms,
///   and several talkers are more often separated in time-frequency at that scale.
/// - **Elevation searched for 3-D arrays** ([`ElevationRange::auto`]). Loudspeakers a metre
///   from a robot sit 30 degrees below its array; searched in the plane, their DoAs bend
///   towards the array's axis and the map's sources with them.
/// - **Blocks of 4 frames (80 ms), pooled with max** where anything starts, stops or
///   takes turns. Within a block one talker tends to dominate each bin, so the block's
///   covariance is close to rank one and its peak sharp; across blocks, talkers take
///   turns, and max pooling keeps every talker's best moment. A recording whose sound is
///   steady and noise-like is pooled by the blocks' mean ([`Pooling::Auto`]): nothing in
///   it has a best moment, and the mean averages its noise down.
///
/// - **Blocks of the room's decay left out** ([`SslConfig::decay_gate_db`]): after a
///   sound stops and in a talker's pauses, the diffuse decay would otherwise win the max
///   pooling with peaks along the room's axes.
/// - **N is an upper bound** ([`SslConfig::min_relative`]): peaks that barely rise above
///   the spectrum's background are not reported, unless they carry a signal that no
///   stronger peak carries ([`SslConfig::incoherent_relative`]): a quiet source, not a
///   loud one's reflection.
///
/// These choices were checked on real recordings of ten talkers (decision records 0003-0005):
/// short blocks beat one spectrum over the whole recording by a wide margin, and the
/// 64 ms frame of MBSS Locate (`frame_len = 4096` at 48 kHz) scores lower and costs more.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SslConfig {
    /// Angular-spectrum method. Default: [`Method::Mvdr`].
    pub method: Method,
    /// STFT frame length (samples, `>= 16`). Default: `None`: for GCC-PHAT, MVDR and
    /// SRP-PHAT, 32 ms at the recording's sample rate ([`FRAME_S`]), rounded up to a length
    /// of 2s, 3s and 5s (512 at 16 kHz, 1440 at 44.1 kHz, 1536 at 48 kHz); for MUSIC and
    /// NormMUSIC, the power of two at or above 20 ms (512 at 16 kHz, 1024 at 44.1 and 48).
    ///
    /// Why a duration: the same sound recorded at another rate is then cut into the same
    /// frames, bins (31.25 Hz apart at 16 and 48 kHz) and blocks, and gives the same DoAs.
    /// The default was the power of two at or above 20 ms for every method: 32 ms at 16
    /// kHz but 21 ms at 48, and the simulated scenes resampled from 16 to 48 kHz gave
    /// other rows and other maps (`reverberant_low_snr` MVDR 0.095 -> 0.443 m); with 32 ms
    /// at both, their rows agree within 1-3 degrees. Why 32
    /// ms: every simulated scene (16 kHz) was always analysed so, and on the authors'
    /// recordings (48 kHz) it does better than 21 ms: DoA score 0.506 / 0.487 -> 0.544 /
    /// 0.531 (MVDR / GCC-PHAT, published truth; 0.744 / 0.762 -> 0.762 / 0.769 in the
    /// poses' frame), maps 0.152 / 0.154 -> 0.147 / 0.152 m (50 runs, ten sources in
    /// every one). Why not for the subspace methods: their covariances want snapshots,
    /// and at 48 kHz NormMUSIC maps those recordings better with 21-ms frames (0.146
    /// against 0.157 m, 20 runs), MUSIC resolves two sources 40 degrees apart in 0.6 s with
    /// them and not with 32 ms. Cost: none (at 48 kHz, 1536-sample frames localise a
    /// recording as fast as 1024-sample ones, or a little faster).
    pub frame_len: Option<usize>,
    /// STFT hop (samples, `1..=frame_len`). Default: `None`, half the frame.
    pub hop: Option<usize>,
    /// Lower edge of the analysis band (Hz, `>= 0`). Default: 200.
    pub fmin_hz: f64,
    /// Upper edge of the analysis band (Hz); capped at the Nyquist frequency. Default: 8000.
    pub fmax_hz: f64,
    /// Azimuth grid step (degrees, in `(0, 90]`). Default: 1.
    pub az_step_deg: f64,
    /// Elevations searched. Default: `None`, chosen from the array by
    /// [`ElevationRange::auto`]: -60 to 60 degrees for a 3-D array, 0 for a planar one.
    pub elevation: Option<ElevationRange>,
    /// Frames per block: statistics are averaged within a block, then blocks are pooled
    /// (`>= 1`). Default: 4 (80 ms at the default frame and hop). A value beyond
    /// a recording's frames makes one block of the whole recording (one spectrum per
    /// recording, as pyroomacoustics computes by default).
    pub block_frames: usize,
    /// How block spectra are pooled. Default: [`Pooling::Auto`], per recording: the mean
    /// where its sound is steady and noise-like, max elsewhere ([`crate::steady`]).
    ///
    /// Why max: talkers take turns, and each keeps its best moment. [`Pooling::Mean`] is
    /// the better estimator for broadband sources that sound without pause in a noisy or
    /// reverberant room, where the best of many noisy blocks is an extreme value and lifts
    /// the room's ripples over the thresholds; with talkers who pause it loses some of
    /// them. Measured: two continuous talkers at RT60 0.8 s
    /// and SNR 5 dB 0.29 / 0.19 -> 0.06 / 0.05 m (GCC-PHAT / MVDR), but five real talkers
    /// in pyroomacoustics rooms MVDR 0.10-0.15 -> 0.24-0.52 m, and the authors' ten
    /// loudspeakers' GCC-PHAT maps 100 % -> 56 % of runs with all ten. Hence the choice
    /// per recording, which keeps max for every recording of speech we have and takes the
    /// mean for steady noise ([`crate::steady`] has the figures).
    pub pooling: Pooling,
    /// With max pooling ([`Pooling::Max`], or [`Pooling::Auto`] on a recording that is not
    /// steady): each direction keeps the mean of its `pool_top` largest block values
    /// instead of the largest alone (`>= 1`; 1 is plain max pooling, more than the blocks
    /// kept averages them all). Default: 1.
    ///
    /// Why one might raise it: under max pooling, one block's chance peak (sensor noise,
    /// a burst of reverberation) stands in the pooled spectrum as high as a source that
    /// dominated that block, and the maximum of many noisy blocks lifts the whole
    /// background; a source present in at least `pool_top` blocks keeps its height when
    /// they are averaged, a one-block fluke does not. Why the default stays 1, measured
    /// (3 seeds per scene): with 3, DoA scores rise in the noisy and
    /// crowded scenes (SNR 5 dB at RT60 0.8 s 0.42 -> 0.58, ten talkers 0.82-0.83 -> 0.87,
    /// two talkers with pauses, GCC-PHAT 0.79 -> 0.83) and the MVDR map of the authors'
    /// recordings improves (0.155 -> 0.141 m), but the lower background lifts a single
    /// talker's weak secondary peaks above [`SslConfig::min_relative`], and in the
    /// one-talker scene they cross into a ghost source in every seed.
    pub pool_top: usize,
    /// With max pooling ([`Pooling::Max`], or [`Pooling::Auto`] on a recording that is not
    /// steady), where each DoA lies: max pooling decides which directions hold
    /// sources, and each DoA that was the strongest direction of a block
    /// ([`crate::Doa::dominant_blocks`] at least 1) is then placed at the highest local
    /// maximum, within half of [`SslConfig::min_sep_deg`] of its pooled peak, of the mean
    /// azimuth profile of the blocks in which its direction stood highest, this share of
    /// the pooled blocks (`[0, 1]`; at least one block; 0 keeps every pooled peak's own
    /// azimuth, as MBSS Locate does). Default: 0.25.
    ///
    /// Why: the pooled maximum is an extreme value, and where it lies is decided by one
    /// block's noise and reverberation. Two continuous talkers at SNR 5 dB and RT60 0.8 s:
    /// the nearer one's max-pooled GCC-PHAT peaks scatter up to 5-7 degrees about its
    /// bearing, where the mean of the same recording's blocks puts them within 1-3
    /// ([`Pooling::Mean`] finds them there, but loses the talkers who pause). Averaging the
    /// blocks in which the DoA's direction was strong averages that noise down and leaves
    /// out the blocks of the other talkers, so a talker heard in a few blocks is placed by
    /// those; the window keeps each DoA in the part of the spectrum it was found in.
    ///
    /// Why only DoAs that dominated a block: a DoA that never was the strongest thing
    /// heard (a reflection, a sidelobe, a source under a louder one's flank) has no blocks
    /// of its own, its best blocks are another sound's, and placed sharply, reflections
    /// cross into ghosts more often. Why a quarter of the blocks. Measured
    /// (78 renderings of the 26 simulated scenes, 20 maps
    /// each; mean OSPA, share of maps with the right count): pooled peaks 0.0863 m, 90.6 %;
    /// every DoA placed, a tenth of the blocks 0.0832, a quarter 0.0803 (89.5 %), half
    /// 0.0807, all 0.0834; a quarter, only DoAs that dominated a block, **0.0803, 90.3 %**
    /// (localisation 0.0607 -> 0.0538 m, cardinality 0.0256 -> 0.0266). The suite 0.0920
    /// -> 0.0863 m, `fixtures/heldout` 0.0785 -> 0.0753, the pyroomacoustics real-speech
    /// surveys' 20 rows -5 % in sum. On the authors' recordings the maps do not move
    /// (aligned to the truth: MVDR 0.034 -> 0.037 m, GCC-PHAT 0.038 -> 0.035, all ten
    /// sources in every run): their DoAs move by a median of 0.5 degrees, and their errors
    /// are the poses'. Their DoA score in the poses' frame
    /// is 0.762 -> 0.744 (MVDR) and 0.762 -> 0.762 (GCC-PHAT); against the published
    /// truth, whose frame is offset, 0.525 -> 0.506 and 0.550 -> 0.487, as DoAs near the
    /// 5-degree line cross it. What it costs: a talker 0.9 m from a
    /// wall is placed slightly nearer its first reflection (the max-pooled block is often
    /// an onset, free of it; the averaged blocks are not): 0.035 -> 0.062 m (GCC-PHAT) in
    /// that held-out room.
    pub placement_share: f64,
    /// Refines each DoA of a row but the first on what the recording holds once the
    /// stronger DoAs are projected out (deflation, the alternating-projection step of the
    /// maximum-likelihood DoA estimator; see [`crate::deflate`]), in rows that `N` did not
    /// cut. `Some(true)` or `Some(false)` turns it on or off for every array. Default:
    /// `None`, on for a compact array: one whose far-field distance at the band's top,
    /// `2 D² f / c` ([`SslConfig::deflates`]), is under [`DEFLATE_FAR_FIELD_M`] (the
    /// ReSpeaker 4-mic 0.19 m, the 6-mic 0.40, the UMA-8 0.35 at 8 kHz), off for the
    /// paper's array (2.1 m) and a Kinect's line (2.4 m).
    ///
    /// Only rows whose DoAs explain what the array hears are refined
    /// ([`SslConfig::deflate_max_residual`]).
    ///
    /// Why: on a compact array a weaker source heard beside a stronger one peaks on the
    /// stronger one's wide lobe, 5-25 degrees off; deflated, within a degree or two.
    /// Measured (78 renderings of the 26 simulated scenes, 20
    /// maps each): two talkers heard by the ReSpeaker 4-mic 0.128 / 0.168 -> 0.085 /
    /// 0.056 m (GCC-PHAT / MVDR), six sources heard by the UMA-8 0.129 / 0.126 -> 0.130 /
    /// 0.116 (but with N = 8, held out, MVDR 0.107 -> 0.141), ten talkers heard by the
    /// ReSpeaker unchanged (the gate leaves their rows alone); `fixtures/heldout` 0.0753
    /// -> 0.0684 m, all 78 renderings 0.0803 -> 0.0771. Why not for a larger array: the step
    /// projects each stronger DoA out as a plane wave, and a source nearer than the
    /// array's far-field distance is none, so that much of it is left. On the paper's
    /// array deflating moves maps both ways (two talkers 0.026 / 0.018 -> 0.033 / 0.022 m,
    /// ten in rows 0.031 / 0.039 -> 0.030 / 0.038) and their mean not at all (0.0742 ->
    /// 0.0744 m over its 66 renderings, both methods); before the gate, MVDR lost in its reverberant rooms
    /// (`reverberant_low_snr` 0.193 -> 0.302 m). The authors' recordings
    /// (rows cut at `N = 4`) and the pyroomacoustics surveys of five talkers (rows the
    /// gate refuses) do not change either way. Cost: a row it refines takes about twice as
    /// long to localise (ReSpeaker, two talkers, 2 s: 1.25 -> 2.47 ms GCC-PHAT, 1.93 ->
    /// 3.77 ms MVDR).
    pub deflate: Option<bool>,
    /// With [`SslConfig::deflate`], a row is refined only when its DoAs explain the field:
    /// once they are all projected out, the power left per dimension is less than this
    /// share of the power per dimension (`[0, 1]`; 0 refines every row that `N` did not
    /// cut). A row whose DoAs leave fewer than two dimensions (three DoAs on a
    /// 4-microphone array) cannot be tested and is left alone. Default: 0.65.
    ///
    /// Why: deflation assumes the row's DoAs are all the sources the recording holds. The
    /// share is about 1 for spatially white noise and for a field of many more sources
    /// than the row holds (what a crowd looks like through a compact array), and the
    /// noise's share of the power when the row's plane waves are all there is. Measured
    /// (first renderings, rows of two DoAs heard by the
    /// ReSpeaker 4-mic): two talkers 0.46-0.63, ten talkers 0.66-0.73; rows of three DoAs
    /// among ten talkers 0.31-0.66, which is why they are not tested. Reverberation fills
    /// the residual as a crowd does, and the paper's array in the suite's reverberant
    /// rooms is not deflated either, where MVDR lost with it (`reverberant_low_snr` 0.193
    /// -> 0.302 m ungated, 0.193 gated). With the gate, deflation costs the suites
    /// nothing on average (`iasm regress` 0.0900 -> 0.0894 m, `fixtures/heldout` 0.0801
    /// -> 0.0718), ten talkers heard by the ReSpeaker are mapped at 0.126 / 0.137 m
    /// (GCC-PHAT / MVDR) against 0.116 / 0.149 without deflation (0.210 / 0.290 ungated),
    /// and two talkers keep its gain (0.173 / 0.242 -> 0.067 / 0.090 m). Why 0.65: it
    /// lies between those two scenes' rows, and means that at least a third of the power
    /// lies in the row's directions' span beyond what noise would put there.
    pub deflate_max_residual: f64,
    /// Number of DoAs reported, strongest first (`>= 1`). Default: 4.
    pub num_peaks: usize,
    /// Minimum azimuth separation between reported peaks (degrees, `[0, 180]`). Default: 10.
    pub min_sep_deg: f64,
    /// Peaks whose [`crate::Doa::relative`] height (above the spectrum's median, as a
    /// fraction of the strongest peak's) is below this are not reported, so that
    /// `num_peaks` is an upper bound a user can guess high rather than a quota (`[0, 1]`;
    /// 0 reports `num_peaks` peaks whatever they are, as MBSS Locate does). Default: 0.3.
    ///
    /// Why 0.3: with one or two talkers in a reverberant room, the spectrum's other peaks
    /// (reflections, sidelobes) stand 0 to 0.5 as high as the strongest; of the 188 such
    /// peaks that the simulated one- and two-talker scenes of the regression suite give
    /// with N = 6 (both methods), 166 lie below 0.3, against 12 of the talkers' own 64
    /// DoAs (the weaker talker, at some stops). In a room of ten talkers, weak far talkers
    /// lie below it too and are lost; on the authors' ten-loudspeaker recordings the first
    /// 4 DoAs of every stop lie above it (the DoA score is unchanged).
    pub min_relative: f64,
    /// A peak is also reported when the strongest direction of at least this many blocks
    /// lay within 2 degrees of it ([`crate::Doa::dominant_blocks`]), whatever its
    /// [`SslConfig::min_relative`] height; blocks holding half the energy of the block
    /// before or less do not count. 0 turns it off. Default: 2.
    ///
    /// Why: a talker far from the array, in a reverberant room, is heard over a nearer one
    /// only in the moments the nearer one pauses; in the pooled spectrum its peak then
    /// stands below `min_relative` (its best block is still mostly the other's
    /// reverberation), although for those moments it was the strongest thing the array
    /// heard. A reflection or a sidelobe is never the strongest direction of a block while
    /// its source sounds, and is after the source stops, in the room's decay: hence the
    /// rule on falling energy (the decay of a room with RT60 below 1.2 s falls by more than
    /// 3 dB from one 64-ms block to the next), and on the pauses: a block more than 10 dB
    /// below the recording's loudest does not count either (in a long silence each block's
    /// top is a random direction of the sensor noise), whatever
    /// [`SslConfig::decay_gate_db`] is.
    /// Why two blocks, not one: one block's top can be a fluke of the decay that the
    /// energy rule misses. Measured (the regression suite, 3 seeds): two talkers with
    /// pauses at RT60 0.5 s, DoA score GCC-PHAT 0.79 -> 0.81, MVDR 0.68 -> 0.78, every
    /// other scene and every map unchanged; on held-out variants (other rooms, talker
    /// positions, SNR) DoA scores rise by 0 to 0.08.
    pub dominance_blocks: usize,
    /// A peak other than the strongest is reported only when the spectrum dips between it
    /// and every higher peak by at least this fraction of its height above the median
    /// ([`crate::Doa::prominence`]): two peaks that the spectrum does not separate are one
    /// source's broad peak, split by noise (`[0, 1]`; 0 reports every local maximum, as
    /// MBSS Locate does). Default: 0.2.
    ///
    /// Why 0.2: it is Rayleigh's criterion for two equal point sources seen through a
    /// uniform aperture, whose summed pattern dips 19 % between them when they are just
    /// resolved; a shallower dip is not a second source the array can tell apart. At low
    /// SNR in a reverberant room one talker's peak is broad and ragged, and its ripples
    /// stand 10-20 degrees beside it, further apart than [`SslConfig::min_sep_deg`].
    /// Measured (3 seeds per scene): SNR 5 dB at RT60 0.8 s, two talkers
    /// mapped at 0.50 / 0.60 m (3-5 sources) -> 0.27 / 0.20 m (2-3); the held-out
    /// one-talker scenes' last ghosts gone (RT60 1.0 s: 0.18 / 0.20 -> 0.01 / 0.04 m); but
    /// ten continuous sources heard by the 4-microphone ReSpeaker, MVDR, 0.196 -> 0.230 m,
    /// where two sources a few degrees apart are one broad peak and splitting it helped.
    pub min_prominence: f64,
    /// A peak other than the strongest is reported only when it stands more than this
    /// many times as high as the stronger peaks' sidelobes there
    /// ([`crate::Localizer::plane_wave_profile`]: the method's own pooled spectrum of an
    /// ideal plane wave from each stronger peak's direction, through this array, band and
    /// grid, scaled by that peak's [`crate::Doa::relative`] height), unless it was the
    /// strongest direction of a block ([`crate::Doa::dominant_blocks`] at least 1)
    /// (`>= 0`; 0 turns the test off, as MBSS Locate has none). Default: 2.5.
    ///
    /// Why such a test: every array's response to one plane wave has sidelobes, at
    /// directions fixed by the array's geometry around the source's (the paper's array,
    /// GCC-PHAT, 200-8000 Hz: about 26-28 degrees either side, at 0.14-0.23 of the main
    /// peak in free field; MVDR's reach 0.31-0.40). As the robot turns or drives past a
    /// talker, its sidelobes turn with it, at a nearly fixed offset, and their rays cross
    /// near each other like a source's. In a reverberant room max pooling lifts them to
    /// about twice their free-field height (a single talker at RT60 0.8 s: 0.36-0.44,
    /// above [`SslConfig::min_relative`]). Why a ratio: what makes a sidelobe is the
    /// stronger peak's pattern, so its height is predicted; a second source there stands
    /// above the prediction by its own height. Why 2.5: the reverberant sidelobes measured
    /// 1.9-2.2 times their predicted height (that talker, GCC-PHAT); before the rule
    /// below, 2 left some (a ghost stayed in `three_talkers_rt06`) and 3 took 18 real
    /// DoAs of the suite's and the pyroomacoustics surveys' first seeds (2.5: 4). Why a
    /// peak that dominated a block is spared: a sidelobe is never the strongest direction
    /// of a block, since wherever its source sounds its main lobe stands higher, and
    /// where the source is silent there is no sidelobe; every real DoA the test took in
    /// the measurements below, without this rule, had dominated one or two blocks.
    ///
    /// Measured (3 seeds per scene, N = 3 or 4): of the
    /// DoAs it removes from the suite's scenes (first seeds) none is a source's;
    /// `three_talkers_rt06` (held out) MVDR 0.150 / 0.304 -> 0.060 / 0.065 m (a ghost
    /// gone), GCC-PHAT 0.157 -> 0.127 m; a pyroomacoustics survey of five talkers
    /// (RT60 0.3 s) GCC-PHAT 0.192 -> 0.116 m; `rows_ten_respeaker4` GCC-PHAT 0.142 ->
    /// 0.167 m (two of its DoAs lost at a 4-microphone array's broad sidelobes), the
    /// suite's other maps within 0.01 m; arrangement II unchanged. No slower: it runs
    /// only for peaks that dominated no block, one block's spectrum per stronger peak.
    pub sidelobe_ratio: f64,
    /// A peak is reported only when the array heard something coherent from its
    /// direction: its [`crate::Doa::significance`], the PHAT coherence of the whole
    /// recording steered towards it, must stand at least this many standard deviations
    /// above zero, its mean when every channel holds independent noise (`>= 0`; 0 turns
    /// the test off, as MBSS Locate has none). Default: 8.
    ///
    /// Why: every other threshold is relative to the spectrum's own strongest peak, and a
    /// spectrum always has one. A stop where nothing sounds (sensor noise only: a quiet
    /// room, a source that stopped) gave `N` DoAs at random directions, and a data set of
    /// such stops a map of 5-8 sources from nothing (`rows_ten`'s 20 stops with their
    /// audio replaced by independent noise, both methods, 3 seeds); it also fills the
    /// rows that the mapper's absence and vote rules read as heard. The statistic is
    /// scale-free: under independent noise it is about standard normal whatever the
    /// array, band or length (the largest value among 320 noise-only DoAs of that data
    /// set, chosen as spectrum peaks: 4.3), while a real source's grows with the square
    /// root of the recording (the weakest DoA of the suite's scenes, reflections included,
    /// 22; of the authors' recordings 26-47). 8 lies between with room on both sides;
    /// every scene of the suite, of `fixtures/heldout` and of arrangement II gives the
    /// same DoAs with and without it. A diffuse noise (fans, traffic) is partly coherent
    /// at low frequencies and passes: it is something the array hears, if not a source.
    pub min_significance: f64,
    /// A peak below [`SslConfig::min_relative`] is still reported when it stands at least
    /// this high and its source coherence with every stronger peak of the spectrum
    /// ([`crate::SpatialCovariance::source_coherence`]) is below
    /// [`SslConfig::max_incoherence`]: it carries a signal of its own, not a copy of
    /// theirs (`[0, 1]`; 0 turns it off, as MBSS Locate has no such rule). Default: 0.15.
    ///
    /// Why: a far talker beside a near one, or a quiet source among loud ones, stands in
    /// the pooled spectrum as low as the loud ones' reflections and sidelobes (0.15-0.3),
    /// where height cannot tell them apart; the signal can. A reflection or a sidelobe
    /// carries the same signal as the direct path it copies, an independent source does
    /// not. Why 0.15: half of `min_relative`; lower peaks are ripples of the background
    /// whose direction means little. The rule sits behind every other threshold (a peak it
    /// keeps must still pass [`SslConfig::sidelobe_ratio`] and
    /// [`SslConfig::min_significance`]), and it costs one pass over the frames, in rows
    /// that have such a peak only.
    ///
    /// Measured (3 renderings x 3 maps per scene, N = 3 or
    /// 4): ten sparse talkers, GCC-PHAT 0.139 -> 0.066 m with all ten found in every map,
    /// MVDR 0.209 -> 0.156 m (8-9 -> 9-10 found); ten talkers in rows 0.037 / 0.049 ->
    /// 0.030 / 0.040 m; two talkers with pauses at RT60 0.5 s, MVDR DoA score 0.78 ->
    /// 0.82; every one-talker scene unchanged. It costs some two-talker held-out maps
    /// 0.01-0.03 m (a far talker's low peak lies up to 8 degrees off on the near one's
    /// flank). The authors' recordings are unchanged: their rows are full at N = 4.
    pub incoherent_relative: f64,
    /// The source coherence below which [`SslConfig::incoherent_relative`] takes a low peak
    /// for an independent source (`[0, 1]`). Default: 0.55.
    ///
    /// Why 0.55: with the sensor noise taken out of the fit, the peaks of a second talker
    /// lie at 0.3-0.55 and the reflections and sidelobes of the scenes' talkers at
    /// 0.5-1 (regression suite and held-out scenes, both methods): of
    /// the peaks between 0.15 and 0.3 high, below 0.55 lie 36 of a source's and 9 others
    /// (MVDR), 26 and 15 (GCC-PHAT); below 0.5, 22 and 6, 15 and 7. At 0.5 the two
    /// talkers with pauses at RT60 0.5 s keep an MVDR DoA score of 0.79.
    pub max_incoherence: f64,
    /// In a row that [`SslConfig::num_peaks`] cut (more peaks passed every threshold than
    /// `N`: the stop hears more sources than a user asked for), a direction is reported
    /// beyond the `N` ([`crate::Located::extra`]) when the band's octaves from 700 Hz
    /// (0.7-1.5, 1.5-3 and 3 kHz to the band's top), each pooled on its own, made it the
    /// strongest direction of at least this many blocks in all ([`crate::Doa::dominant_blocks`]
    /// counted per octave, merged within 6 degrees) and no DoA of the row lies within
    /// [`SslConfig::min_sep_deg`] of it (`>= 0`; 0 turns it off, as MBSS Locate has none).
    /// Default: 4.
    ///
    /// Why: with more sources than `N`, the row holds the `N` strongest pooled peaks, and
    /// a source that is weaker over the whole band, far or quiet, is left out at every stop
    /// and never mapped, although it may be the strongest thing the array hears in one part
    /// of the spectrum for a while: sounds are sparse in frequency (a talker's voiced
    /// harmonics, another's fricatives), and each octave's block maximum is then that
    /// source's direct path. Why only in cut rows: a row that was not cut already holds
    /// every peak that passed the thresholds, and in the one- and two-talker scenes the
    /// octaves' own maxima are mostly reflections. Why octaves: a source's sparsity is at
    /// that scale, and each octave keeps enough bins (17 at 48 kHz in the lowest) for a
    /// block's maximum to mean something; below 700 Hz a robot-sized array resolves too
    /// little. Why 4 blocks: a reflection can be an octave's strongest direction for a
    /// block or two, as in the full band ([`SslConfig::dominance_blocks`]); over the
    /// suite's and held-out scenes, in every row, 3 votes added 13 real DoAs and 90 false
    /// ones, 4 added 6 and 45, 5 none and 20; in cut rows
    /// only, on the authors' recordings, every threshold from 3 to 8 maps all ten sources
    /// in every run, and 4 keeps 46 of 53 of 3's added DoAs. The pairwise
    /// methods' octave spectra cost about 4 ms per 3-s recording, in cut rows only; MUSIC
    /// and NormMUSIC sum their octaves' groups apart in the band's own pass
    /// ([`crate::SpectrumEstimator::estimate_blocks_parts`]), about 1 ms in every row.
    pub subband_votes: usize,
    /// Blocks whose energy (all channels, the band) lies more than this many dB below the
    /// loudest block of the preceding `decay_window_s` are left out of the pooling (`>= 0`;
    /// 0 pools every block, as MBSS Locate does). Default: 10.
    ///
    /// Why: after a sound stops, and in a talker's pauses, what the array hears is the
    /// room's decay, a diffuse field whose spectrum has peaks of its own (along the room's
    /// axes in a shoebox) that max pooling would keep; the decay falls 60 dB in RT60
    /// (6 dB per 50-ms block at 0.5 s), so it soon lies far below what preceded it, while
    /// a talker's own blocks, and the onset of a new one, do not.
    pub decay_gate_db: f64,
    /// The memory of the decay gate (s, `> 0`): about the reverberation time of the rooms
    /// a robot works in. Default: 0.5.
    pub decay_window_s: f64,
    /// Speed of sound (m/s). Default: 343.
    pub speed_of_sound: f64,
    /// MVDR diagonal loading, relative to the (unit) diagonal of the pair's coherence
    /// matrix (`> 0`). It bounds how sharp one coherent bin's peak can be. Default: 0.1.
    pub mvdr_loading: f64,
    /// MVDR: the pair covariance is also averaged over this many bins on each side
    /// (Default: 2), so that a block of a few frames still gives a well-conditioned matrix.
    pub mvdr_freq_smoothing: usize,
    /// The subspace methods: the dimension `K` of the signal subspace, at most one less than
    /// the number of microphones. TOPS, CSSM and WAVES take [`SslConfig::num_peaks`] when
    /// unset: their one spectrum of a whole recording holds every source heard in it
    /// (decision 0012; TOPS on arrangement II 0.537 with K = 4, 0.475 estimated as below).
    /// MUSIC and NormMUSIC, default `None`: estimated for each group of bins of each
    /// block: the eigenvectors whose eigenvalue lies within 10 dB of the largest, up to
    /// [`SslConfig::num_peaks`]. Why not N for all: a group (4 frames x 5 bins, about
    /// 50 ms x 230 Hz) often holds only one or two of the N sources, since speech and most
    /// sounds are sparse in time and frequency, and a subspace of N then takes noise for
    /// signal. Why not a small fixed K: sources that play at once in every bin (three
    /// noise sources) need all N. Measured (DoA score on the authors' ten-loudspeaker
    /// recordings, NormMUSIC, 3-D search): K = 1 0.51, 2 0.60, 3 0.56, 4 0.48, estimated
    /// 0.52; K = 2 loses one of three simultaneous noise sources in the analytic tests,
    /// the estimate finds all three.
    ///
    /// For MUSIC a signal eigenvalue must also stand 10 dB above the group's noise floor
    /// (the least eigenvalue its snapshots resolve), and a group with none adds the same
    /// to every direction: MUSIC sums its groups unnormalised, and a group of noise alone,
    /// whose eigenvalues lie close together, would otherwise take N for signal and spike
    /// at random directions as high as a source. Measured (first 4 DoAs within 5 degrees):
    /// arrangement II (poses' frame) 0.606 -> 0.662; over the suite's and
    /// `fixtures/heldout`'s 29 scenes 0.329 (K = 1: 0.324, but two noise sources playing
    /// at once in every bin are then found between them), pyroomacoustics' MUSIC 0.223.
    pub music_sources: Option<usize>,
    /// MUSIC and NormMUSIC: the covariance of a bin is averaged over this many neighbouring
    /// bins on each side, and the spectrum is evaluated at the centre of each such group
    /// of `2 F + 1` bins (`>= 0`). Default (`None`): 2 for NormMUSIC, 0 for MUSIC.
    ///
    /// Why 2 for NormMUSIC: an `M`-microphone covariance needs well over `M` snapshots
    /// before its smallest eigenvectors mean anything; a block of 4 frames times 5 bins
    /// gives 20 for 6 microphones. Across 5 bins of 47 Hz the steering phase of a 0.24-m
    /// array changes by up to 0.4 rad, which blurs but does not move a peak, and the
    /// evaluation costs a fifth as much.
    ///
    /// Why 0 for MUSIC: the blur that NormMUSIC's per-bin normalisation shrugs off is
    /// what MUSIC's unnormalised peaks are made of. Grouped bins without focusing spread a
    /// source's steering vector over more than one eigenvector, so the noise subspace
    /// keeps part of it and the true direction's peak is capped, while the bins that decide
    /// MUSIC's sum are those with the sharpest peaks. Measured on arrangement II (first 4
    /// DoAs within 5 degrees of the truth in the poses' frame, mean pooling, before the
    /// noise floor of [`SslConfig::music_sources`]): F = 2 0.381, 1 0.463, 0 0.606
    /// (pyroomacoustics' MUSIC, one bin at a time: 0.388); NormMUSIC 0.750 at 0 and at 2,
    /// three times slower at 0.
    pub music_freq_smoothing: Option<usize>,
    /// MUSIC and NormMUSIC: search the grid coarse-to-fine (every other azimuth at every
    /// other elevation, then the full grid around the `6 N` strongest local maxima of each
    /// block, the rest interpolated) instead of steering every direction. Default: false.
    /// Why: measured, the maps move both ways (arrangement II 0.145 -> 0.143 m, rows_ten
    /// 0.195 -> 0.164, but speech_two_rt05 0.017 -> 0.104): a weak source's peak that is
    /// not among a block's refined maxima is pooled at its interpolated height, below its
    /// own. It was 1.65x faster than the full search when that steered block by block
    /// (NormMUSIC 40 -> 24 ms per 3-s recording); since the full search evaluates all of a
    /// recording's blocks at once (and half of a symmetric grid) it is slower (NormMUSIC
    /// 25.8 against 18.3 ms, medians of 7 interleaved runs), and it is kept only to
    /// reproduce those measurements.
    pub music_coarse: bool,
    /// Leave out of each recording the channels that do not hear the room: silent ones
    /// (a dead or muted microphone) and ones that hold only noise of their own (a
    /// disconnected microphone's preamplifier), and localise it with the others
    /// ([`crate::channels`], where the tests and their measurements are;
    /// [`crate::Located::faulty_channels`] says which). A recording of working
    /// microphones is localised exactly as without the screen. Default: true (false
    /// localises every channel whatever it holds, as MBSS Locate does).
    pub screen_channels: bool,
}

impl Default for SslConfig {
    fn default() -> Self {
        Self {
            method: Method::default(),
            frame_len: None,
            hop: None,
            fmin_hz: 200.0,
            fmax_hz: 8000.0,
            az_step_deg: 1.0,
            elevation: None,
            block_frames: 4,
            pooling: Pooling::default(),
            pool_top: 1,
            placement_share: 0.25,
            deflate: None,
            deflate_max_residual: 0.65,
            num_peaks: 4,
            min_sep_deg: 10.0,
            min_relative: 0.3,
            min_prominence: 0.2,
            sidelobe_ratio: 2.5,
            min_significance: 8.0,
            incoherent_relative: 0.15,
            max_incoherence: 0.55,
            dominance_blocks: 2,
            subband_votes: 4,
            decay_gate_db: 10.0,
            decay_window_s: 0.5,
            speed_of_sound: 343.0,
            mvdr_loading: 0.1,
            mvdr_freq_smoothing: 2,
            music_sources: None,
            music_freq_smoothing: None,
            music_coarse: false,
            screen_channels: true,
        }
    }
}

/// The default STFT frame (s) of the pairwise and beamforming methods:
/// [`SslConfig::frame_len`].
pub const FRAME_S: f64 = 0.032;

/// The least length `>= n` whose only prime factors are 2, 3 and 5.
fn smooth_at_or_above(n: usize) -> usize {
    let smooth = |mut m: usize| {
        for p in [2, 3, 5] {
            while m.is_multiple_of(p) {
                m /= p;
            }
        }
        m == 1
    };
    (n.max(1)..)
        .find(|&m| smooth(m))
        .expect("a power of two lies beyond any n")
}

/// [`SslConfig::deflate`]'s default deflates for arrays whose far-field distance at the
/// band's top is under this (m): the range of the nearest sources a mapping robot passes
/// (arrangement II's nearest loudspeakers stand 0.6 m from the path, most of its sources 1-3
/// m away), beyond which a source is a plane wave to such an array.
pub const DEFLATE_FAR_FIELD_M: f64 = 1.0;

impl SslConfig {
    /// The half-width of MUSIC's and NormMUSIC's groups of bins
    /// ([`SslConfig::music_freq_smoothing`]): as set, or 0 for MUSIC and 2 for NormMUSIC.
    pub fn music_smoothing(&self) -> usize {
        self.music_freq_smoothing
            .unwrap_or(if self.method == Method::Music { 0 } else { 2 })
    }

    /// Whether rows are deflated ([`SslConfig::deflate`]) for `array` at `sample_rate`:
    /// as set, or, by default, when the array's far-field (Fraunhofer) distance at the
    /// band's top, `2 D² f / c` (`D` its aperture, `f` the band's upper edge capped at the
    /// Nyquist frequency), is under [`DEFLATE_FAR_FIELD_M`].
    pub fn deflates(&self, array: &crate::MicArray, sample_rate: u32) -> bool {
        self.deflate.unwrap_or_else(|| {
            let f = self.band_top_hz(sample_rate);
            let d = array.aperture();
            2.0 * d * d * f / self.speed_of_sound < DEFLATE_FAR_FIELD_M
        })
    }

    /// The frame length used at `sample_rate` ([`SslConfig::frame_len`]): as set; else,
    /// for the subspace methods (MUSIC, NormMUSIC, TOPS, CSSM, WAVES), the power of two at
    /// or above 20 ms (pyroomacoustics' 1024 points at 48 kHz); for the other methods,
    /// [`FRAME_S`] rounded up to a length whose only prime factors are 2, 3 and 5 (an FFT
    /// as fast as a power of two's).
    pub fn frame_len_at(&self, sample_rate: u32) -> usize {
        let fs = f64::from(sample_rate);
        self.frame_len.unwrap_or_else(|| match self.method {
            Method::Music | Method::NormMusic | Method::Tops | Method::Cssm | Method::Waves => {
                ((0.020 * fs).ceil() as usize).next_power_of_two()
            }
            // Less a hair, so that 32 ms of a round rate is not one sample more.
            _ => smooth_at_or_above((FRAME_S * fs - 1e-6).ceil() as usize),
        })
    }

    /// The analysis band's upper edge at `sample_rate` (Hz): [`SslConfig::fmax_hz`],
    /// capped at the Nyquist frequency.
    pub fn band_top_hz(&self, sample_rate: u32) -> f64 {
        self.fmax_hz.min(f64::from(sample_rate) / 2.0)
    }

    /// Checks every setting that does not depend on the sample rate.
    ///
    /// # Errors
    /// The first [`ConfigError`] found.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.check_ranges()?;
        crate::grid::check(self.az_step_deg, self.elevation)?;
        if self.pool_top == 0 {
            return Err(ConfigError::PoolTop(0));
        }
        if self.block_frames == 0 {
            return Err(ConfigError::BlockFrames(0));
        }
        if self.num_peaks == 0 {
            return Err(ConfigError::MaxPeaks(0));
        }
        if !(0.0..=180.0).contains(&self.min_sep_deg) {
            return Err(ConfigError::MinSeparation(self.min_sep_deg));
        }
        if !(0.0..=1.0).contains(&self.min_relative) {
            return Err(ConfigError::MinRelative(self.min_relative));
        }
        if !(0.0..=1.0).contains(&self.min_prominence) {
            return Err(ConfigError::MinProminence(self.min_prominence));
        }
        for (name, v) in [
            ("incoherent_relative", self.incoherent_relative),
            ("max_incoherence", self.max_incoherence),
            ("deflate_max_residual", self.deflate_max_residual),
            ("placement_share", self.placement_share),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(ConfigError::Fraction(name, v));
            }
        }
        if !(self.sidelobe_ratio.is_finite() && self.sidelobe_ratio >= 0.0) {
            return Err(ConfigError::SidelobeRatio(self.sidelobe_ratio));
        }
        if !(self.min_significance.is_finite() && self.min_significance >= 0.0) {
            return Err(ConfigError::MinSignificance(self.min_significance));
        }
        if !(self.decay_gate_db.is_finite() && self.decay_gate_db >= 0.0) {
            return Err(ConfigError::DecayGate(self.decay_gate_db));
        }
        if !(self.decay_window_s.is_finite() && self.decay_window_s > 0.0) {
            return Err(ConfigError::DecayWindow(self.decay_window_s));
        }
        if !(self.speed_of_sound.is_finite() && self.speed_of_sound > 0.0) {
            return Err(ConfigError::SpeedOfSound(self.speed_of_sound));
        }
        if !(self.mvdr_loading.is_finite() && self.mvdr_loading > 0.0) {
            return Err(ConfigError::Loading(self.mvdr_loading));
        }
        if self.music_sources == Some(0) {
            return Err(ConfigError::MusicSources(0));
        }
        Ok(())
    }
}

mod method;
mod ranges;

pub use method::Method;

#[cfg(test)]
mod tests;
