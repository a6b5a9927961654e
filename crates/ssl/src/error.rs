//! Error types: [`ConfigError`] for settings rejected at construction, [`ArrayError`] for
//! array descriptions, and [`Error`] for everything that can go wrong at run time.

use std::path::PathBuf;

/// A setting that [`crate::Localizer::new`] (or one of the config constructors) refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// A setting outside the range in which it means something for an array and a room:
    /// refused when the settings are read, before any memory or time is spent on it.
    #[error("{name} = {value} is out of range: accepted {range}")]
    OutOfRange {
        /// The setting.
        name: &'static str,
        /// Its value, as given.
        value: String,
        /// What is accepted, and why.
        range: &'static str,
    },
    /// The STFT frame is too short to hold a useful spectrum.
    #[error("frame_len = {0} samples is too short (at least 16)")]
    FrameLen(usize),
    /// The hop is zero or longer than the frame.
    #[error("hop = {hop} must be in 1..={frame_len} samples (the frame)")]
    Hop {
        /// The hop that was asked for.
        hop: usize,
        /// The frame length it must not exceed.
        frame_len: usize,
    },
    /// The frequency band is empty or outside `[0, fs / 2]`.
    #[error(
        "frequency band fmin_hz = {fmin} to fmax_hz = {fmax} Hz is empty or outside [0, {nyquist}] Hz"
    )]
    Band {
        /// Lower edge (Hz).
        fmin: f64,
        /// Upper edge (Hz).
        fmax: f64,
        /// Half the sample rate (Hz).
        nyquist: f64,
    },
    /// The band holds no STFT bin at this frame length and sample rate.
    #[error(
        "frequency band fmin_hz = {fmin} to fmax_hz = {fmax} Hz holds no STFT bin (bin spacing {spacing} Hz)"
    )]
    BandHasNoBin {
        /// Lower edge (Hz).
        fmin: f64,
        /// Upper edge (Hz).
        fmax: f64,
        /// Width of one bin (Hz).
        spacing: f64,
    },
    /// The azimuth step does not divide the circle into at least 4 cells.
    #[error("az_step_deg = {0} must be in (0, 90] degrees")]
    AzimuthStep(f64),
    /// The elevation search range is malformed.
    #[error(
        "elevation = {{ min_deg = {min}, max_deg = {max}, step_deg = {step} }} is invalid (need -90 <= min_deg <= max_deg <= 90, step_deg > 0)"
    )]
    Elevation {
        /// Lowest elevation (degrees).
        min: f64,
        /// Highest elevation (degrees).
        max: f64,
        /// Step (degrees).
        step: f64,
    },
    /// A block must hold at least one frame.
    #[error("block_frames = {0}: must be at least 1")]
    BlockFrames(usize),
    /// Max pooling must average at least the one best block.
    #[error("pool_top = {0}: must be at least 1")]
    PoolTop(usize),
    /// Peak separation outside `[0, 180]` degrees.
    #[error("min_sep_deg = {0} must be in [0, 180] degrees")]
    MinSeparation(f64),
    /// A decay gate that is negative or not finite.
    #[error("decay_gate_db must be finite and >= 0, got {0}")]
    DecayGate(f64),
    /// A decay window that is not positive.
    #[error("decay_window_s must be positive, got {0}")]
    DecayWindow(f64),
    /// A relative peak threshold outside `[0, 1]`.
    #[error("min_relative must be in [0, 1], got {0}")]
    MinRelative(f64),
    /// A prominence threshold outside `[0, 1]`.
    #[error("min_prominence must be in [0, 1], got {0}")]
    MinProminence(f64),
    /// A setting that is a fraction, outside `[0, 1]`.
    #[error("{0} must be in [0, 1], got {1}")]
    Fraction(&'static str, f64),
    /// A sidelobe ratio negative or not finite.
    #[error("sidelobe_ratio must be finite and >= 0, got {0}")]
    SidelobeRatio(f64),
    /// A significance threshold negative or not finite.
    #[error("min_significance must be finite and >= 0, got {0}")]
    MinSignificance(f64),
    /// Asked for no peaks at all.
    #[error("num_peaks must be at least 1, got {0}")]
    MaxPeaks(usize),
    /// Speed of sound not positive and finite.
    #[error("speed_of_sound = {0} m/s must be positive and finite")]
    SpeedOfSound(f64),
    /// A MUSIC signal subspace of no dimension.
    #[error("music_sources must be at least 1, got {0}")]
    MusicSources(usize),
    /// MVDR diagonal loading not positive and finite.
    #[error("mvdr_loading = {0} must be positive and finite")]
    Loading(f64),
    /// A sample rate of zero.
    #[error("sample rate must be positive")]
    SampleRate,
    /// A method name that is not known.
    #[error(
        "unknown method {0:?}; expected one of: gcc-phat, mvdr, srp-phat, music, normmusic, tops, cssm, waves"
    )]
    UnknownMethod(String),
    /// A pooling name that is not known.
    #[error("unknown pooling {0:?}; expected one of: auto, max, mean")]
    UnknownPooling(String),
}

