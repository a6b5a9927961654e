//! What each microphone hears: every source's signal convolved with its room impulse
//! response to that microphone, summed.
//!
//! A robot's recording session renders the same sources at many poses, so a [`Renderer`]
//! keeps what does not depend on the microphones: each source's image sources (the
//! image lattice depends on the source and the room only) and the spectra of its signal,
//! cut into blocks. A stop then costs one impulse response and one FFT per source and
//! microphone, and one inverse FFT per block and microphone.
//!
//! Convolution is overlap-add with FFTs of a size `N` chosen per scene: each block of
//! `B = N - L + 1` signal samples convolved with a response of `L` samples fits in `N`.
//! One FFT of the whole signal (`N >= n + L - 1`) would do, but a 3 s clip at 48 kHz with a
//! 0.5 s response would need 2^18-point transforms for each of 60 responses; blocks let the
//! responses be transformed at 2^16 and cost ~3.5 times less.

use std::sync::Arc;

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex, num_complex::Complex64};

use crate::ism::{HIGH_PASS_HZ, ImageSource, add_images, high_pass, image_sources};
use crate::plan::{self, PlanImages, PlanRoom};
use crate::room::{Room, Space};

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
/// sources of `signal * rir`. The impulse responses carry `1 / (4 pi d)`, so a source 1 m
/// away in free field would arrive at `1 / (4 pi)` of its signal; the factor `4 pi` is put
/// back so that a source's signal is its pressure at 1 m.
///
/// To render the same sources at many microphone positions, build a [`Renderer`] once.
pub fn render(
    room: &Room,
    sources: &[RoomSource],
    mics: &[[f64; 3]],
    n: usize,
    cfg: &RenderConfig,
) -> Vec<Vec<f64>> {
    Renderer::new(room, sources, n, cfg).render(mics)
}

/// Each source's images: a shoebox's sound everywhere; a plan's are checked per
/// microphone, and a diffuse tail follows them.
#[derive(Clone)]
enum Images {
    Shoebox(Vec<Vec<ImageSource>>),
    Plan(PlanRoom, Vec<PlanImages>),
}

impl Images {
    fn len(&self) -> usize {
        match self {
            Images::Shoebox(v) => v.len(),
            Images::Plan(_, v) => v.len(),
        }
    }
}

/// Sources in a room, ready to be heard from anywhere: see the module documentation.
#[derive(Clone)]
pub struct Renderer {
    cfg: RenderConfig,
    /// Samples rendered per microphone.
    n: usize,
    /// Per source: its images within reach of any point of the room.
    images: Images,
    /// Transform size `N` and block length `B`.
    fft_len: usize,
    block: usize,
    /// Per source, per block: the spectrum of the block (`N / 2 + 1` bins).
    spectra: Vec<Vec<Vec<Complex64>>>,
    fwd: Arc<dyn RealToComplex<f64>>,
    inv: Arc<dyn ComplexToReal<f64>>,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("cfg", &self.cfg)
            .field("n", &self.n)
            .field("sources", &self.images.len())
            .field("images", &self.image_counts())
            .field("fft_len", &self.fft_len)
            .field("block", &self.block)
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// Prepares `sources` in `room` for rendering `n` samples (signals shorter than `n`
    /// are padded with silence).
    pub fn new(room: &Room, sources: &[RoomSource], n: usize, cfg: &RenderConfig) -> Self {
        Self::new_in(&Space::Shoebox(room.clone()), sources, n, cfg)
    }

