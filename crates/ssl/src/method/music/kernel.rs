//! The kernels of [`super::Music`]: the spatial covariance of a group of bins, and the
//! pair kernel that evaluates every block's pseudo-spectrum at [`W`] directions at a time.

use super::*;

/// Directions are steered [`W`] at a time: a chunk's phasors stay in registers (or L1)
/// while every group is evaluated, so the tables are read once per block.
pub(super) const W: usize = 16;

/// The steering tables, chunk-major: `[(chunk * mics + mic) * W + lane]`.
pub(super) struct Tables<'a> {
    pub(super) start_re: &'a [f32],
    pub(super) start_im: &'a [f32],
    pub(super) step_re: &'a [f32],
    pub(super) step_im: &'a [f32],
}

/// One group of [`Music::all_blocks`]: its per-block projector terms, and the phasor step
/// to the next group (none after the last).
pub(super) struct PairKernel<'a> {
    pub(super) terms: &'a [f32],
    pub(super) mics: usize,
    pub(super) blocks: usize,
    pub(super) step: Option<(&'a [f32], &'a [f32])>,
    /// With the steered directions' antipodes ([`Antipodes`]): where they start in a row.
    pub(super) antipodes: Option<usize>,
}

impl PairKernel<'_> {
    /// `xs[b * row + d] = sum_v |e_v^H a(d)|^2` of block `b` for every padded steered
    /// direction `d`, from the phasors `cur_*` (chunk-major, as [`Tables`]), which are then
    /// advanced to the next group; with `antipodes`, the same of `-d` at `xs[b * row + h +
    /// d]` (`h` the offset given).
    pub(super) fn run(
        &self,
        cur_re: &mut [f32],
        cur_im: &mut [f32],
        g_re: &mut [f32],
        g_im: &mut [f32],
        xs: &mut [f32],
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::method::avx2_fma() {
            // SAFETY: the CPU supports the features the function is compiled for.
            unsafe { self.run_avx2(cur_re, cur_im, g_re, g_im, xs) };
            return;
        }
        self.run_portable::<false>(cur_re, cur_im, g_re, g_im, xs);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn run_avx2(
        &self,
        cur_re: &mut [f32],
        cur_im: &mut [f32],
        g_re: &mut [f32],
        g_im: &mut [f32],
        xs: &mut [f32],
    ) {
        self.run_portable::<true>(cur_re, cur_im, g_re, g_im, xs);
    }

    /// With `FMA`, the block sums use fused multiply-adds (compiled where the CPU has
    /// them; elsewhere `mul_add` would be a slow library call).
    #[inline(always)]
    pub(super) fn run_portable<const FMA: bool>(
        &self,
        cur_re: &mut [f32],
        cur_im: &mut [f32],
        g_re: &mut [f32],
        g_im: &mut [f32],
        xs: &mut [f32],
    ) {
        let m = self.mics;
        let np = m * (m - 1) / 2;
        let stride = 1 + 2 * np;
        let row = xs.len() / self.blocks;
        let chunks = self.antipodes.unwrap_or(row) / W;
        let (g_re, g_im) = (g_re.as_chunks_mut::<W>().0, g_im.as_chunks_mut::<W>().0);
        let (cur_re, cur_im) = (cur_re.as_chunks_mut::<W>().0, cur_im.as_chunks_mut::<W>().0);
        let put = |xs: &mut [f32], b: usize, c: usize, re: &[f32; W], im: &[f32; W]| {
            put_sums(xs, b * row + c * W, self.antipodes, re, im);
        };
        for c in 0..chunks {
            let (ar, ai) = (
                &mut cur_re[c * m..(c + 1) * m],
                &mut cur_im[c * m..(c + 1) * m],
            );
            let mut p = 0;
            for i in 0..m {
                for j in i + 1..m {
                    // a_i conj(a_j)
                    for l in 0..W {
                        g_re[p][l] = ar[i][l] * ar[j][l] + ai[i][l] * ai[j][l];
                        g_im[p][l] = ai[i][l] * ar[j][l] - ar[i][l] * ai[j][l];
                    }
                    p += 1;
                }
            }
            // Two blocks at a time, so that each pair phasor loaded serves both. A block's
            // terms: the trace, then each pair's two coefficients.
            let g = || g_re.iter().zip(g_im.iter());
            let mut tiles = self.terms.chunks_exact(2 * stride);
            let mut b = 0;
            for t2 in tiles.by_ref() {
                let (t, u) = t2.split_at(stride);
                // Real and imaginary parts summed apart: four independent chains of
                // multiply-adds per block pair instead of two, so that the adder's latency
                // does not bound the loop.
                let (mut x, mut y) = ([t[0]; W], [u[0]; W]);
                let (mut xi, mut yi) = ([0.0f32; W], [0.0f32; W]);
                let coefs = t[1..].chunks_exact(2).zip(u[1..].chunks_exact(2));
                for ((c, d), (gr, gi)) in coefs.zip(g()) {
                    for l in 0..W {
                        x[l] = madd::<FMA>(c[0], gr[l], x[l]);
                        xi[l] = madd::<FMA>(c[1], gi[l], xi[l]);
                        y[l] = madd::<FMA>(d[0], gr[l], y[l]);
                        yi[l] = madd::<FMA>(d[1], gi[l], yi[l]);
                    }
                }
                put(xs, b, c, &x, &xi);
                put(xs, b + 1, c, &y, &yi);
                b += 2;
            }
            let t = tiles.remainder();
            if !t.is_empty() {
                let (mut x, mut xi) = ([t[0]; W], [0.0f32; W]);
                for (c, (gr, gi)) in t[1..].chunks_exact(2).zip(g()) {
                    for l in 0..W {
                        x[l] = madd::<FMA>(c[0], gr[l], x[l]);
                        xi[l] = madd::<FMA>(c[1], gi[l], xi[l]);
                    }
                }
                put(xs, b, c, &x, &xi);
            }
            if let Some((step_re, step_im)) = self.step {
                let (sr, si) = (
                    &step_re[c * m * W..(c + 1) * m * W],
                    &step_im[c * m * W..(c + 1) * m * W],
                );
                for mic in 0..m {
                    for l in 0..W {
                        let (ox, oy) = (ar[mic][l], ai[mic][l]);
                        let (r, i) = (sr[mic * W + l], si[mic * W + l]);
                        ar[mic][l] = ox * r - oy * i;
                        ai[mic][l] = ox * i + oy * r;
                    }
                }
            }
        }
    }
}

