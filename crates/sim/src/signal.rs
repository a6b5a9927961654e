//! Seeded source signals.

use rand::{Rng, rngs::StdRng};
use rand_distr::StandardNormal;

/// A source signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Signal {
    /// White Gaussian noise.
    Noise,
    /// A voiced, speech-like harmonic series: fundamental `f0` (Hz), harmonics up to
    /// 8 kHz (and below Nyquist), random phases, amplitude falling as `1/h` (-6 dB/octave,
    /// the glottal source's tilt).
    Harmonic(f64),
}

/// `n` samples of `signal` at `fs` Hz, drawn from `rng`, scaled to unit mean power.
pub fn generate(signal: Signal, n: usize, fs: u32, rng: &mut StdRng) -> Vec<f64> {
    let mut x: Vec<f64> = match signal {
        Signal::Noise => (0..n).map(|_| rng.sample(StandardNormal)).collect(),
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
        for s in [Signal::Noise, Signal::Harmonic(150.0)] {
            let a = generate(s, 4800, 48_000, &mut StdRng::seed_from_u64(3));
            let b = generate(s, 4800, 48_000, &mut StdRng::seed_from_u64(3));
            assert_eq!(a, b);
            let p = a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64;
            approx::assert_abs_diff_eq!(p, 1.0, epsilon = 1e-9);
        }
    }
}