    /// [`Renderer::new`] in a room of either kind. In a plan ([`crate::plan`]) each
    /// source's images are those within [`plan::EXACT_S`] after the direct sound from
    /// anywhere in the room; a stop checks them at each microphone and adds the diffuse
    /// tail, a fresh draw for each source and stop.
    pub fn new_in(space: &Space, sources: &[RoomSource], n: usize, cfg: &RenderConfig) -> Self {
        let l = cfg.rir_len.max(1);
        let (fft_len, block) = plan_blocks(n.max(1), l, sources.len());
        let mut planner = RealFftPlanner::<f64>::new();
        let fwd = planner.plan_fft_forward(fft_len);
        let inv = planner.plan_fft_inverse(fft_len);
        let images = match space {
            Space::Shoebox(room) => {
                // Reach of the response from the farthest point of the room.
                let half_diag = room.dims().iter().map(|d| d * d).sum::<f64>().sqrt() / 2.0;
                let centre = room.dims().map(|d| d / 2.0);
                let reach = l as f64 / cfg.fs * cfg.speed_of_sound + half_diag;
                Images::Shoebox(
                    sources
                        .iter()
                        .map(|s| image_sources(room, s.pos, centre, reach, cfg.max_order))
                        .collect(),
                )
            }
            Space::Plan(room) => {
                // The farthest a microphone can be from a source, then the exact part.
                let (lo, hi) = room.bounds();
                let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]).hypot(room.height());
                let exact = (plan::EXACT_S + plan::FADE_S) * cfg.speed_of_sound + diag;
                let reach = exact.min(l as f64 / cfg.fs * cfg.speed_of_sound);
                Images::Plan(
                    room.clone(),
                    sources
                        .iter()
                        .map(|s| room.images(s.pos, reach, cfg.max_order))
                        .collect(),
                )
            }
        };
        let mut buf = fwd.make_input_vec();
        let spectra = sources
            .iter()
            .map(|s| {
                let x = &s.signal[..s.signal.len().min(n)];
                (0..n.div_ceil(block))
                    .map(|b| {
                        buf.fill(0.0);
                        let part = x
                            .get(b * block..x.len().min((b + 1) * block))
                            .unwrap_or(&[]);
                        buf[..part.len()].copy_from_slice(part);
                        let mut spec = fwd.make_output_vec();
                        fwd.process(&mut buf, &mut spec)
                            .expect("buffers sized by the plan");
                        spec
                    })
                    .collect()
            })
            .collect();
        Self {
            cfg: *cfg,
            n,
            images,
            fft_len,
            block,
            spectra,
            fwd,
            inv,
        }
    }

    /// Number of image sources kept per source (in a plan, the plan's images, before
    /// each microphone's check).
    pub fn image_counts(&self) -> Vec<usize> {
        match &self.images {
            Images::Shoebox(v) => v.iter().map(Vec::len).collect(),
            Images::Plan(_, v) => v.iter().map(|i| i.plan.len()).collect(),
        }
    }

    /// What each microphone (world positions, m) hears: `n` samples per microphone.
    pub fn render(&self, mics: &[[f64; 3]]) -> Vec<Vec<f64>> {
        self.render_playing(mics, &vec![true; self.images.len()])
    }

    /// [`Renderer::render`] with only the sources whose flag in `playing` is set.
    ///
    /// # Panics
    /// If `playing` has not one flag per source.
    pub fn render_playing(&self, mics: &[[f64; 3]], playing: &[bool]) -> Vec<Vec<f64>> {
        assert_eq!(playing.len(), self.images.len(), "one flag per source");
        let RenderConfig {
            fs,
            speed_of_sound: c,
            rir_len,
            ..
        } = self.cfg;
        let l = rir_len.max(1);
        let bins = self.fft_len / 2 + 1;
        let blocks = self.n.div_ceil(self.block);
        let gain = 4.0 * std::f64::consts::PI / self.fft_len as f64;
        let mut h = self.fwd.make_input_vec();
        let mut y = self.inv.make_output_vec();
        // Source by source, every microphone's response first: a diffuse tail's waves are
        // then read once for the whole array ([`add_tail`]) instead of once a microphone.
        // Each microphone's sums run in the same order as one microphone at a time.
        let mut hs = vec![self.fwd.make_output_vec(); mics.len()];
        let mut acc = vec![vec![vec![Complex64::default(); bins]; blocks]; mics.len()];
        let centre = centroid(mics);
        let tails = self.tails(centre, playing);
        // The array's reach about its centre: in a plan, the images near enough to sound at
        // any of its microphones are taken once for all of them ([`plan::PlanImages::near`]).
        let radius = mics
            .iter()
            .map(|m| (m[0] - centre[0]).hypot(m[1] - centre[1]))
            .fold(0.0, f64::max);
        for (i, spectra) in self.spectra.iter().enumerate().filter(|(i, _)| playing[*i]) {
            // One microphone's response to the source's images.
            let from = tails[i].as_ref().map(|t| t.from);
            let add: Box<Respond> = match &self.images {
                Images::Shoebox(images) => {
                    let images = &images[i];
                    Box::new(move |h, m| add_images(h, images, m, fs, c))
                }
                Images::Plan(room, images) => {
                    let images = &images[i];
                    let reach = plan::image_reach(l, fs, c, from);
                    let near = images.near(room, [centre[0], centre[1]], radius, reach);
                    Box::new(move |h, m| {
                        plan::add_plan_images(room, images, Some(&near), m, fs, c, h, from);
                    })
                }
            };
            for (&m, hs) in mics.iter().zip(hs.iter_mut()) {
                h.fill(0.0);
                add(&mut h[..l], m);
                high_pass(&mut h[..l], HIGH_PASS_HZ, fs);
                self.fwd
                    .process(&mut h, hs)
                    .expect("buffers sized by the plan");
            }
            if let Some(tail) = &tails[i] {
                add_tail(&mut hs, &tail.waves, mics, centre, c / fs, self.fft_len);
            }
            for (acc, hs) in acc.iter_mut().zip(&hs) {
                for (a, x) in acc.iter_mut().zip(spectra) {
                    for ((a, x), h) in a.iter_mut().zip(x).zip(hs) {
                        *a += x * h;
                    }
                }
            }
        }
        acc.into_iter()
            .map(|mut acc| {
                let mut out = vec![0.0; self.n];
                for (b, a) in acc.iter_mut().enumerate() {
                    // The inverse real FFT wants real DC and Nyquist bins; they are, up to
                    // rounding.
                    a[0].im = 0.0;
                    a[bins - 1].im = 0.0;
                    self.inv
                        .process(a, &mut y)
                        .expect("buffers sized by the plan");
                    let at = b * self.block;
                    for (o, v) in out[at..].iter_mut().zip(&y) {
                        *o += v * gain;
                    }
                }
                out
            })
            .collect()
    }
}

