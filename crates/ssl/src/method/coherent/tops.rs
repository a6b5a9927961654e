//! TOPS: the test of orthogonality of projected subspaces (see [`super`] for the method,
//! how its cost is brought to one complex multiply-add per microphone pair, direction and
//! bin, and why the projection is left out).

use std::ops::Range;

use super::{C64, Mat, Plan, eigh_desc, projector};
use crate::grid::DirectionGrid;
use crate::method::{MethodScratch, SpectrumEstimator};
use crate::stft::Spectrogram;

/// Directions summed at a time by the pair kernel (one vector of lanes each).
const W: usize = 8;

/// The TOPS estimator for one array, grid, band and sample rate.
#[derive(Clone, Debug)]
pub struct Tops {
    pub(super) plan: Plan,
    /// The microphone pairs `(i, j)`, `i < j`.
    pairs: Vec<(usize, usize)>,
    /// Per direction and microphone, the steering phasor at the band's first bin and its
    /// step from one bin to the next (re, im), computed once.
    start: Vec<[f32; 2]>,
    step: Vec<[f32; 2]>,
    /// The directions the pair kernel steers, and each one's antipode when the grid holds
    /// them all (then half the grid is steered: see [`PairSums`]).
    steered: Vec<usize>,
    antipode: Option<Vec<usize>>,
}

/// What [`Tops::spectrum`] reads for every direction: the reference bin, its signal
/// subspace, and every other bin's noise projector.
pub(crate) struct Subspaces {
    /// The reference bin and `F_0` (`M x K`).
    pub b0: usize,
    pub f0: Mat,
    /// Per band bin, its projector's pair entries `Pi_ij` (`i < j`, the pairs' order),
    /// real and imaginary parts apart; all 0 for the reference bin and for bins without
    /// energy.
    pub pi_re: Vec<f32>,
    pub pi_im: Vec<f32>,
    /// Per microphone, the diagonal `sum_b Pi_b,mm`.
    pub diag: Vec<f64>,
}

impl Tops {
    /// TOPS on `plan`, which was made for `grid`.
    pub(crate) fn new(plan: Plan, grid: &DirectionGrid) -> Self {
        let m = plan.mics;
        let pairs = (0..m)
            .flat_map(|i| (i + 1..m).map(move |j| (i, j)))
            .collect();
        let (w0, dw) = (plan.omega(0), std::f64::consts::TAU / plan.frame_len as f64);
        let phasor = |w: f64| move |&lead: &f64| [(w * lead).cos() as f32, (w * lead).sin() as f32];
        let start = plan.leads.iter().map(phasor(w0)).collect();
        let step = plan.leads.iter().map(phasor(dw)).collect();
        let (steered, antipode) = match grid.antipodal_half() {
            Some((half, anti)) => (half, Some(anti)),
            None => ((0..plan.n_dirs()).collect(), None),
        };
        Self {
            plan,
            pairs,
            start,
            step,
            steered,
            antipode,
        }
    }

    /// The reference bin's signal subspace and the other bins' noise projectors, or `None`
    /// for a recording without energy.
    pub(crate) fn subspaces(&self, covs: &[Mat]) -> Option<Subspaces> {
        let (m, np) = (self.plan.mics, self.pairs.len());
        let b0 = Plan::reference(covs);
        let (vals, vecs) = eigh_desc(&covs[b0]);
        if vals[0] <= f64::MIN_POSITIVE {
            return None;
        }
        let k = self.plan.k;
        let f0 = vecs.columns(0, k).into_owned();
        let nb = covs.len();
        let (mut pi_re, mut pi_im) = (vec![0.0; nb * np], vec![0.0; nb * np]);
        let mut diag = vec![0.0; m];
        for (b, r) in covs.iter().enumerate() {
            if b == b0 || r.diagonal().iter().all(|v| v.re <= f64::MIN_POSITIVE) {
                continue;
            }
            let (_, vecs) = eigh_desc(r);
            let pi = projector(&vecs, k);
            for (p, &(i, j)) in self.pairs.iter().enumerate() {
                pi_re[b * np + p] = pi[(i, j)].re as f32;
                pi_im[b * np + p] = pi[(i, j)].im as f32;
            }
            for (i, d) in diag.iter_mut().enumerate() {
                *d += pi[(i, i)].re;
            }
        }
        Some(Subspaces {
            b0,
            f0,
            pi_re,
            pi_im,
            diag,
        })
    }

