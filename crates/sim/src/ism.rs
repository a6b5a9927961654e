//! The image-source method (Allen & Berkley, 1979) for shoebox rooms.
//!
//! A wall reflection is replaced by a mirror image of the source behind the wall; along one
//! axis of length `L` the images sit at `(1 - 2q) s + 2 n L` (`q` in {0, 1}, `n` any
//! integer) and have crossed the wall at 0 `|n - q|` times and the wall at `L` `|n|` times.
//! Each image reaches a microphone after `d / c` with pressure `prod(beta_w^k_w) / (4 pi d)`
//! (spherical spreading, `beta` the walls' pressure reflection coefficients). The impulse
//! response sums one band-limited impulse per image: a Hann-windowed sinc of 81 taps
//! centred on the exact, fractional arrival time (as pyroomacoustics does), so that arrival
//! times are not rounded to samples.
//!
//! ## Algorithm
//! 1. For every axis, every `q` and every `n` with `|2 n L| <= d_max + L`, list the
//!    images within `d_max` (the response's length times `c`) of the room.
//! 2. For each microphone, add each image's windowed sinc at `d / c * fs`.

use crate::error::SimError;
use crate::room::Room;

/// Half-width of the fractional-delay filter (taps on each side of the centre).
pub const SINC_HALF: usize = 40;

/// One image source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageSource {
    /// Position (m).
    pub pos: [f64; 3],
    /// Product of the reflection coefficients of the walls it crossed.
    pub gain: f64,
    /// Number of reflections.
    pub order: u32,
}

/// Every image of `src` in `room` within `max_dist` (m) of `center`, with at most
/// `max_order` reflections when given. The direct path (order 0) comes first.
pub fn image_sources(
    room: &Room,
    src: [f64; 3],
    center: [f64; 3],
    max_dist: f64,
    max_order: Option<u32>,
) -> Vec<ImageSource> {
    let dims = room.dims();
    let beta = room.reflection();
    // Per axis: (coordinate, reflections on the low wall, on the high wall).
    let axis = |a: usize| -> Vec<(f64, u32, u32)> {
        let l = dims[a];
        let n_max = ((max_dist + l) / (2.0 * l)).ceil() as i64 + 1;
        let mut v = Vec::new();
        for n in -n_max..=n_max {
            for q in 0..2i64 {
                let x = (1 - 2 * q) as f64 * src[a] + 2.0 * n as f64 * l;
                if (x - center[a]).abs() <= max_dist {
                    v.push((x, (n - q).unsigned_abs() as u32, n.unsigned_abs() as u32));
                }
            }
        }
        v
    };
    let (ax, ay, az) = (axis(0), axis(1), axis(2));
    let mut out = Vec::new();
    let d2max = max_dist * max_dist;
    for &(x, x0, x1) in &ax {
        for &(y, y0, y1) in &ay {
            let dxy = (x - center[0]).powi(2) + (y - center[1]).powi(2);
            if dxy > d2max {
                continue;
            }
            for &(z, z0, z1) in &az {
                if dxy + (z - center[2]).powi(2) > d2max {
                    continue;
                }
                let counts = [x0, x1, y0, y1, z0, z1];
                let order: u32 = counts.iter().sum();
                if max_order.is_some_and(|m| order > m) {
                    continue;
                }
                let gain = counts
                    .iter()
                    .zip(&beta)
                    .map(|(&k, b)| b.powi(k as i32))
                    .product();
                out.push(ImageSource {
                    pos: [x, y, z],
                    gain,
                    order,
                });
            }
        }
    }
    out.sort_by_key(|i| i.order);
    out
}

/// `sinc(x) * hann` at offset `x` (samples) from the centre of the 81-tap filter.
pub fn windowed_sinc(x: f64) -> f64 {
    if x.abs() >= SINC_HALF as f64 + 1.0 {
        return 0.0;
    }
    let w = 0.5 + 0.5 * (std::f64::consts::PI * x / (SINC_HALF as f64 + 1.0)).cos();
    let s = if x.abs() < 1e-12 {
        1.0
    } else {
        (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
    };
    s * w
}

/// Taps an impulse can touch: `floor(t) - SINC_HALF ..= floor(t) + SINC_HALF + 1`.
const TAPS: usize = 2 * SINC_HALF + 2;

/// Fractional positions tabulated per sample (see [`add_impulse`]).
pub const LUT_STEPS: usize = 256;

/// `windowed_sinc(j - SINC_HALF - g / LUT_STEPS)` for `g` in `0..=LUT_STEPS`, `j` in
/// `0..TAPS`: 168 KiB, built once.
fn lut() -> &'static [[f64; TAPS]] {
    static LUT: std::sync::OnceLock<Vec<[f64; TAPS]>> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        (0..=LUT_STEPS)
            .map(|g| {
                let frac = g as f64 / LUT_STEPS as f64;
                std::array::from_fn(|j| windowed_sinc(j as f64 - SINC_HALF as f64 - frac))
            })
            .collect()
    })
}

