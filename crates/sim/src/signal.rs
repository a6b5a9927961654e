//! Seeded source signals.

use rand::{Rng, rngs::StdRng};
use rand_distr::StandardNormal;
use rustfft::{FftPlanner, num_complex::Complex64};

/// A source signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Signal {
    /// White Gaussian noise.
    Noise,
    /// Pink noise: amplitude falling as `1 / sqrt(f)` (-3 dB per octave) above 20 Hz.
    PinkNoise,
    /// Noise with the long-term spectrum of speech: rising to 100 Hz, flat to 500 Hz, then
    /// -6 dB per octave.
    SpeechShaped,
    /// A voiced, speech-like harmonic series: fundamental `f0` (Hz), harmonics up to
    /// 8 kHz (and below Nyquist), random phases, amplitude falling as `1/h` (-6 dB/octave,
    /// the glottal source's tilt). The pitch is steady (no intonation or jitter), so in a
    /// room it behaves as a hum more than a voice: each harmonic's reflections stay coherent
    /// with its direct path however late they arrive (see `ssl::covariance`).
    Harmonic(f64),
}

/// A generated signal as a scene file names it (`signal = "..."`); a voiced source takes
/// its fundamental from the scene's `f0`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SignalKind {
    /// [`Signal::Noise`].
    WhiteNoise,
    /// [`Signal::PinkNoise`].
    PinkNoise,
    /// [`Signal::SpeechShaped`] (the default: robots mostly hear people).
    #[default]
    SpeechShaped,
    /// [`Signal::Harmonic`].
    Voiced,
}

impl SignalKind {
    /// The signal, with fundamental `f0` (Hz) for a voiced one.
    pub fn signal(self, f0: f64) -> Signal {
        match self {
            SignalKind::WhiteNoise => Signal::Noise,
            SignalKind::PinkNoise => Signal::PinkNoise,
            SignalKind::SpeechShaped => Signal::SpeechShaped,
            SignalKind::Voiced => Signal::Harmonic(f0),
        }
    }
}

/// `n` samples of `signal` at `fs` Hz, drawn from `rng`, scaled to unit mean power.
pub fn generate(signal: Signal, n: usize, fs: u32, rng: &mut StdRng) -> Vec<f64> {
    let mut x: Vec<f64> = match signal {
        Signal::Noise => (0..n).map(|_| rng.sample(StandardNormal)).collect(),
        // The shaped noises are scaled by their own division (not `scale_to_unit_power`'s
        // reciprocal) so that scenes render the same bits as before the two were joined.
        Signal::PinkNoise => return shaped_noise(n, fs, rng, |f| 1.0 / f.max(20.0).sqrt()),
        Signal::SpeechShaped => {
            return shaped_noise(n, fs, rng, |f| {
                if f < 100.0 {
                    f / 100.0
                } else {
                    (500.0 / f.max(500.0)).max(0.0)
                }
            });
        }
        Signal::Harmonic(f0) => {
            let top = 8000.0f64.min(0.45 * f64::from(fs));
            let harmonics: Vec<(f64, f64, f64)> = (1..)
                .map(|h| h as f64 * f0)
                .take_while(|&f| f < top)
                .map(|f| (f, f0 / f, rng.random::<f64>() * std::f64::consts::TAU))
                .collect();
            (0..n)
                .map(|t| {
                    let t = t as f64 / f64::from(fs);
                    harmonics
                        .iter()
                        .map(|&(f, a, ph)| a * (std::f64::consts::TAU * f * t + ph).sin())
                        .sum()
                })
                .collect()
        }
    };
    scale_to_unit_power(&mut x);
    x
}

/// Unit-power noise with amplitude spectrum `shape(f)`.
fn shaped_noise(n: usize, fs: u32, rng: &mut StdRng, shape: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut b: Vec<Complex64> = (0..n)
        .map(|_| Complex64::new(rng.sample(StandardNormal), 0.0))
        .collect();
    let mut planner = FftPlanner::<f64>::new();
    planner.plan_fft_forward(n).process(&mut b);
    for (k, v) in b.iter_mut().enumerate() {
        let f = k.min(n - k) as f64 * f64::from(fs) / n as f64;
        *v *= shape(f);
    }
    planner.plan_fft_inverse(n).process(&mut b);
    let x: Vec<f64> = b.iter().map(|v| v.re).collect();
    let p = (x.iter().map(|v| v * v).sum::<f64>() / n as f64)
        .sqrt()
        .max(1e-300);
    x.into_iter().map(|v| v / p).collect()
}

/// Scales `x` to unit mean power, unless it is silent or not finite; returns its mean power
/// before scaling.
pub fn scale_to_unit_power(x: &mut [f64]) -> f64 {
    let p = x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64;
    if p > 0.0 && p.is_finite() {
        let g = p.sqrt().recip();
        x.iter_mut().for_each(|v| *v *= g);
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn signals_have_unit_power_and_are_seeded() {
        for s in [
            Signal::Noise,
            Signal::PinkNoise,
            Signal::SpeechShaped,
            Signal::Harmonic(150.0),
        ] {
            let a = generate(s, 4800, 48_000, &mut StdRng::seed_from_u64(3));
            let b = generate(s, 4800, 48_000, &mut StdRng::seed_from_u64(3));
            assert_eq!(a, b);
            let p = a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64;
            approx::assert_abs_diff_eq!(p, 1.0, epsilon = 1e-9);
        }
    }

    #[test]
    fn shaped_noises_have_their_spectral_slopes() {
        // Mean power density (per Hz) in 500-1000 Hz against 2000-4000 Hz, two octaves
        // higher: pink noise (-3 dB per octave) is 6.02 dB weaker there; speech-shaped
        // noise (-6 dB per octave above 500 Hz) 12.04 dB.
        let n = 1 << 16;
        let fs = 16_000;
        let density = |x: &[f64], lo: f64, hi: f64| {
            let mut b: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
            FftPlanner::<f64>::new().plan_fft_forward(n).process(&mut b);
            let df = f64::from(fs) / n as f64;
            let (a, z) = ((lo / df) as usize, (hi / df) as usize);
            b[a..z].iter().map(|v| v.norm_sqr()).sum::<f64>() / (hi - lo)
        };
        for (s, want_db) in [(Signal::PinkNoise, 6.02), (Signal::SpeechShaped, 12.04)] {
            let x = generate(s, n, fs, &mut StdRng::seed_from_u64(5));
            let db = 10.0 * (density(&x, 500.0, 1000.0) / density(&x, 2000.0, 4000.0)).log10();
            approx::assert_abs_diff_eq!(db, want_db, epsilon = 0.5);
        }
    }
}
