//! What a source sounds like: the array steered at it, and a coarse kind from stated
//! physical features.
//!
//! [`listen`] steers an MVDR beamformer at a direction of one recording and keeps what
//! the beam hears: its power spectrum (the mean over frames, per bin) and its envelope (the
//! power of each frame in the speech band, 300-3400 Hz). MVDR passes the steered direction
//! undistorted and takes as little as it can of every other, so other sources of the room
//! leak in less than through one microphone; the covariance is loaded with a tenth of its
//! mean power on the diagonal, so that a steering a few degrees off (a map position's
//! error, a source's unknown height) does not cancel the source itself.
//!
//! [`Signature::of`] joins what several stops heard of one source (each with its distance)
//! into features, each a physical quantity:
//!
//! - **level** (dB, arbitrary reference; the caller makes it relative to the loudest
//!   source): the beam's power brought to 1 m by spherical spreading (`+20 log10 r`), the
//!   mean over stops, and its spread over stops (`level_spread_db`: how steady across
//!   stops);
//! - **modulation** (`modulation`): the depth of the envelope's modulation between 3 and
//!   8 Hz, the syllable rate of speech (a sinusoidal modulation of depth `m` gives `m`);
//!   the median over stops;
//! - **fluctuation**: the envelope's standard deviation over its mean within a recording
//!   (how steady within a recording), the median over stops;
//! - **tonality**: the share of the spectrum's power in narrow lines, bins at least 6 dB
//!   above the median of the bins within 150 Hz (a hum's harmonics, a whine);
//! - **band**: the octave band that holds the most power, and the spectrum in
//!   third-octave bands (dB, 0 at the strongest).
//!
//! The kind follows from them: **tonal** when at least 60 % of the power is in lines,
//! else **speech** when the syllabic modulation is at least 0.4, else **broadband**
//! (steady: a fan, a vent, a stationary noise). Alone, a steady noise modulates its band
//! power by a few hundredths at these rates and speech by half or more; in a room of
//! several sources the beam lets some of the others through, which lifts a steady
//! source's modulation to 0.2-0.4 and dilutes a hum's lines (decision 0017 has the
//! measurement behind both thresholds). No learned model and nothing downloaded: a kind is
//! only as good as these features, and a noise with speech's long-term spectrum but no
//! syllables is broadband, as it physically is.

use nalgebra::{Cholesky, Complex, DMatrix, DVector, Dyn};
use serde::{Deserialize, Serialize};

use crate::array::MicArray;
use crate::audio::Audio;
use crate::covariance::leads;
use crate::error::Result;
use crate::grid::unit_vector;
use crate::stft::Stft;

/// How the beam listens.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ListenConfig {
    /// The analysis window (s), rounded up to a power of two in samples: 64 ms resolves
    /// lines 16 Hz apart, a 50-Hz mains hum's harmonics among them.
    pub window_s: f64,
    /// Frames per window (the hop is the window over this): 4, so that the envelope is
    /// sampled at 62 Hz, well above the 8-Hz top of the syllable band.
    pub overlap: usize,
    /// Lowest frequency heard (Hz).
    pub fmin_hz: f64,
    /// Highest frequency heard (Hz; at most Nyquist).
    pub fmax_hz: f64,
    /// Diagonal loading, a share of the covariance's mean power.
    pub loading: f64,
    /// Speed of sound (m/s).
    pub speed_of_sound: f64,
}

impl Default for ListenConfig {
    fn default() -> Self {
        Self {
            window_s: 0.064,
            overlap: 4,
            fmin_hz: 80.0,
            fmax_hz: 8000.0,
            loading: 0.1,
            speed_of_sound: 343.0,
        }
    }
}