/// Adds a band-limited impulse of amplitude `amp` at fractional time `t` (samples, not
/// negative) to `h`, clipped to `h`'s extent.
///
/// The filter depends on `t` only through its fractional part, so it is read from a table
/// of [`LUT_STEPS`] + 1 filters and interpolated linearly between the two nearest: two
/// multiply-adds per tap, no trigonometry, and a loop the compiler vectorises (it was a
/// sine and a cosine per tap, 83 % of a room's rendering time, then a rotation recurrence
/// whose dependency chain still cost 8 cycles a tap). The interpolation error is at most
/// `max|f''| / (8 LUT_STEPS^2) < 6.3e-6` of `amp` (`|f''| < 3.3` for the windowed sinc,
/// `pi^2 / 3` at its centre), 50 dB below the float32 resolution of the files it ends up
/// in. pyroomacoustics does the same with 20 steps per sample.
pub fn add_impulse(h: &mut [f64], t: f64, amp: f64) {
    impulse(h, t, amp);
}

#[inline(always)]
fn impulse(h: &mut [f64], t: f64, amp: f64) {
    let base = t.floor();
    let start = base as i64 - SINC_HALF as i64; // sample of tap 0
    let len = h.len() as i64;
    if start >= len || start + TAPS as i64 <= 0 {
        return;
    }
    let pos = (t - base) * LUT_STEPS as f64;
    let g = (pos as usize).min(LUT_STEPS - 1);
    let w = pos - g as f64;
    let table = lut();
    let (r0, r1) = (&table[g], &table[g + 1]);
    let (a0, a1) = (amp * (1.0 - w), amp * w);
    let j0 = (-start).max(0) as usize;
    let j1 = (len - start).min(TAPS as i64) as usize;
    let first = (start + j0 as i64) as usize;
    let dst = &mut h[first..first + (j1 - j0)];
    for ((d, x0), x1) in dst.iter_mut().zip(&r0[j0..j1]).zip(&r1[j0..j1]) {
        *d += a0 * x0 + a1 * x1;
    }
}

/// The room impulse response (`len` samples at `fs`) from `src` to `mic`, with images up to
/// `max_order` reflections when given (else every image that arrives within `len`),
/// high-passed at [`HIGH_PASS_HZ`].
pub fn rir(
    room: &Room,
    src: [f64; 3],
    mic: [f64; 3],
    fs: f64,
    c: f64,
    len: usize,
    max_order: Option<u32>,
) -> Vec<f64> {
    let mut h = rir_unfiltered(room, src, mic, fs, c, len, max_order);
    high_pass(&mut h, HIGH_PASS_HZ, fs);
    h
}

/// As [`rir`], before the high-pass: the plain sum of the images' band-limited impulses.
pub fn rir_unfiltered(
    room: &Room,
    src: [f64; 3],
    mic: [f64; 3],
    fs: f64,
    c: f64,
    len: usize,
    max_order: Option<u32>,
) -> Vec<f64> {
    let max_dist = len as f64 / fs * c;
    let mut h = vec![0.0; len];
    add_images(
        &mut h,
        &image_sources(room, src, mic, max_dist, max_order),
        mic,
        fs,
        c,
    );
    h
}

/// Adds to `h` the band-limited impulse of every image in `images` that arrives at `mic`
/// within `h` (arrival `d / c`, amplitude `gain / (4 pi d)`).
///
/// This loop is most of a room's rendering time; it is compiled twice, for any x86-64 and
/// for AVX2 (four taps per instruction, and an inlined `floor`), and the build the CPU
/// supports is chosen at run time. Both give the same bits (no fused multiply-adds).
pub fn add_images(h: &mut [f64], images: &[ImageSource], mic: [f64; 3], fs: f64, c: f64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports the feature the function is compiled for.
        unsafe { add_images_avx2(h, images, mic, fs, c) };
        return;
    }
    add_images_portable(h, images, mic, fs, c);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn add_images_avx2(h: &mut [f64], images: &[ImageSource], mic: [f64; 3], fs: f64, c: f64) {
    add_images_portable(h, images, mic, fs, c);
}

