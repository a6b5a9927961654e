//! MUSIC's coarse-to-fine search ([`crate::SslConfig::music_coarse`]): a thinned grid
//! steered everywhere, the full grid around the coarse spectrum's strongest local maxima,
//! the rest interpolated.

use super::*;

/// The coarse-to-fine search: a thinned grid searched everywhere, the full grid around the
/// coarse spectrum's strongest local maxima, and the rest interpolated.
#[derive(Clone, Debug)]
pub(super) struct Coarse {
    n_az: usize,
    /// Fine azimuth cells per coarse one.
    az_stride: usize,
    /// Fine elevation indices searched coarsely, ascending, the first and last included.
    els: Vec<usize>,
    /// The steering tables of the coarse directions, coarse-elevation-major ([`Tables`]'
    /// layout).
    start_re: Vec<f32>,
    start_im: Vec<f32>,
    step_re: Vec<f32>,
    step_im: Vec<f32>,
    /// For each fine elevation: the bracketing coarse elevations and the weight of the
    /// upper one.
    el_bracket: Vec<(usize, usize, f32)>,
    /// For each fine azimuth: the bracketing coarse azimuths and the weight of the second.
    az_bracket: Vec<(usize, usize, f32)>,
    /// Local maxima refined per block.
    candidates: usize,
}

impl Music {
    /// Searches `grid` coarse-to-fine when `on` (and the grid is fine enough to thin: at
    /// least 72 azimuths, an even number): every other azimuth at every other elevation
    /// (the first and last kept) everywhere, the full grid within one coarse cell of the
    /// coarse spectrum's strongest local maxima (`6 N`, at least 12), and the rest
    /// interpolated bilinearly from the coarse cells. About a third of the directions are
    /// steered. See [`crate::SslConfig::music_coarse`] for what it costs the maps.
    #[must_use]
    pub(crate) fn coarse_search(mut self, grid: &DirectionGrid, on: bool) -> Self {
        let n_az = grid.num_azimuths();
        let n_el = grid.elevations().len();
        if !on || n_az < 72 || !n_az.is_multiple_of(2) {
            self.coarse = None;
            return self;
        }
        let mut els: Vec<usize> = (0..n_el).step_by(2).collect();
        if els.last() != Some(&(n_el - 1)) {
            els.push(n_el - 1);
        }
        let az_stride = 2;
        let dirs: Vec<usize> = els
            .iter()
            .flat_map(|&e| (0..n_az).step_by(az_stride).map(move |a| e * n_az + a))
            .collect();
        let mut tables: [Vec<f32>; 4] = Default::default();
        self.gather_into(&dirs, &mut tables);
        let [start_re, start_im, step_re, step_im] = tables;
        let el_bracket = (0..n_el)
            .map(|e| {
                let hi = els.iter().position(|&c| c >= e).expect("the last is kept");
                if els[hi] == e || hi == 0 {
                    (hi, hi, 0.0)
                } else {
                    let lo = hi - 1;
                    let t = (e - els[lo]) as f32 / (els[hi] - els[lo]) as f32;
                    (lo, hi, t)
                }
            })
            .collect();
        let caz = n_az / az_stride;
        let az_bracket = (0..n_az)
            .map(|a| {
                let (i0, r) = (a / az_stride, a % az_stride);
                (i0, (i0 + 1) % caz, r as f32 / az_stride as f32)
            })
            .collect();
        self.coarse = Some(Coarse {
            n_az,
            az_bracket,
            az_stride,
            els,
            start_re,
            start_im,
            step_re,
            step_im,
            el_bracket,
            candidates: (6 * self.sources).max(12),
        });
        self
    }