/// What a beam steered at a source heard in one recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Heard {
    /// The first bin's frequency (Hz) and the bins' spacing (Hz).
    pub f0_hz: f64,
    /// Bin spacing (Hz).
    pub df_hz: f64,
    /// The beam's mean power per bin.
    pub spectrum: Vec<f64>,
    /// The beam's power in 300-3400 Hz, per frame.
    pub envelope: Vec<f64>,
    /// Frames per second of the envelope.
    pub frame_rate: f64,
}

/// The speech band whose power is the envelope (Hz).
const ENVELOPE_BAND_HZ: (f64, f64) = (300.0, 3400.0);
/// The syllable rates of speech (Hz).
const SYLLABLE_HZ: (f64, f64) = (3.0, 8.0);
/// How far a line must stand above its neighbourhood's median (6 dB, a power ratio).
const LINE_RATIO: f64 = 4.0;
/// Half-width of a line's neighbourhood (Hz).
const LINE_NEIGHBOURHOOD_HZ: f64 = 150.0;
/// The kinds' thresholds (decision 0017).
const TONAL_MIN: f64 = 0.6;
/// Syllabic modulation depth from which a source is speech-like.
const SPEECH_MIN: f64 = 0.4;
/// The nearest distance the level is brought back from (m): nearer, the beam is not in a
/// source's far field and spreading overstates it.
const LEVEL_NEAR_M: f64 = 0.3;

/// Steers an MVDR beam at `azimuth_deg`, `elevation_deg` (array frame) in `audio` and
/// keeps what it hears (see the module docs): [`Listener::new`] then
/// [`Listener::steer`]. To steer at several directions of one recording, make the
/// [`Listener`] once.
///
/// # Errors
/// Audio shorter than one window, or channels that are not the array's.
pub fn listen(
    audio: &Audio,
    array: &MicArray,
    azimuth_deg: f64,
    elevation_deg: f64,
    config: &ListenConfig,
) -> Result<Heard> {
    Ok(Listener::new(audio, array, config)?.steer(azimuth_deg, elevation_deg))
}

/// One recording made ready for beams ([`Listener::steer`]): its spectra and, per bin,
/// the loaded covariance's Cholesky factor, none of which depends on where the beam
/// points.
pub struct Listener {
    bins: Vec<Bin>,
    /// Each microphone's position (m).
    positions: Vec<[f64; 3]>,
    frames: usize,
    f0_hz: f64,
    df_hz: f64,
    frame_rate: f64,
    speed_of_sound: f64,
}

/// One bin of a [`Listener`]: its frequency (Hz), and the frames' microphone spectra
/// (channels x frames) with the loaded covariance's Cholesky factor; `None` for a bin with
/// no power.
struct Bin {
    f_hz: f64,
    frames: Option<(DMatrix<Complex<f64>>, Factor)>,
}

/// A bin's loaded covariance, factored.
type Factor = Cholesky<Complex<f64>, Dyn>;