/// Adds one microphone's response to one source's images to a buffer: the microphone's
/// position (m).
type Respond<'a> = dyn Fn(&mut [f64], [f64; 3]) + 'a;

impl Renderer {
    /// In a plan, each playing source's diffuse tail heard at `centre`: when it takes
    /// over, and its plane waves' spectra, high-passed as the images are, with where each
    /// comes from. A fresh draw per source and stop (seeded by both), so that sources and
    /// stops do not share it.
    fn tails(&self, centre: [f64; 3], playing: &[bool]) -> Vec<Option<Tail>> {
        let Images::Plan(room, images) = &self.images else {
            return playing.iter().map(|_| None).collect();
        };
        let RenderConfig {
            fs,
            speed_of_sound: c,
            rir_len,
            ..
        } = self.cfg;
        let l = rir_len.max(1);
        let dirs = plan::tail_directions();
        images
            .iter()
            .zip(playing)
            .enumerate()
            .map(|(i, (im, &on))| {
                on.then(|| {
                    let from = plan::tail_start(distance(im.src, centre), c);
                    let seed = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                        ^ centre[0].to_bits().rotate_left(17)
                        ^ centre[1].to_bits().rotate_left(31)
                        ^ centre[2].to_bits().rotate_left(47);
                    let mut buf = self.fwd.make_input_vec();
                    let waves = plan::tail_waves(room, fs, c, l, from, seed)
                        .into_iter()
                        .zip(&dirs)
                        .map(|(mut w, d)| {
                            high_pass(&mut w, HIGH_PASS_HZ, fs);
                            buf.fill(0.0);
                            buf[..l].copy_from_slice(&w);
                            let mut spec = self.fwd.make_output_vec();
                            self.fwd
                                .process(&mut buf, &mut spec)
                                .expect("buffers sized by the plan");
                            (*d, spec)
                        })
                        .collect();
                    Tail { from, waves }
                })
            })
            .collect()
    }
}

/// A diffuse tail's plane waves: where each comes from, and its spectrum.
type TailWaves = Vec<([f64; 3], Vec<Complex64>)>;

/// One source's diffuse tail at one stop: when it takes over (s from emission, at the
/// array's centre), and its plane waves.
struct Tail {
    from: f64,
    waves: TailWaves,
}