    /// The coarse-to-fine search (see [`Music::coarse_search`]).
    pub(super) fn coarse_to_fine(
        &self,
        c: &Coarse,
        dim: usize,
        out: &mut [f32],
        s: &mut SubspaceScratch,
    ) {
        let (caz, cel) = (c.n_az / c.az_stride, c.els.len());
        let nc = caz * cel;
        let coarse = Tables {
            start_re: &c.start_re,
            start_im: &c.start_im,
            step_re: &c.step_re,
            step_im: &c.step_im,
        };
        let sub = Subspaces {
            re: &s.vec_re,
            im: &s.vec_im,
            stride: dim,
            used: &s.used,
            signal: &s.signal,
            floor: &s.floor,
        };
        let nc_pad = self.pseudo(&coarse, nc, &sub, (&mut s.a_re, &mut s.a_im), &mut s.proj);
        // The coarse spectrum with each group scaled by its coarse maximum: enough to rank
        // the local maxima.
        let sum = zeroed(&mut s.coarse_sum, nc);
        self.sum_groups(&s.proj, nc_pad, nc, sum);
        c.local_maxima(sum, &mut s.peaks);
        // The full grid within one coarse cell of each.
        let mark = zeroed(&mut s.fine_mark, self.n_dirs);
        c.around(&s.peaks, mark, &mut s.fine_dirs);
        let nf = s.fine_dirs.len();
        self.gather_into(&s.fine_dirs, &mut s.fine_tables);
        let [fr, fi, sr, si] = &s.fine_tables;
        let fine = Tables {
            start_re: fr,
            start_im: fi,
            step_re: sr,
            step_im: si,
        };
        let sub = Subspaces {
            re: &s.vec_re,
            im: &s.vec_im,
            stride: dim,
            used: &s.used,
            signal: &s.signal,
            floor: &s.floor,
        };
        let nf_pad = self.pseudo(
            &fine,
            nf,
            &sub,
            (&mut s.a_re, &mut s.a_im),
            &mut s.proj_fine,
        );
        // Final sums, each group scaled by its largest value over both sets.
        let sum = zeroed(&mut s.coarse_sum, nc);
        let fine_sum = zeroed(&mut s.fine_sum, nf);
        for (pc, pf) in s
            .proj
            .chunks_exact(nc_pad)
            .zip(s.proj_fine.chunks_exact(nf_pad))
        {
            let (pc, pf) = (&pc[..nc], &pf[..nf]);
            let max = pc.iter().chain(pf).copied().fold(0.0, f32::max);
            let scale = self.group_scale(max);
            for (o, v) in sum.iter_mut().zip(pc) {
                *o += v * scale;
            }
            for (o, v) in fine_sum.iter_mut().zip(pf) {
                *o += v * scale;
            }
        }
        // Everywhere: interpolated from the coarse directions.
        c.interpolate(sum, zeroed(&mut s.rows, cel * c.n_az), out);
        // Where refined: the values themselves.
        for (&d, &v) in s.fine_dirs.iter().zip(fine_sum.iter()) {
            out[d] = v;
        }
    }
}

impl Coarse {
    /// The local maxima of the coarse spectrum `sum` (coarse-elevation-major; nothing
    /// around one, azimuth wrapping, is larger), strongest first, at most
    /// [`Coarse::candidates`] of them: `(value, coarse elevation, coarse azimuth)`.
    fn local_maxima(&self, sum: &[f32], peaks: &mut Vec<(f32, usize, usize)>) {
        let (caz, cel) = (self.n_az / self.az_stride, self.els.len());
        let at = |j: usize, i: usize| sum[j * caz + i];
        peaks.clear();
        for j in 0..cel {
            let (j0, j1) = (j.saturating_sub(1), (j + 1).min(cel - 1));
            for i in 0..caz {
                let v = at(j, i);
                let (il, ir) = (
                    if i == 0 { caz - 1 } else { i - 1 },
                    if i + 1 == caz { 0 } else { i + 1 },
                );
                let top = (j0..=j1)
                    .all(|jj| at(jj, il) <= v && at(jj, ir) <= v && (jj == j || at(jj, i) <= v));
                if top {
                    peaks.push((v, j, i));
                }
            }
        }
        peaks.sort_by(|a, b| b.0.total_cmp(&a.0));
        peaks.truncate(self.candidates);
    }

    /// The fine directions within one coarse cell of each of `peaks`, each once (`mark`,
    /// one flag per fine direction, all false on entry), in `dirs`.
    fn around(&self, peaks: &[(f32, usize, usize)], mark: &mut [bool], dirs: &mut Vec<usize>) {
        let (cel, n_el) = (self.els.len(), self.el_bracket.len());
        dirs.clear();
        for &(_, j, i) in peaks {
            let e_lo = if j == 0 { 0 } else { self.els[j - 1] };
            let e_hi = if j + 1 < cel {
                self.els[j + 1]
            } else {
                n_el - 1
            };
            let a0 = i * self.az_stride;
            for e in e_lo..=e_hi {
                for da in 0..=2 * self.az_stride {
                    let a = (a0 + self.n_az + da - self.az_stride) % self.n_az;
                    let d = e * self.n_az + a;
                    if !mark[d] {
                        mark[d] = true;
                        dirs.push(d);
                    }
                }
            }
        }
    }

    /// The full grid in `out` from the coarse spectrum `sum`: linear in azimuth along
    /// each coarse elevation (in `rows`), then in elevation.
    fn interpolate(&self, sum: &[f32], rows: &mut [f32], out: &mut [f32]) {
        let (n_az, caz) = (self.n_az, self.n_az / self.az_stride);
        for (j, row) in rows.chunks_exact_mut(n_az).enumerate() {
            let cs = &sum[j * caz..(j + 1) * caz];
            for (o, &(i0, i1, u)) in row.iter_mut().zip(&self.az_bracket) {
                *o = cs[i0] + (cs[i1] - cs[i0]) * u;
            }
        }
        for (e, &(lo, hi, t)) in self.el_bracket.iter().enumerate() {
            let (rl, rh) = (
                &rows[lo * n_az..(lo + 1) * n_az],
                &rows[hi * n_az..(hi + 1) * n_az],
            );
            for ((o, &l), &h) in out[e * n_az..(e + 1) * n_az].iter_mut().zip(rl).zip(rh) {
                *o = l + (h - l) * t;
            }
        }
    }
}