impl Listener {
    /// The recording `audio` of `array`, analysed as `config` says.
    ///
    /// # Errors
    /// Audio shorter than one window, or channels that are not the array's.
    pub fn new(audio: &Audio, array: &MicArray, config: &ListenConfig) -> Result<Self> {
        let fs = f64::from(audio.sample_rate());
        if audio.num_channels() != array.len() {
            return Err(crate::Error::ChannelMismatch {
                got: audio.num_channels(),
                expected: array.len(),
            });
        }
        let n = ((config.window_s * fs).ceil() as usize)
            .next_power_of_two()
            .max(16);
        let stft = Stft::new(n, (n / config.overlap.max(1)).max(1))?;
        let df = fs / n as f64;
        let k0 = ((config.fmin_hz / df).ceil() as usize).max(1);
        let k1 = ((config.fmax_hz.min(0.5 * fs) / df).floor() as usize).min(n / 2);
        let spec = stft.analyze(audio, k0..k1 + 1)?;
        let (m, t) = (spec.num_channels(), spec.num_frames());
        let bins = (k0..=k1)
            .enumerate()
            .map(|(b, k)| {
                let f = k as f64 * df;
                let mut x = DMatrix::<Complex<f64>>::zeros(m, t);
                for frame in 0..t {
                    for c in 0..m {
                        let v = spec.frame(frame, c)[b];
                        x[(c, frame)] = Complex::new(f64::from(v.re), f64::from(v.im));
                    }
                }
                let mut r = (&x * x.adjoint()).unscale(t as f64);
                let mean_power = (0..m).map(|c| r[(c, c)].re).sum::<f64>() / m as f64;
                if !(mean_power > 0.0 && mean_power.is_finite()) {
                    return Bin {
                        f_hz: f,
                        frames: None,
                    };
                }
                for c in 0..m {
                    r[(c, c)] += Complex::new(config.loading * mean_power, 0.0);
                }
                Bin {
                    f_hz: f,
                    frames: r.cholesky().map(|chol| (x, chol)),
                }
            })
            .collect();
        Ok(Self {
            bins,
            positions: array.positions().to_vec(),
            frames: t,
            f0_hz: k0 as f64 * df,
            df_hz: df,
            frame_rate: fs / stft.hop() as f64,
            speed_of_sound: config.speed_of_sound,
        })
    }

    /// What an MVDR beam steered at `azimuth_deg`, `elevation_deg` (array frame) hears.
    pub fn steer(&self, azimuth_deg: f64, elevation_deg: f64) -> Heard {
        let u = unit_vector(azimuth_deg, elevation_deg);
        let ahead = leads(&self.positions, u, self.speed_of_sound);
        let t = self.frames;
        let mut spectrum = vec![0.0; self.bins.len()];
        let mut envelope = vec![0.0; t];
        for (b, bin) in self.bins.iter().enumerate() {
            let (f, Some((x, chol))) = (&bin.f_hz, &bin.frames) else {
                continue;
            };
            let d = DVector::from_iterator(
                ahead.len(),
                ahead
                    .iter()
                    .map(|&tau| Complex::from_polar(1.0, std::f64::consts::TAU * f * tau)),
            );
            let rd = chol.solve(&d);
            let denom = d.dotc(&rd);
            if denom.norm() <= 0.0 {
                continue;
            }
            let w = rd / denom;
            let y = w.adjoint() * x;
            let in_envelope = (ENVELOPE_BAND_HZ.0..=ENVELOPE_BAND_HZ.1).contains(f);
            for (frame, v) in y.iter().enumerate() {
                let p = v.norm_sqr();
                spectrum[b] += p / t as f64;
                if in_envelope {
                    envelope[frame] += p;
                }
            }
        }
        Heard {
            f0_hz: self.f0_hz,
            df_hz: self.df_hz,
            spectrum,
            envelope,
            frame_rate: self.frame_rate,
        }
    }
}

/// A source's coarse kind (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Syllabic modulation of 3-8 Hz.
    Speech,
    /// Most of its power in narrow lines.
    Tonal,
    /// Neither: a steady broadband sound.
    Broadband,
}

impl Kind {
    /// Its name as the JSON writes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Speech => "speech",
            Self::Tonal => "tonal",
            Self::Broadband => "broadband",
        }
    }
}

/// A source's signature (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Signature {
    /// The coarse kind.
    pub kind: Kind,
    /// Level at 1 m (dB, arbitrary reference; relative to the loudest source when a map
    /// sets it so).
    pub level_db: f64,
    /// The level's standard deviation over the stops (dB): how steady across stops.
    pub level_spread_db: f64,
    /// Depth of the envelope's modulation at 3-8 Hz.
    pub modulation: f64,
    /// The envelope's standard deviation over its mean within a recording.
    pub fluctuation: f64,
    /// How deep the envelope's gaps go (dB): its median over its 10th percentile within a
    /// recording, the median over stops (speech's pauses; not used for the kind, which it
    /// did not separate better than the modulation).
    pub gap_db: f64,
    /// Share of the power in narrow lines.
    pub tonality: f64,
    /// The octave band that holds the most power (Hz, its edges).
    pub band_hz: [f64; 2],
    /// The spectrum in third-octave bands: centre (Hz) and level (dB, 0 at the strongest).
    pub spectrum_db: Vec<[f64; 2]>,
    /// Recordings it was heard in.
    pub stops: usize,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The depth of `envelope`'s modulation between `lo` and `hi` Hz at `rate` frames per