/// Adds to each microphone's response spectrum (`hs`, one `n`-point real FFT per
/// microphone of `mics`) the tail's plane waves as it hears them: each arrives `u . (mic -
/// centre) / c` earlier there than at the centre (`u` the direction it comes from;
/// `per_sample` = `c / fs`, metres per sample), a phase ramp over the bins.
///
/// A ramp is a running product (`turn *= step`), a chain whose latency bound the loop
/// while one microphone's took the waves one after the other, and each wave's spectrum
/// (megabytes) was read again for every microphone. Here a stretch of bins at a time,
/// each wave's stretch is read once and turned for every microphone, their chains side by
/// side in SIMD lanes (real and imaginary parts apart, microphones along the lanes). Each
/// bin still adds the waves in their order and each chain runs as before, with the
/// products and sums of complex arithmetic and no fused multiply-adds: the same bits.
fn add_tail(
    hs: &mut [Vec<Complex64>],
    waves: &[([f64; 3], Vec<Complex64>)],
    mics: &[[f64; 3]],
    centre: [f64; 3],
    per_sample: f64,
    n: usize,
) {
    // Microphones padded to whole lanes; a padded lane turns nothing into nothing.
    let m = mics.len().div_ceil(LANES) * LANES;
    let mut step_re = vec![1.0; waves.len() * m];
    let mut step_im = vec![0.0; waves.len() * m];
    for (w, (u, _)) in waves.iter().enumerate() {
        for (j, mic) in mics.iter().enumerate() {
            let r = [mic[0] - centre[0], mic[1] - centre[1], mic[2] - centre[2]];
            // Delay in samples (negative: earlier).
            let delay = -(u[0] * r[0] + u[1] * r[1] + u[2] * r[2]) / per_sample;
            let step = Complex64::from_polar(1.0, -std::f64::consts::TAU * delay / n as f64);
            step_re[w * m + j] = step.re;
            step_im[w * m + j] = step.im;
        }
    }
    let mut turn_re = vec![0.0; waves.len() * m];
    for w in 0..waves.len() {
        turn_re[w * m..w * m + mics.len()].fill(1.0);
    }
    let bins = waves
        .iter()
        .map(|(_, s)| s.len())
        .chain(hs.iter().map(Vec::len))
        .min()
        .unwrap_or(0);
    // Bin-major, microphone-minor copies of the responses, the parts apart.
    let (mut re, mut im) = (vec![0.0; bins * m], vec![0.0; bins * m]);
    for (j, h) in hs.iter().enumerate() {
        for (k, x) in h[..bins].iter().enumerate() {
            re[k * m + j] = x.re;
            im[k * m + j] = x.im;
        }
    }
    let mut turns = TailTurns {
        m,
        step_re,
        step_im,
        turn_im: vec![0.0; turn_re.len()],
        turn_re,
    };
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports the feature the function is compiled for.
        unsafe { turns.turn_avx2(waves, &mut re, &mut im, bins) };
    } else {
        turns.turn(waves, &mut re, &mut im, bins);
    }
    #[cfg(not(target_arch = "x86_64"))]
    turns.turn(waves, &mut re, &mut im, bins);
    for (j, h) in hs.iter_mut().enumerate() {
        for (k, x) in h[..bins].iter_mut().enumerate() {
            *x = Complex64::new(re[k * m + j], im[k * m + j]);
        }
    }
}

/// Microphones per SIMD group in [`add_tail`] (four doubles: one AVX2 register).
const LANES: usize = 4;

/// Every wave's phase ramp at every microphone ([`add_tail`]): wave-major, microphones
/// (padded to whole [`LANES`]) minor, the parts apart.
struct TailTurns {
    m: usize,
    step_re: Vec<f64>,
    step_im: Vec<f64>,
    turn_re: Vec<f64>,
    turn_im: Vec<f64>,
}

impl TailTurns {
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn turn_avx2(
        &mut self,
        waves: &[([f64; 3], Vec<Complex64>)],
        re: &mut [f64],
        im: &mut [f64],
        bins: usize,
    ) {
        self.turn(waves, re, im, bins);
    }