/// A direction's pair sum, its real-part and imaginary-part sums added, at `xs[at..]`; with
/// `antipodes`, its antipode's, the second subtracted, at `h` beyond.
#[inline(always)]
pub(super) fn put_sums(
    xs: &mut [f32],
    at: usize,
    antipodes: Option<usize>,
    re: &[f32; W],
    im: &[f32; W],
) {
    let out: &mut [f32; W] = (&mut xs[at..at + W]).try_into().expect("W values");
    for l in 0..W {
        out[l] = re[l] + im[l];
    }
    if let Some(h) = antipodes {
        let out: &mut [f32; W] = (&mut xs[at + h..at + h + W]).try_into().expect("W values");
        for l in 0..W {
            out[l] = re[l] - im[l];
        }
    }
}

/// `outs[b] += scale(top_b) * p_b(x_b)` for each block `b`, `p_b` its [`Pseudo`], its
/// `x_b` the values of its row of `xs` in the ranges `segs`, one after the other (as many
/// as `outs[b]` holds), and `top_b` the row's largest value of `p_b`: one group's
/// pseudo-spectrum, scaled by its largest value and summed.
pub(super) fn accumulate(
    xs: &[f32],
    segs: &[Range<usize>; 2],
    outs: &mut [f32],
    pseudo: &[Pseudo],
    scale: &dyn Fn(f32) -> f32,
) {
    #[cfg(target_arch = "x86_64")]
    if crate::method::avx2_fma() {
        // SAFETY: the CPU supports the features the function is compiled for.
        unsafe { accumulate_avx2(xs, segs, outs, pseudo, scale) };
        return;
    }
    accumulate_portable(xs, segs, outs, pseudo, scale);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn accumulate_avx2(
    xs: &[f32],
    segs: &[Range<usize>; 2],
    outs: &mut [f32],
    pseudo: &[Pseudo],
    scale: &dyn Fn(f32) -> f32,
) {
    accumulate_portable(xs, segs, outs, pseudo, scale);
}

#[inline(always)]
pub(super) fn accumulate_portable(
    xs: &[f32],
    segs: &[Range<usize>; 2],
    outs: &mut [f32],
    pseudo: &[Pseudo],
    scale: &dyn Fn(f32) -> f32,
) {
    let nb = pseudo.len();
    let (row, nd) = (xs.len() / nb, outs.len() / nb);
    for ((x, o), &Pseudo { a0, a1, floor }) in xs
        .chunks_exact(row)
        .zip(outs.chunks_exact_mut(nd))
        .zip(pseudo)
    {
        let parts = segs.clone().map(|r| &x[r]);
        // The smallest denominator is the largest value; reduced in lanes, so that it
        // vectorises.
        let mut low = [f32::INFINITY; 8];
        let mut rest = f32::INFINITY;
        for part in parts {
            let mut it = part.chunks_exact(8);
            for ch in it.by_ref() {
                for l in 0..8 {
                    let d = a0 + a1 * ch[l];
                    low[l] = if d < low[l] { d } else { low[l] };
                }
            }
            rest = it
                .remainder()
                .iter()
                .map(|&v| a0 + a1 * v)
                .fold(rest, f32::min);
        }
        let s = scale(1.0 / low.into_iter().fold(rest, f32::min).max(floor));
        let (o0, o1) = o.split_at_mut(parts[0].len());
        for (o, part) in [o0, o1].into_iter().zip(parts) {
            for (o, &v) in o.iter_mut().zip(part) {
                *o += s / (a0 + a1 * v).max(floor);
            }
        }
    }
}

/// The upper triangle of `cov` (the rest left as it was) = `sum x x^H` over `frames` and
/// the band-relative bins `bins`, `x` a bin's value at every microphone; less the robot's
/// noise over as many frames and bins when it is known ([`crate::noise`]).
pub(crate) fn covariance(
    stft: &Spectrogram,
    frames: Range<usize>,
    bins: Range<usize>,
    cov: &mut DMatrix<Complex32>,
) {
    let t = frames.len() as f32;
    covariance_sums(stft, frames, bins.clone(), cov);
    if let Some(field) = stft.noise() {
        let m = stft.num_channels();
        let start = stft.bins().start;
        for i in 0..m {
            for j in i..m {
                let n: Complex32 = bins.clone().map(|b| field.cross(start + b, i, j)).sum();
                cov[(i, j)] -= n * t;
            }
        }
    }
}

/// [`covariance`] without the noise.
pub(super) fn covariance_sums(
    stft: &Spectrogram,
    frames: Range<usize>,
    bins: Range<usize>,
    cov: &mut DMatrix<Complex32>,
) {
    let m = stft.num_channels();
    if m > COV_LANES {
        for i in 0..m {
            for j in i..m {
                cov[(i, j)] = Complex::default();
            }
        }
        for f in frames {
            for b in bins.clone() {
                for i in 0..m {
                    let xi = stft.frame(f, i)[b];
                    for j in i..m {
                        cov[(i, j)] += xi * stft.frame(f, j)[b].conj();
                    }
                }
            }
        }
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if crate::method::avx2_fma() {
        // SAFETY: the CPU supports the features the function is compiled for.
        unsafe { covariance_avx2(stft, frames, bins, cov) };
        return;
    }
    covariance_lanes(stft, frames, bins, cov);
}

/// Arrays of up to this many microphones sum their covariance a whole row at a time.
pub(super) const COV_LANES: usize = 8;

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn covariance_avx2(
    stft: &Spectrogram,
    frames: Range<usize>,
    bins: Range<usize>,
    cov: &mut DMatrix<Complex32>,
) {
    covariance_lanes(stft, frames, bins, cov);
}

/// [`covariance`] for up to [`COV_LANES`] microphones: each row of `x x^H` summed over
/// [`COV_LANES`] columns at once (the ones beyond the array's stay 0), real and imaginary
/// parts apart, so that the sums vectorise.
#[inline(always)]
pub(super) fn covariance_lanes(
    stft: &Spectrogram,
    frames: Range<usize>,
    bins: Range<usize>,
    cov: &mut DMatrix<Complex32>,
) {
    const L: usize = COV_LANES;
    let m = stft.num_channels();
    let mut sr = [[0.0f32; L]; L];
    let mut si = [[0.0f32; L]; L];
    for f in frames {
        for b in bins.clone() {
            let (mut xr, mut xi) = ([0.0f32; L], [0.0f32; L]);
            for i in 0..m {
                let z = stft.frame(f, i)[b];
                (xr[i], xi[i]) = (z.re, z.im);
            }
            // x_i conj(x_j) = xr_i xr_j + xi_i xi_j + i (xi_i xr_j - xr_i xi_j)
            for i in 0..m {
                for j in 0..L {
                    sr[i][j] += xr[i] * xr[j] + xi[i] * xi[j];
                    si[i][j] += xi[i] * xr[j] - xr[i] * xi[j];
                }
            }
        }
    }
    for i in 0..m {
        for j in i..m {
            cov[(i, j)] = Complex::new(sr[i][j], si[i][j]);
        }
    }
}

/// One group's pseudo-spectrum in one block, `1 / max(a0 + a1 x, floor)`, for a group whose
/// projected-on vectors sum to `x = sum_v |e_v^H a|^2`: `a0 + a1 x = |E_n^H a|^2 / |a|^2`
/// (`|a|^2 = M`) is the noise subspace's projection itself, or `M` less the signal
/// subspace's, and `floor` the least of it that the group's snapshots resolve
/// ([`super::Music::resolution`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Pseudo {
    pub(super) a0: f32,
    pub(super) a1: f32,
    pub(super) floor: f32,
}

impl Pseudo {
    /// For `m` microphones, projecting on the signal subspace when `signal`, else on the
    /// noise subspace.
    pub(super) fn new(signal: bool, m: usize, floor: f32) -> Self {
        let inv_m = 1.0 / m as f32;
        let (a0, a1) = if signal { (1.0, -inv_m) } else { (0.0, inv_m) };
        Self { a0, a1, floor }
    }

    /// The pseudo-spectrum of a group holding no vector: 1 everywhere.
    pub(super) const FLAT: Self = Self {
        a0: 1.0,
        a1: 0.0,
        floor: 1.0,
    };
}

/// `a b + c`, fused when `FMA`.
#[inline(always)]
pub(super) fn madd<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// The groups' eigenvectors as [`Music::subspaces`] leaves them: group-major (`stride`
/// slots per group), then vector, then mic; group `k` uses its first `used[k]` slots, which
/// span its signal subspace when `signal[k]`, else its noise subspace.
pub(super) struct Subspaces<'a> {
    pub(super) re: &'a [f32],
    pub(super) im: &'a [f32],
    pub(super) stride: usize,
    pub(super) used: &'a [usize],
    pub(super) signal: &'a [bool],
    /// Per group, the least `|E_n^H a|^2 / |a|^2` its pseudo-spectrum takes.
    pub(super) floor: &'a [f32],
}

