//! What each microphone hears: every source's signal convolved with its room impulse
//! response to that microphone, summed.

use rustfft::{FftPlanner, num_complex::Complex64};

use crate::ism::rir;
use crate::room::Room;

/// One source in a room: position (m) and the signal it emits (at the sample rate given to
/// [`render`], pressure at 1 m).
#[derive(Clone, Debug, PartialEq)]
pub struct RoomSource {
    /// Position (m), inside the room.
    pub pos: [f64; 3],
    /// The emitted signal, scaled to its pressure at 1 m.
    pub signal: Vec<f64>,
}

/// How responses are computed for [`render`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderConfig {
    /// Sample rate (Hz).
    pub fs: f64,
    /// Speed of sound (m/s).
    pub speed_of_sound: f64,
    /// Impulse-response length (samples).
    pub rir_len: usize,
    /// At most this many reflections per image, when given.
    pub max_order: Option<u32>,
}

/// Renders `n` samples at each microphone (`mics`, world positions in m): the sum over
/// sources of `signal * rir` (FFT convolution). The impulse responses carry `1 / (4 pi d)`,
/// so a source 1 m away in free field would arrive at `1 / (4 pi)` of its signal; the
/// factor `4 pi` is put back so that a source's signal is its pressure at 1 m.
pub fn render(
    room: &Room,
    sources: &[RoomSource],
    mics: &[[f64; 3]],
    n: usize,
    cfg: &RenderConfig,
) -> Vec<Vec<f64>> {
    let RenderConfig {
        fs,
        speed_of_sound: c,
        rir_len,
        max_order,
    } = *cfg;
    let size = (n + rir_len).next_power_of_two();
    let mut planner = FftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(size);
    let inv = planner.plan_fft_inverse(size);
    let spectrum = |x: &[f64]| -> Vec<Complex64> {
        let mut b: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        b.resize(size, Complex64::default());
        fwd.process(&mut b);
        b
    };
    let spectra: Vec<Vec<Complex64>> = sources
        .iter()
        .map(|s| spectrum(&s.signal[..s.signal.len().min(n)]))
        .collect();
    let gain = 4.0 * std::f64::consts::PI / size as f64;
    mics.iter()
        .map(|&m| {
            let mut acc = vec![Complex64::default(); size];
            for (s, sx) in sources.iter().zip(&spectra) {
                let h = spectrum(&rir(room, s.pos, m, fs, c, rir_len, max_order));
                for ((a, x), y) in acc.iter_mut().zip(sx).zip(&h) {
                    *a += x * y;
                }
            }
            inv.process(&mut acc);
            acc[..n].iter().map(|v| v.re * gain).collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ism::dist;

    #[test]
    fn an_anechoic_room_delays_and_attenuates_by_distance() {
        // Fully absorbing walls: only the direct path. A click train reaches a microphone
        // 3.43 m away 10 ms (160 samples at 16 kHz) later at 1 / 3.43 of its level at 1 m.
        let room = Room::new([10.0, 8.0, 4.0], [1.0; 6]).unwrap();
        let fs = 16_000.0;
        let mut click = vec![0.0; 4000];
        click[500] = 1.0;
        let src = RoomSource {
            pos: [2.0, 2.0, 1.5],
            signal: click,
        };
        let mic = [5.43, 2.0, 1.5];
        approx::assert_abs_diff_eq!(dist(src.pos, mic), 3.43, epsilon = 1e-12);
        let cfg = RenderConfig {
            fs,
            speed_of_sound: 343.0,
            rir_len: 1024,
            max_order: Some(0),
        };
        let y = render(&room, &[src], &[mic], 4000, &cfg);
        let (peak_at, peak) =
            y[0].iter().enumerate().fold(
                (0, 0.0f64),
                |b, (i, &v)| if v.abs() > b.1.abs() { (i, v) } else { b },
            );
        assert_eq!(peak_at, 660);
        // The 50 Hz high-pass takes a little of an impulse's peak.
        approx::assert_abs_diff_eq!(peak, 1.0 / 3.43, epsilon = 0.01);
    }

    #[test]
    fn sources_add_up() {
        let room = Room::with_rt60([6.0, 4.0, 3.0], 0.3, 343.0).unwrap();
        let s1 = RoomSource {
            pos: [1.0, 1.0, 1.0],
            signal: (0..800).map(|i| ((i * 37) % 17) as f64 - 8.0).collect(),
        };
        let s2 = RoomSource {
            pos: [4.0, 3.0, 2.0],
            signal: (0..800).map(|i| ((i * 11) % 7) as f64 - 3.0).collect(),
        };
        let mics = [[3.0, 2.0, 1.2], [3.1, 2.0, 1.2]];
        let cfg = RenderConfig {
            fs: 8000.0,
            speed_of_sound: 343.0,
            rir_len: 512,
            max_order: Some(3),
        };
        let both = render(&room, &[s1.clone(), s2.clone()], &mics, 800, &cfg);
        let a = render(&room, &[s1], &mics, 800, &cfg);
        let b = render(&room, &[s2], &mics, 800, &cfg);
        for m in 0..2 {
            for t in 0..800 {
                approx::assert_abs_diff_eq!(both[m][t], a[m][t] + b[m][t], epsilon = 1e-9);
            }
        }
    }
}