/// second: `2 sqrt(sum |E_k|^2) / (N mean)` over the DFT bins in the band, which is `m`
/// for `mean (1 + m cos(2 pi f t))` with `f` in the band.
pub fn modulation_depth(envelope: &[f64], rate: f64, (lo, hi): (f64, f64)) -> f64 {
    let n = envelope.len();
    let mean = envelope.iter().sum::<f64>() / n.max(1) as f64;
    if n < 4 || mean <= 0.0 || !mean.is_finite() {
        return 0.0;
    }
    let mut power = 0.0;
    for k in 1..n / 2 {
        let f = k as f64 * rate / n as f64;
        if f < lo || f > hi {
            continue;
        }
        let (mut re, mut im) = (0.0, 0.0);
        for (t, e) in envelope.iter().enumerate() {
            let ph = std::f64::consts::TAU * (k * t) as f64 / n as f64;
            re += (e - mean) * ph.cos();
            im -= (e - mean) * ph.sin();
        }
        power += re * re + im * im;
    }
    2.0 * power.sqrt() / (n as f64 * mean)
}

/// The share of `spectrum`'s power in narrow lines (see the module docs).
pub fn tonality(spectrum: &[f64], df_hz: f64) -> f64 {
    let total: f64 = spectrum.iter().sum();
    if total <= 0.0 || !total.is_finite() {
        return 0.0;
    }
    let half = ((LINE_NEIGHBOURHOOD_HZ / df_hz).round() as usize).max(2);
    let mut lines = 0.0;
    for (k, &p) in spectrum.iter().enumerate() {
        let around: Vec<f64> =
            spectrum[k.saturating_sub(half)..(k + half + 1).min(spectrum.len())].to_vec();
        if p >= LINE_RATIO * median(around) {
            lines += p;
        }
    }
    lines / total
}