/// A microphone array description that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ArrayError {
    /// Fewer than two microphones: no pair, no delay, no direction.
    #[error("an array needs at least two microphones, got {0}")]
    TooFewMics(usize),
    /// A coordinate is NaN or infinite.
    #[error("microphone {index} has a non-finite coordinate")]
    NonFinite {
        /// Zero-based microphone index.
        index: usize,
    },
    /// Two microphones share one position (within 0.1 mm).
    #[error("microphones {a} and {b} are at the same position")]
    Duplicate {
        /// Zero-based index of the first.
        a: usize,
        /// Zero-based index of the second.
        b: usize,
    },
    /// The array is wider than [`crate::array::MAX_APERTURE_M`].
    #[error(
        "the microphones span {aperture_m:.3} m: positions are in metres, and the arrays a robot carries are centimetres to decimetres across (positions in millimetres or centimetres read as metres make a 6.4-cm array 64 or 6.4 m wide); DoAs from one plane wave per source need an array of at most {max} m",
        max = crate::array::MAX_APERTURE_M
    )]
    TooLarge {
        /// The largest distance between two microphones (m).
        aperture_m: f64,
    },
    /// Seen from above, the microphones span too little of the aperture to hear azimuth
    /// (a vertical line or stack).
    #[error(
        "the microphones span {horizontal_m:.3} m seen from above, under a tenth of the array's {aperture_m:.3} m aperture: a vertical array hears no azimuth (positions are x, y, z with z up)"
    )]
    NoAzimuth {
        /// The microphones' largest horizontal distance (m).
        horizontal_m: f64,
        /// The aperture (m).
        aperture_m: f64,
    },
    /// A preset name that is not built in.
    #[error("unknown array {name:?}: not a preset ({list}) nor an existing file", list = presets.join(", "))]
    UnknownPreset {
        /// The name given.
        name: String,
        /// The presets there are.
        presets: &'static [&'static str],
    },
    /// The array file could not be read.
    #[error("failed to read array file {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// The array file is not valid TOML/JSON or lacks `positions`.
    #[error("array file {path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file was read but describes a bad array.
    #[error("array file {path}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong with the geometry (part of this message, so not a `source()`).
        reason: Box<ArrayError>,
    },
}