    /// `1 / sigma_min(D(u))` on every direction, into `out`.
    pub(crate) fn spectrum(&self, sub: &Subspaces, out: &mut [f32]) {
        let p = &self.plan;
        let (m, np, k) = (p.mics, self.pairs.len(), sub.f0.ncols());
        let mut sums = PairSums::new(m, np);
        // S (row-major), C = diag(conj a_0) F_0 and S C (M x K, row-major), G = C^H S C.
        let mut s = vec![C64::default(); m * m];
        let mut a0 = vec![C64::default(); m];
        let (mut c, mut sc) = (vec![C64::default(); m * k], vec![C64::default(); m * k]);
        let mut g = Mat::zeros(k, k);
        let n = self.steered.len();
        for c0 in (0..n).step_by(W) {
            let lanes = W.min(n - c0);
            sums.run(self, &self.steered[c0..c0 + lanes], sub);
            for l in 0..lanes {
                let anti = self.antipode.as_ref().map(|a| (a[c0 + l], true));
                for (d, mirrored) in std::iter::once((self.steered[c0 + l], false)).chain(anti) {
                    for (i, &v) in sub.diag.iter().enumerate() {
                        s[i * m + i] = C64::new(v, 0.0);
                    }
                    for (q, &(i, j)) in self.pairs.iter().enumerate() {
                        let v = sums.pair(q, l, mirrored);
                        s[i * m + j] = v;
                        s[j * m + i] = v.conj();
                    }
                    p.steer(d, sub.b0, &mut a0);
                    for i in 0..m {
                        for col in 0..k {
                            c[i * k + col] = a0[i].conj() * sub.f0[(i, col)];
                        }
                    }
                    for i in 0..m {
                        for col in 0..k {
                            sc[i * k + col] = (0..m).map(|j| s[i * m + j] * c[j * k + col]).sum();
                        }
                    }
                    for r in 0..k {
                        for col in r..k {
                            let v: C64 =
                                (0..m).map(|i| c[i * k + r].conj() * sc[i * k + col]).sum();
                            g[(r, col)] = v;
                            g[(col, r)] = v.conj();
                        }
                    }
                    let lambda = least_eigenvalue(&g);
                    let scale = g.diagonal().iter().map(|v| v.re).sum::<f64>();
                    out[d] = (1.0 / lambda.max(1e-12 * scale).max(f64::MIN_POSITIVE).sqrt()) as f32;
                }
            }
        }
    }
}

/// The least eigenvalue of a small Hermitian matrix: closed forms up to 2 x 2, nalgebra's
/// fixed-size eigensolver (no allocation) for 3 x 3 and 4 x 4.
fn least_eigenvalue(g: &Mat) -> f64 {
    match g.nrows() {
        1 => g[(0, 0)].re,
        2 => {
            let (a, d, b) = (g[(0, 0)].re, g[(1, 1)].re, g[(0, 1)].norm_sqr());
            let h = 0.5 * (a - d);
            0.5 * (a + d) - (h * h + b).sqrt()
        }
        3 => nalgebra::Matrix3::from_fn(|i, j| g[(i, j)])
            .symmetric_eigenvalues()
            .min(),
        4 => nalgebra::Matrix4::from_fn(|i, j| g[(i, j)])
            .symmetric_eigenvalues()
            .min(),
        _ => nalgebra::SymmetricEigen::new(g.clone()).eigenvalues.min(),
    }
}

/// The pair kernel's working memory: per bin and microphone the lanes' steering phasors,
/// per pair the lanes' four partial sums.
///
/// With `Pi = P_r + i P_i` and `g = conj(a_i) a_j = g_r + i g_i`,
/// `S_ij(u) = (A - B) + i (C + D)` for `A = sum P_r g_r`, `B = sum P_i g_i`, `C = sum P_r g_i`, `D = sum P_i g_r`; and
/// the antipode `-u` has the conjugate phasors, so `S_ij(-u) = (A + B) + i (D - C)`: the
/// same four sums give both, and a symmetric grid is steered by halves, as MUSIC's is.
struct PairSums {
    tab_re: Vec<[f32; W]>,
    tab_im: Vec<[f32; W]>,
    /// Per pair: A, B, C, D.
    sums: Vec<[[f32; W]; 4]>,
}