impl Signature {
    /// The signature of one source from what the beam heard of it at several stops, each
    /// with the stop's distance to it (m); `None` when nothing was heard.
    pub fn of(heard: &[(Heard, f64)]) -> Option<Self> {
        let (first, _) = heard.first()?;
        let (f0, df) = (first.f0_hz, first.df_hz);
        let nb = first.spectrum.len();
        let mut shape = vec![0.0; nb];
        let mut levels = Vec::new();
        let (mut mods, mut flucts, mut gaps) = (Vec::new(), Vec::new(), Vec::new());
        for (h, r) in heard {
            let total: f64 = h.spectrum.iter().sum();
            if h.spectrum.len() != nb || total <= 0.0 || !total.is_finite() {
                continue;
            }
            for (s, p) in shape.iter_mut().zip(&h.spectrum) {
                *s += p / total;
            }
            levels.push(10.0 * total.log10() + 20.0 * r.max(LEVEL_NEAR_M).log10());
            mods.push(modulation_depth(&h.envelope, h.frame_rate, SYLLABLE_HZ));
            let n = h.envelope.len().max(1) as f64;
            let mean = h.envelope.iter().sum::<f64>() / n;
            let var = h.envelope.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n;
            flucts.push(if mean > 0.0 { var.sqrt() / mean } else { 0.0 });
            let mut e = h.envelope.clone();
            e.sort_by(f64::total_cmp);
            if let (Some(&lo), Some(&mid)) = (e.get(e.len() / 10), e.get(e.len() / 2))
                && lo > 0.0
            {
                gaps.push(10.0 * (mid / lo).log10());
            }
        }
        if levels.is_empty() {
            return None;
        }
        let level = levels.iter().sum::<f64>() / levels.len() as f64;
        let spread =
            (levels.iter().map(|l| (l - level).powi(2)).sum::<f64>() / levels.len() as f64).sqrt();
        let (modulation, fluctuation, gap_db) = (median(mods), median(flucts), median(gaps));
        let tonality = tonality(&shape, df);
        let kind = if tonality >= TONAL_MIN {
            Kind::Tonal
        } else if modulation >= SPEECH_MIN {
            Kind::Speech
        } else {
            Kind::Broadband
        };
        let band_power = |lo: f64, hi: f64| -> f64 {
            shape
                .iter()
                .enumerate()
                .filter(|(k, _)| (lo..hi).contains(&(f0 + *k as f64 * df)))
                .map(|(_, p)| p)
                .sum()
        };
        // Octaves centred on 125 Hz * 2^k (edges at centre / sqrt 2 and * sqrt 2).
        let top = f0 + nb as f64 * df;
        let octaves: Vec<[f64; 2]> = (0..8)
            .map(|k| 125.0 * 2f64.powi(k))
            .map(|c| [c / std::f64::consts::SQRT_2, c * std::f64::consts::SQRT_2])
            .filter(|b| b[0] < top)
            .collect();
        let band_hz = octaves
            .iter()
            .copied()
            .max_by(|a, b| band_power(a[0], a[1]).total_cmp(&band_power(b[0], b[1])))
            .unwrap_or([0.0, 0.0]);
        let thirds: Vec<(f64, f64)> = (0..24)
            .map(|k| 100.0 * 2f64.powf(f64::from(k) / 3.0))
            .filter(|&c| c * 2f64.powf(1.0 / 6.0) <= top)
            .map(|c| {
                (
                    c,
                    band_power(c / 2f64.powf(1.0 / 6.0), c * 2f64.powf(1.0 / 6.0)),
                )
            })
            .collect();
        let strongest = thirds.iter().map(|t| t.1).fold(0.0, f64::max);
        let spectrum_db = thirds
            .iter()
            .map(|&(c, p)| {
                let db = if p > 0.0 && strongest > 0.0 {
                    (10.0 * (p / strongest).log10()).max(-60.0)
                } else {
                    -60.0
                };
                [c.round(), (db * 10.0).round() / 10.0]
            })
            .collect();
        Some(Self {
            kind,
            level_db: level,
            level_spread_db: spread,
            modulation,
            fluctuation,
            gap_db,
            tonality,
            band_hz,
            spectrum_db,
            stops: levels.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane wave of `signal` from `azimuth_deg` on the paper's array, with a little
    /// independent noise on each microphone, at `fs`.
    fn recording(signal: &[f64], azimuth_deg: f64, fs: u32) -> Audio {
        let array = MicArray::preset("iasm6").unwrap();
        let az = azimuth_deg.to_radians();
        let mut seed = 12345u64;
        let mut noise = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64 - 1.0) * 1e-3
        };
        let channels = array
            .positions()
            .iter()
            .map(|p| {
                // Earlier by (p . u) / c: sample the signal that much ahead (linear
                // interpolation; the delays are fractions of a millisecond).
                let ahead = (p[0] * az.cos() + p[1] * az.sin()) / 343.0 * f64::from(fs);
                (0..signal.len())
                    .map(|i| {
                        let t = (i as f64 + ahead).clamp(0.0, (signal.len() - 2) as f64);
                        let (j, a) = (t.floor() as usize, t.fract());
                        ((1.0 - a) * signal[j] + a * signal[j + 1] + noise()) as f32
                    })
                    .collect()
            })
            .collect();
        Audio::new(fs, channels).unwrap()
    }

    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                // A sum of uniforms: near-Gaussian white noise.
                (0..4)
                    .map(|_| {
                        s = s
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        (s >> 33) as f64 / (1u64 << 31) as f64 - 1.0
                    })
                    .sum::<f64>()
            })
            .collect()
    }

    fn signature(signal: &[f64], fs: u32) -> Signature {
        let array = MicArray::preset("iasm6").unwrap();
        let heard: Vec<(Heard, f64)> = [30.0, -100.0]
            .iter()
            .map(|&az| {
                let a = recording(signal, az, fs);
                (
                    listen(&a, &array, az, 0.0, &ListenConfig::default()).unwrap(),
                    2.0,
                )
            })
            .collect();
        Signature::of(&heard).unwrap()
    }

    #[test]
    fn a_sinusoidal_modulation_has_its_depth() {
        // 62.5 frames a second for 2 s, modulated 40 % at 5 Hz: depth 0.4 in 3-8 Hz and
        // none in 10-20 Hz.
        let rate = 62.5;
        let e: Vec<f64> = (0..125)
            .map(|t| 3.0 * (1.0 + 0.4 * (std::f64::consts::TAU * 5.0 * t as f64 / rate).cos()))
            .collect();
        assert!((modulation_depth(&e, rate, (3.0, 8.0)) - 0.4).abs() < 0.01);
        assert!(modulation_depth(&e, rate, (10.0, 20.0)) < 0.01);
    }

    #[test]
    fn a_hum_is_tonal_a_steady_noise_broadband_and_a_syllabic_one_speech() {
        let fs = 16_000;
        let n = fs as usize;
        // A 120-Hz hum: harmonics falling as 1/h.
        let hum: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / f64::from(fs);
                (1..40)
                    .map(|h| {
                        (std::f64::consts::TAU * 120.0 * f64::from(h) * t).sin() / f64::from(h)
                    })
                    .sum()
            })
            .collect();
        let steady = noise(n, 1);
        // Noise switched on and off four times a second: syllables.
        let syllables: Vec<f64> = noise(n, 2)
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let t = i as f64 / f64::from(fs);
                v * (0.5 + 0.5 * (std::f64::consts::TAU * 4.0 * t).sin()).powi(2)
            })
            .collect();
        let (h, s, y) = (
            signature(&hum, fs),
            signature(&steady, fs),
            signature(&syllables, fs),
        );
        assert_eq!(h.kind, Kind::Tonal, "{h:?}");
        assert_eq!(s.kind, Kind::Broadband, "{s:?}");
        assert_eq!(y.kind, Kind::Speech, "{y:?}");
        assert!(h.tonality > 0.8 && s.tonality < 0.1, "{h:?} {s:?}");
        assert!(s.modulation < 0.1 && y.modulation > 0.5, "{s:?} {y:?}");
        // The hum's strongest octave holds its fundamental: 125 Hz.
        assert_eq!(h.band_hz.map(f64::round), [88.0, 177.0]);
        // The same stops at the same distance: the level is the same at each.
        assert!(h.level_spread_db < 0.5, "{h:?}");
    }

    #[test]
    fn the_beam_passes_its_direction_and_rejects_another() {
        // A 1-kHz band of noise from 60 degrees: steered there it is 10 dB or more above
        // the beam steered at -120 degrees.
        let fs = 16_000;
        let a = recording(&noise(fs as usize, 3), 60.0, fs);
        let array = MicArray::preset("iasm6").unwrap();
        let power = |az: f64| -> f64 {
            let h = listen(&a, &array, az, 0.0, &ListenConfig::default()).unwrap();
            h.spectrum
                .iter()
                .enumerate()
                .filter(|(k, _)| (800.0..4000.0).contains(&(h.f0_hz + *k as f64 * h.df_hz)))
                .map(|(_, p)| p)
                .sum()
        };
        let gain_db = 10.0 * (power(60.0) / power(-120.0)).log10();
        assert!(gain_db > 10.0, "{gain_db} dB");
    }
}