/// Everything that can fail while reading audio or localising.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A setting was refused.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The array description was refused.
    #[error(transparent)]
    Array(#[from] ArrayError),
    /// The file could not be opened or is not a WAV file hound understands.
    #[error("{path}: {message}")]
    Wav {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file holds fewer samples than its header declares.
    #[error("{path}: truncated: the header declares {declared} samples but the file holds {read}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Samples the header announces (all channels).
        declared: u64,
        /// Samples actually present.
        read: u64,
    },
    /// A WAV longer than one localisation takes ([`crate::audio::MAX_WAV_SAMPLES`]).
    #[error(
        "{path}: {seconds:.0} s of {channels} channels at {rate} Hz is longer than one \
         localisation takes ({limit_s:.0} s at this rate and channel count); a stop's \
         recording is seconds long: cut it to the stop (e.g. `sox in.wav out.wav trim 0 10`)"
    )]
    TooLong {
        /// The file.
        path: PathBuf,
        /// Its duration (s).
        seconds: f64,
        /// Its channels.
        channels: u16,
        /// Its sample rate (Hz).
        rate: u32,
        /// The longest accepted at its rate and channel count (s).
        limit_s: f64,
    },
    /// A WAV with no samples.
    #[error("{path}: the file holds no audio samples")]
    EmptyWav {
        /// The file.
        path: PathBuf,
    },
    /// In-memory audio whose channels are empty or of different lengths.
    #[error("audio channels must be non-empty and of equal length")]
    RaggedAudio,
    /// A sample that is NaN or infinite (a float WAV written from a failed computation):
    /// its every frame's spectrum would be NaN, and no direction could be found.
    #[error("channel {channel} holds a non-finite sample ({value}) at sample {sample}")]
    NonFiniteSample {
        /// The channel (from 1).
        channel: usize,
        /// The sample's index in the channel (from 0).
        sample: usize,
        /// The sample.
        value: f32,
    },
    /// [`Error::NonFiniteSample`] in a file.
    #[error("{path}: channel {channel} holds a non-finite sample ({value}) at sample {sample}")]
    NonFiniteWav {
        /// The file.
        path: PathBuf,
        /// The channel (from 1).
        channel: usize,
        /// The sample's index in the channel (from 0).
        sample: usize,
        /// The sample.
        value: f32,
    },
    /// The audio's channel count differs from the array's microphone count.
    #[error("audio has {got} channels but the array has {expected} microphones")]
    ChannelMismatch {
        /// Microphones in the array.
        expected: usize,
        /// Channels in the audio.
        got: usize,
    },
    /// An STFT given as frames ([`crate::Spectrogram::from_frames`]) whose values do not
    /// fill its shape, or are not finite.
    #[error(
        "an STFT of {frames} frames x {channels} channels x {bins} bins needs that many finite values, got {got} values or a non-finite one"
    )]
    SpectrogramShape {
        /// Frames.
        frames: usize,
        /// Channels.
        channels: usize,
        /// Bins.
        bins: usize,
        /// Values given.
        got: usize,
    },
    /// An STFT given as frames that does not hold the localizer's band.
    #[error(
        "the STFT holds bins {}..{} over {frames} frames; the band needs bins {}..{} (fmin_hz and fmax_hz at frame_len, the STFT's FFT length) and at least one frame",
        have.0, have.1, band.0, band.1
    )]
    BandNotInSpectrogram {
        /// The band's bins, `[start, end)`.
        band: (usize, usize),
        /// The STFT's bins, `[start, end)`.
        have: (usize, usize),
        /// The STFT's frames.
        frames: usize,
    },
    /// A channel asked for ([`crate::Audio::select`]) that the audio does not have.
    #[error("channel {channel} asked for, but the audio has {channels} channels")]
    NoSuchChannel {
        /// The channel asked for (from 1).
        channel: usize,
        /// Channels in the audio.
        channels: usize,
    },
    /// The audio is shorter than one STFT frame.
    #[error("audio of {samples} samples per channel is shorter than one {frame_len}-sample frame")]
    TooShort {
        /// Samples per channel.
        samples: usize,
        /// Frame length.
        frame_len: usize,
    },
    /// A recording of the robot's noise too short to estimate it from
    /// ([`crate::noise::MIN_NOISE_FRAMES`]).
    #[error(
        "the noise recording holds {frames} STFT frames, fewer than {min}: record the robot alone for a few seconds"
    )]
    NoiseTooShort {
        /// Its frames.
        frames: usize,
        /// The fewest taken.
        min: usize,
    },
    /// The audio's sample rate is not the one the localizer was built for.
    #[error("audio sample rate {got} Hz differs from the localizer's {expected} Hz")]
    SampleRateMismatch {
        /// The localizer's rate.
        expected: u32,
        /// The audio's rate.
        got: u32,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