#[inline(always)]
fn add_images_portable(h: &mut [f64], images: &[ImageSource], mic: [f64; 3], fs: f64, c: f64) {
    let max_dist = h.len() as f64 / fs * c;
    let max_d2 = max_dist * max_dist;
    // Each image's arrival and amplitude first, a batch at a time, in a loop the compiler
    // vectorises (square roots and divisions included, which round alike in SIMD lanes),
    // then the impulses: the per-image arithmetic was a third of the loop, done scalar.
    const BATCH: usize = 64;
    let (mut t, mut amp) = ([0.0f64; BATCH], [0.0f64; BATCH]);
    for batch in images.chunks(BATCH) {
        for ((img, t), amp) in batch.iter().zip(&mut t).zip(&mut amp) {
            let d2 = (img.pos[0] - mic[0]).powi(2)
                + (img.pos[1] - mic[1]).powi(2)
                + (img.pos[2] - mic[2]).powi(2);
            let d = d2.sqrt().max(1e-3);
            // An image beyond reach is marked by a time no impulse starts at.
            *t = if d2 > max_d2 { f64::NAN } else { d / c * fs };
            *amp = img.gain / (4.0 * std::f64::consts::PI * d);
        }
        for (&t, &amp) in t.iter().zip(&amp).take(batch.len()) {
            if !t.is_nan() {
                impulse(h, t, amp);
            }
        }
    }
}

/// Cut-off (Hz) of the high-pass filter applied to every impulse response.
///
/// Image amplitudes are all positive, so their sum carries a slowly varying offset whose
/// energy grows with the density of arrivals and outlasts the reverberation proper. Allen
/// & Berkley high-pass their responses for the same reason; 50 Hz is below every speech
/// band.
pub const HIGH_PASS_HZ: f64 = 50.0;

/// A second-order Butterworth high-pass (RBJ biquad), in place, causal.
pub fn high_pass(x: &mut [f64], fc: f64, fs: f64) {
    let w0 = std::f64::consts::TAU * fc / fs;
    let alpha = w0.sin() / std::f64::consts::SQRT_2; // Q = 1 / sqrt(2)
    let cw = w0.cos();
    let a0 = 1.0 + alpha;
    let (b0, b1, b2) = (
        (1.0 + cw) / 2.0 / a0,
        -(1.0 + cw) / a0,
        (1.0 + cw) / 2.0 / a0,
    );
    let (a1, a2) = (-2.0 * cw / a0, (1.0 - alpha) / a0);
    let (mut x1, mut x2, mut y1, mut y2) = (0.0, 0.0, 0.0, 0.0);
    for v in x.iter_mut() {
        let y = b0 * *v + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
        (x2, x1, y2, y1) = (x1, *v, y1, y);
        *v = y;
    }
}

/// Euclidean distance.
pub fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The reverberation time (s) of an impulse response by Schroeder backward integration:
/// the energy decay curve's least-squares slope between -5 dB and `-5 - range_db` dB
/// (30 for T30, 20 for T20), extrapolated to 60 dB. `None` if the decay never reaches the
/// lower bound.
pub fn schroeder_rt(h: &[f64], fs: f64, range_db: f64) -> Option<f64> {
    let energy: Vec<f64> = h.iter().map(|v| v * v).collect();
    decay_time(&energy, fs, range_db)
}

/// As [`schroeder_rt`], from energies per time bin (`rate` bins per second).
pub fn decay_time(energy: &[f64], rate: f64, range_db: f64) -> Option<f64> {
    let mut edc = vec![0.0; energy.len()];
    let mut acc = 0.0;
    for i in (0..energy.len()).rev() {
        acc += energy[i];
        edc[i] = acc;
    }
    let total = *edc.first()?;
    if total <= 0.0 {
        return None;
    }
    let db: Vec<f64> = edc
        .iter()
        .map(|e| 10.0 * (e / total).max(1e-300).log10())
        .collect();
    let start = db.iter().position(|&v| v <= -5.0)?;
    let end = db.iter().position(|&v| v <= -5.0 - range_db)?;
    let n = (end - start + 1) as f64;
    let (mut st, mut sy, mut stt, mut sty) = (0.0, 0.0, 0.0, 0.0);
    for (i, &y) in db.iter().enumerate().take(end + 1).skip(start) {
        let t = i as f64 / rate;
        st += t;
        sy += y;
        stt += t * t;
        sty += t * y;
    }
    let slope = (n * sty - st * sy) / (n * stt - st * st);
    (slope < 0.0).then(|| -60.0 / slope)
}

