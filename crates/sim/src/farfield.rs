//! Far-field plane waves delayed exactly to each microphone.
//!
//! A plane wave from unit direction `u` reaches a microphone at `r` earlier than the
//! origin by `r . u / c`. The delay is applied as a linear phase ramp on the whole signal's
//! DFT, which is exact at every frequency below Nyquist for a circular signal; only the
//! first and last few samples (the delay's length) see the wrap-around.

use rand::{Rng, SeedableRng, rngs::StdRng};
use rand_distr::StandardNormal;
use rustfft::{FftPlanner, num_complex::Complex64};

use crate::signal::{Signal, generate};

/// One far-field source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneWave {
    /// Azimuth (degrees, counter-clockwise from `x`).
    pub azimuth_deg: f64,
    /// Elevation (degrees above the `xy` plane).
    pub elevation_deg: f64,
    /// The signal it carries (unit power at the origin).
    pub signal: Signal,
}

impl From<(f64, f64, Signal)> for PlaneWave {
    /// `(azimuth_deg, elevation_deg, signal)`.
    fn from((azimuth_deg, elevation_deg, signal): (f64, f64, Signal)) -> Self {
        Self {
            azimuth_deg,
            elevation_deg,
            signal,
        }
    }
}

/// Delays `x` by `d` samples (any real number, either sign), circularly.
pub fn fractional_delay(x: &[f64], d: f64) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let mut planner = FftPlanner::<f64>::new();
    let mut buf: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
    planner.plan_fft_forward(n).process(&mut buf);
    for (k, v) in buf.iter_mut().enumerate() {
        let f = if k <= n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        };
        if n.is_multiple_of(2) && k == n / 2 {
            // The Nyquist bin has no well-defined fractional phase for a real signal.
            *v = Complex64::new(0.0, 0.0);
        } else {
            *v *= Complex64::from_polar(1.0, -std::f64::consts::TAU * f * d / n as f64);
        }
    }
    planner.plan_fft_inverse(n).process(&mut buf);
    buf.iter().map(|v| v.re / n as f64).collect()
}

/// Renders `n` samples at `fs` of `waves` at microphones `mics` (m), speed of sound `c`,
/// each wave of unit power, plus white sensor noise at `snr_db` against the sources'
/// total power when given. Seeded by `seed`.
pub fn render(
    mics: &[[f64; 3]],
    waves: &[PlaneWave],
    fs: u32,
    n: usize,
    c: f64,
    snr_db: Option<f64>,
    seed: u64,
) -> Vec<Vec<f64>> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut out = vec![vec![0.0f64; n]; mics.len()];
    for w in waves {
        let s = generate(w.signal, n, fs, &mut rng);
        let (az, el) = (w.azimuth_deg.to_radians(), w.elevation_deg.to_radians());
        let u = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        for (m, r) in mics.iter().enumerate() {
            let delay = -(r[0] * u[0] + r[1] * u[1] + r[2] * u[2]) / c * f64::from(fs);
            for (acc, v) in out[m].iter_mut().zip(fractional_delay(&s, delay)) {
                *acc += v;
            }
        }
    }
    if let Some(snr) = snr_db {
        let sd = (waves.len().max(1) as f64).sqrt() * 10f64.powf(-snr / 20.0);
        for ch in &mut out {
            for v in ch.iter_mut() {
                *v += sd * rng.sample::<f64, _>(StandardNormal);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_integer_delay_is_a_circular_shift() {
        // A signal with no Nyquist component (the one bin the delay drops).
        let w = |k: f64| std::f64::consts::TAU * k / 64.0;
        let x: Vec<f64> = (0..64)
            .map(|t| (w(3.0) * t as f64).sin() + 0.5 * (w(20.0) * t as f64 + 1.0).cos() + 0.2)
            .collect();
        let y = fractional_delay(&x, 3.0);
        for i in 0..64 {
            approx::assert_abs_diff_eq!(y[i], x[(i + 61) % 64], epsilon = 1e-9);
        }
    }

    #[test]
    fn a_half_sample_delay_of_a_sine_shifts_its_phase() {
        // sin(w t) delayed by 0.5 samples is sin(w (t - 0.5)), exactly, for a bin-centred w.
        let n = 256;
        let w = std::f64::consts::TAU * 10.0 / n as f64;
        let x: Vec<f64> = (0..n).map(|t| (w * t as f64).sin()).collect();
        let y = fractional_delay(&x, 0.5);
        for (t, v) in y.iter().enumerate() {
            approx::assert_abs_diff_eq!(*v, (w * (t as f64 - 0.5)).sin(), epsilon = 1e-9);
        }
    }

    #[test]
    fn the_microphone_nearer_the_source_hears_it_first() {
        // Source on +x: the mic at +0.343 m hears it 0.001 s = 16 samples (16 kHz) early.
        let mics = [[0.0, 0.0, 0.0], [0.343, 0.0, 0.0]];
        let waves = [PlaneWave {
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
            signal: Signal::Noise,
        }];
        let a = render(&mics, &waves, 16_000, 4000, 343.0, None, 9);
        let xc = |lag: usize| -> f64 { (100..3800).map(|t| a[1][t] * a[0][t + lag]).sum() };
        let best = (0..32).max_by(|&p, &q| xc(p).total_cmp(&xc(q))).unwrap();
        assert_eq!(best, 16);
    }
}