    /// Adds each wave, turned, to the responses `re` and `im` (bin-major, microphones
    /// minor), `bins` bins.
    #[inline(always)]
    fn turn(
        &mut self,
        waves: &[([f64; 3], Vec<Complex64>)],
        re: &mut [f64],
        im: &mut [f64],
        bins: usize,
    ) {
        /// Bins per stretch: the stretch of every microphone's response stays in cache.
        const STRETCH: usize = 256;
        let m = self.m;
        for start in (0..bins).step_by(STRETCH) {
            let end = (start + STRETCH).min(bins);
            for (w, (_, spec)) in waves.iter().enumerate() {
                for g in (0..m).step_by(LANES) {
                    let at = w * m + g;
                    let lanes = |v: &[f64]| -> [f64; LANES] { std::array::from_fn(|l| v[at + l]) };
                    let (sr, si) = (lanes(&self.step_re), lanes(&self.step_im));
                    let (mut tr, mut ti) = (lanes(&self.turn_re), lanes(&self.turn_im));
                    for (k, x) in spec[start..end].iter().enumerate() {
                        let row = (start + k) * m + g;
                        let hr: &mut [f64; LANES] = (&mut re[row..row + LANES]).try_into().unwrap();
                        let hi: &mut [f64; LANES] = (&mut im[row..row + LANES]).try_into().unwrap();
                        for l in 0..LANES {
                            // h += x * turn; turn *= step (num_complex's arithmetic).
                            let (a, b) = (tr[l], ti[l]);
                            hr[l] += x.re * a - x.im * b;
                            hi[l] += x.re * b + x.im * a;
                            tr[l] = a * sr[l] - b * si[l];
                            ti[l] = a * si[l] + b * sr[l];
                        }
                    }
                    self.turn_re[at..at + LANES].copy_from_slice(&tr);
                    self.turn_im[at..at + LANES].copy_from_slice(&ti);
                }
            }
        }
    }
}

/// The mean of `points`.
fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in points {
        for k in 0..3 {
            c[k] += p[k] / n;
        }
    }
    c
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// The transform size `N` (a power of two) and block length `N - L + 1` for `n` samples
/// convolved with `L`-sample responses of `sources` sources, minimising the work of a
/// stop: `S` + `blocks` transforms of size `N` per microphone (at `N log2 N` each) and `S
/// * blocks` spectrum products (at `N` each).
fn plan_blocks(n: usize, l: usize, sources: usize) -> (usize, usize) {
    let whole = (n + l - 1).next_power_of_two();
    let s = sources as f64;
    let cost = |size: usize| {
        let (nf, blocks) = (size as f64, n.div_ceil(size - l + 1) as f64);
        (s + blocks) * nf * nf.log2() + s * blocks * nf * 2.0
    };
    let first = (2 * l).next_power_of_two().min(whole);
    let size = std::iter::successors(Some(first), |&z| (z < whole).then_some(2 * z))
        .min_by(|a, b| cost(*a).total_cmp(&cost(*b)))
        .expect("the sizes from `first` to `whole` are not empty");
    (size, size - l + 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ism::{dist, rir};

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
    fn block_convolution_equals_direct_convolution() {
        // 20 000 samples against a 2048-sample response: the renderer picks 8192-point
        // transforms and four blocks; every output sample must equal the plain sum
        // 4 pi sum_k h[k] x[t - k] with the same response.
        let room = Room::with_rt60([6.0, 4.0, 3.0], 0.3, 343.0).unwrap();
        let cfg = RenderConfig {
            fs: 8000.0,
            speed_of_sound: 343.0,
            rir_len: 2048,
            max_order: None,
        };
        assert_eq!(plan_blocks(20_000, 2048, 1), (8192, 6145));
        let x: Vec<f64> = (0..20_000)
            .map(|i| (((i * 7919) % 113) as f64 - 56.0) / 56.0)
            .collect();
        let (src, mic) = ([1.0, 1.2, 1.1], [4.5, 2.9, 1.4]);
        let h = rir(
            &room,
            src,
            mic,
            cfg.fs,
            cfg.speed_of_sound,
            cfg.rir_len,
            None,
        );
        let y = render(
            &room,
            &[RoomSource {
                pos: src,
                signal: x.clone(),
            }],
            &[mic],
            20_000,
            &cfg,
        );
        let scale = 4.0 * std::f64::consts::PI;
        for t in 0..20_000 {
            let direct: f64 = (0..=t.min(2047)).map(|k| h[k] * x[t - k]).sum::<f64>() * scale;
            approx::assert_abs_diff_eq!(y[0][t], direct, epsilon = 1e-9);
        }
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