impl PairSums {
    fn new(m: usize, np: usize) -> Self {
        Self {
            tab_re: Vec::with_capacity(m),
            tab_im: Vec::with_capacity(m),
            sums: vec![[[0.0; W]; 4]; np],
        }
    }

    /// `S_ij` of pair `q` at lane `l`, or at its antipode (`mirrored`).
    fn pair(&self, q: usize, l: usize, mirrored: bool) -> C64 {
        let [a, b, c, d] = self.sums[q].map(|v| f64::from(v[l]));
        if mirrored {
            C64::new(a + b, d - c)
        } else {
            C64::new(a - b, c + d)
        }
    }

    /// The sums of `S_ij = sum_b Pi_b,ij conj(a_b,i) a_b,j` for directions `dirs` (at most
    /// [`W`]; the lanes past them repeat the last).
    fn run(&mut self, tops: &Tops, dirs: &[usize], sub: &Subspaces) {
        let p = &tops.plan;
        let (m, nb) = (p.mics, p.n_bins);
        // Every bin's phasors, stepped from the first bin's (one complex multiplication
        // per microphone and bin; the drift over a band's bins stays near 1e-5).
        self.tab_re.clear();
        self.tab_re.resize(nb * m, [0.0; W]);
        self.tab_im.clear();
        self.tab_im.resize(nb * m, [0.0; W]);
        for i in 0..m {
            let (mut ar, mut ai, mut sr, mut si) =
                ([0.0f32; W], [0.0f32; W], [0.0f32; W], [0.0f32; W]);
            for l in 0..W {
                let at = dirs[l.min(dirs.len() - 1)] * m + i;
                [ar[l], ai[l]] = tops.start[at];
                [sr[l], si[l]] = tops.step[at];
            }
            for b in 0..nb {
                (self.tab_re[b * m + i], self.tab_im[b * m + i]) = (ar, ai);
                for l in 0..W {
                    let (x, y) = (ar[l], ai[l]);
                    ar[l] = x * sr[l] - y * si[l];
                    ai[l] = x * si[l] + y * sr[l];
                }
            }
        }
        #[cfg(target_arch = "x86_64")]
        if crate::method::avx2_fma() {
            // SAFETY: the CPU supports the features the function is compiled for.
            unsafe { self.pairs_avx2(&tops.pairs, sub, m, nb) };
            return;
        }
        self.pairs(&tops.pairs, sub, m, nb);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn pairs_avx2(
        &mut self,
        pairs: &[(usize, usize)],
        sub: &Subspaces,
        m: usize,
        nb: usize,
    ) {
        self.pairs(pairs, sub, m, nb);
    }

    /// Per pair, its four sums over the bins, kept in registers.
    #[inline(always)]
    fn pairs(&mut self, pairs: &[(usize, usize)], sub: &Subspaces, m: usize, nb: usize) {
        let np = pairs.len();
        for (q, &(i, j)) in pairs.iter().enumerate() {
            let mut acc = [[0.0f32; W]; 4];
            for b in 0..nb {
                let (pr, pi) = (sub.pi_re[b * np + q], sub.pi_im[b * np + q]);
                let (ari, aii) = (&self.tab_re[b * m + i], &self.tab_im[b * m + i]);
                let (arj, aij) = (&self.tab_re[b * m + j], &self.tab_im[b * m + j]);
                for l in 0..W {
                    let gr = ari[l] * arj[l] + aii[l] * aij[l];
                    let gi = ari[l] * aij[l] - aii[l] * arj[l];
                    acc[0][l] += pr * gr;
                    acc[1][l] += pi * gi;
                    acc[2][l] += pr * gi;
                    acc[3][l] += pi * gr;
                }
            }
            self.sums[q] = acc;
        }
    }
}

impl SpectrumEstimator for Tops {
    fn name(&self) -> &'static str {
        "tops"
    }

    fn whole_recording(&self) -> bool {
        true
    }

    fn estimate_into(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        out: &mut [f32],
        _scratch: &mut MethodScratch,
    ) {
        self.plan.check(stft, out);
        let covs = self.plan.covariances(stft, frames);
        match self.subspaces(&covs) {
            Some(sub) => self.spectrum(&sub, out),
            None => out.fill(1.0),
        }
    }
}