/// `proj[k * nd_pad + d] = sum over the group's vectors e of |e^H a_k(d)|^2` for every
/// group `k` and (padded) direction `d`.
pub(super) fn steer_all(
    t: &Tables,
    vecs: &Subspaces,
    mics: usize,
    groups: usize,
    a_re: &mut [f32],
    a_im: &mut [f32],
    proj: &mut [f32],
) {
    #[cfg(target_arch = "x86_64")]
    if crate::method::avx2_fma() {
        // SAFETY: the CPU supports the features the function is compiled for.
        unsafe { steer_all_avx2(t, vecs, mics, groups, a_re, a_im, proj) };
        return;
    }
    steer_all_portable(t, vecs, mics, groups, a_re, a_im, proj);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn steer_all_avx2(
    t: &Tables,
    vecs: &Subspaces,
    mics: usize,
    groups: usize,
    a_re: &mut [f32],
    a_im: &mut [f32],
    proj: &mut [f32],
) {
    steer_all_portable(t, vecs, mics, groups, a_re, a_im, proj);
}

#[inline(always)]
pub(super) fn steer_all_portable(
    t: &Tables,
    vecs: &Subspaces,
    mics: usize,
    groups: usize,
    a_re: &mut [f32],
    a_im: &mut [f32],
    proj: &mut [f32],
) {
    let (vec_re, vec_im, dim) = (vecs.re, vecs.im, vecs.stride);
    let nd_pad = proj.len() / groups;
    let (a_re, a_im) = (a_re.as_chunks_mut::<W>().0, a_im.as_chunks_mut::<W>().0);
    let (start_re, start_im) = (t.start_re.as_chunks::<W>().0, t.start_im.as_chunks::<W>().0);
    let (step_re, step_im) = (t.step_re.as_chunks::<W>().0, t.step_im.as_chunks::<W>().0);
    let proj = proj.as_chunks_mut::<W>().0;
    let chunks = nd_pad / W;
    for c in 0..chunks {
        let rows = c * mics..(c + 1) * mics;
        a_re.copy_from_slice(&start_re[rows.clone()]);
        a_im.copy_from_slice(&start_im[rows.clone()]);
        let (st_re, st_im) = (&step_re[rows.clone()], &step_im[rows]);
        for k in 0..groups {
            let mut p = [0.0f32; W];
            for v in 0..vecs.used[k] {
                let e = (k * dim + v) * mics;
                let (er, ei) = (&vec_re[e..e + mics], &vec_im[e..e + mics]);
                let (mut sr, mut si) = ([0.0f32; W], [0.0f32; W]);
                for (((x, y), &r), &i) in a_re.iter().zip(a_im.iter()).zip(er).zip(ei) {
                    // conj(e) a = (r - i j)(x + y j) = (r x + i y) + (r y - i x) j
                    for l in 0..W {
                        sr[l] += r * x[l] + i * y[l];
                        si[l] += r * y[l] - i * x[l];
                    }
                }
                for l in 0..W {
                    p[l] += sr[l] * sr[l] + si[l] * si[l];
                }
            }
            proj[k * chunks + c] = p;
            if k + 1 < groups {
                for (((x, y), r), i) in a_re.iter_mut().zip(a_im.iter_mut()).zip(st_re).zip(st_im) {
                    let (ox, oy) = (*x, *y);
                    for l in 0..W {
                        x[l] = ox[l] * r[l] - oy[l] * i[l];
                        y[l] = ox[l] * i[l] + oy[l] * r[l];
                    }
                }
            }
        }
    }
}