/// The T30 (s) of `room` as the image-source method renders it, from the energies of the
/// images (1 ms bins, no filter) of a source at 0.3 of the room's extent heard at 0.7, over
/// `length_s`: cheap enough to search absorption with. The offset that the high-pass
/// removes from rendered responses never enters, since energies add incoherently here.
pub fn ism_t30(room: &Room, c: f64, length_s: f64) -> Option<f64> {
    let d = room.dims();
    let (src, mic) = (d.map(|v| 0.3 * v), d.map(|v| 0.7 * v));
    let rate = 1000.0;
    let mut energy = vec![0.0; (length_s * rate) as usize + 1];
    for img in image_sources(room, src, mic, length_s * c, None) {
        let r = dist(img.pos, mic).max(1e-3);
        if let Some(e) = energy.get_mut((r / c * rate) as usize) {
            *e += img.gain * img.gain / (r * r);
        }
    }
    decay_time(&energy, rate, 30.0)
}

/// The constructor that calibrates a room against the rendered decay lives here, beside
/// the image-source method it runs, so that [`Room`] itself stays plain geometry.
impl Room {
    /// A room whose walls all absorb alike, with reverberation time `rt60` (s) as the
    /// image-source method renders it at speed of sound `c`.
    ///
    /// Sabine's inversion `alpha = 0.161 V / (S RT60)` is the start. A shoebox's specular
    /// images decay more slowly than Sabine's diffuse field, though (paths along the long
    /// axis meet walls less often and dominate the late decay: +4 % at 0.3 s, +23 % at
    /// 0.8 s in a 6 x 4 x 3 m room), so the absorption is then raised by bisection until the
    /// rendered decay ([`ism_t30`]) lasts `rt60`.
    ///
    /// # Errors
    /// [`SimError::Invalid`] if `rt60` is not positive, or is shorter than the room can
    /// have even with fully absorbing walls.
    pub fn with_rt60(dims: [f64; 3], rt60: f64, c: f64) -> Result<Self, SimError> {
        let room = Self::new(dims, [0.0; 6])?;
        if !(rt60.is_finite() && rt60 > 0.0) {
            return Err(SimError::Invalid {
                field: "room.rt60".into(),
                message: format!("{rt60} s is not a positive time"),
            });
        }
        let too_short = || SimError::Invalid {
            field: "room.rt60".into(),
            message: format!(
                "{rt60} s is shorter than this room can have ({:.3} s by Sabine with fully absorbing walls)",
                0.161 * room.volume() / room.surface()
            ),
        };
        let sabine = 0.161 * room.volume() / (room.surface() * rt60);
        if sabine >= 1.0 {
            return Err(too_short());
        }
        // `a` stays within [sabine, 0.99], a valid absorption of these (checked) dims.
        let t30 = |a: f64| {
            Self::new(dims, [a; 6])
                .ok()
                .and_then(|r| ism_t30(&r, c, 1.2 * rt60))
        };
        let (mut lo, mut hi) = (sabine, 0.99);
        if t30(lo).is_none_or(|t| t <= rt60) {
            return Self::new(dims, [sabine; 6]);
        }
        if t30(hi).is_some_and(|t| t > rt60) {
            return Err(too_short());
        }
        // T30 falls as absorption rises: keep lo too live, hi too dead.
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            if t30(mid).is_some_and(|t| t > rt60) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Self::new(dims, [0.5 * (lo + hi); 6])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    const C: f64 = 343.0;

    #[test]
    fn the_direct_path_arrives_at_d_over_c_with_one_over_4_pi_d() {
        let room = Room::new([6.0, 4.0, 3.0], [1.0; 6]).unwrap(); // anechoic
        let (src, mic) = ([1.0, 1.0, 1.5], [4.0, 3.0, 1.2]);
        let fs = 16_000.0;
        let h = rir_unfiltered(&room, src, mic, fs, C, 2048, None);
        let d = dist(src, mic);
        let t = d / C * fs; // 169.5.. samples
        // The band-limited impulse interpolates back to its amplitude at its exact time.
        let peak: f64 = (0..h.len())
            .map(|k| h[k] * windowed_sinc(k as f64 - t))
            .sum::<f64>()
            / (0..h.len())
                .map(|k| windowed_sinc(k as f64 - t).powi(2))
                .sum::<f64>();
        assert_abs_diff_eq!(peak, 1.0 / (4.0 * std::f64::consts::PI * d), epsilon = 1e-6);
        // Nothing before it (beyond the filter's half-width).
        assert!(h[..(t as usize - SINC_HALF - 1)].iter().all(|v| *v == 0.0));
    }

    #[test]
    fn the_six_first_order_images_are_mirror_points() {
        let room = Room::new([6.0, 4.0, 3.0], [0.0; 6]).unwrap();
        let s = [1.0, 1.5, 2.0];
        let imgs = image_sources(&room, s, s, 100.0, Some(1));
        assert_eq!(imgs[0].pos, s);
        let mut first: Vec<[f64; 3]> = imgs
            .iter()
            .filter(|i| i.order == 1)
            .map(|i| i.pos)
            .collect();
        first.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut want = vec![
            [-1.0, 1.5, 2.0],
            [11.0, 1.5, 2.0],
            [1.0, -1.5, 2.0],
            [1.0, 6.5, 2.0],
            [1.0, 1.5, -2.0],
            [1.0, 1.5, 4.0],
        ];
        want.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(first, want);
    }

    #[test]
    fn the_tabulated_impulse_matches_the_windowed_sinc_tap_by_tap() {
        // Linear interpolation between filters 1/256 sample apart: error at most
        // max|f''| / (8 * 256^2) < 3.3 / 524288 = 6.3e-6 of the amplitude. Impulses cut by
        // either end of the response keep their inner taps.
        let bound = 3.3 / (8.0 * (LUT_STEPS as f64).powi(2));
        for t in [
            100.0,
            100.3,
            100.999,
            100.5 + 0.5 / 256.0,
            7.5,
            3990.2,
            4030.0,
        ] {
            let mut h = vec![0.0; 4000];
            add_impulse(&mut h, t, 0.7);
            for (k, v) in h.iter().enumerate() {
                assert_abs_diff_eq!(*v, 0.7 * windowed_sinc(k as f64 - t), epsilon = 0.7 * bound);
            }
        }
        let mut h = vec![0.0; 10];
        add_impulse(&mut h, 60.0, 1.0);
        assert!(h.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn a_fractional_delay_reproduces_a_sub_sample_shift() {
        // An impulse at 100.3 samples delays an in-band sine by exactly 100.3 samples.
        let mut h = vec![0.0; 256];
        add_impulse(&mut h, 100.3, 1.0);
        let w = std::f64::consts::TAU * 0.04;
        for n in 300..340 {
            let y: f64 = h
                .iter()
                .enumerate()
                .map(|(k, v)| v * (w * (n as f64 - k as f64)).sin())
                .sum();
            assert_abs_diff_eq!(y, (w * (n as f64 - 100.3)).sin(), epsilon = 2e-3);
        }
    }

    #[test]
    fn schroeder_recovers_an_exponential_decay() {
        // Noise-free exponential energy decay of 60 dB in 0.4 s.
        let fs = 1000.0;
        let energy: Vec<f64> = (0..1000)
            .map(|i| 10f64.powf(-6.0 * (i as f64 / fs) / 0.4))
            .collect();
        assert_abs_diff_eq!(decay_time(&energy, fs, 30.0).unwrap(), 0.4, epsilon = 0.01);
        assert_abs_diff_eq!(decay_time(&energy, fs, 20.0).unwrap(), 0.4, epsilon = 0.01);
    }

    #[test]
    fn measured_rt60_is_within_15_percent_of_the_target() {
        let fs = 8_000.0;
        let mut report = Vec::new();
        let mut failed = false;
        for target in [0.3, 0.5, 0.8] {
            let room = Room::with_rt60([6.0, 4.0, 3.0], target, C).unwrap();
            let h = rir(
                &room,
                [1.3, 1.1, 1.4],
                [4.2, 2.7, 1.6],
                fs,
                C,
                (1.5 * target * fs) as usize,
                None,
            );
            let t30 = schroeder_rt(&h, fs, 30.0).unwrap();
            let t20 = schroeder_rt(&h, fs, 20.0).unwrap();
            report.push(format!("target {target}: T30 {t30:.3}, T20 {t20:.3}"));
            failed |= (t30 - target).abs() > 0.15 * target || (t20 - target).abs() > 0.15 * target;
        }
        assert!(!failed, "{}", report.join("; "));
    }
}
