//! MUSIC and NormMUSIC against naive sums and known directions.

use super::*;
use crate::grid::ElevationRange;
use crate::method::lcg;
use nalgebra::SymmetricEigen;

/// NormMUSIC for `array` on `grid` (at most 4 sources, groups of 5 bins).
fn plan(
    array: &MicArray,
    grid: &DirectionGrid,
    (fs, c): (f64, f64),
    bins: Range<usize>,
    frame_len: usize,
    sources: Option<usize>,
) -> Music {
    Music::new(array, grid, fs, c, bins, frame_len, subspace(sources))
}

/// NormMUSIC's subspace of `sources` (`None`: estimated, at most 4), groups of 5 bins.
fn subspace(sources: Option<usize>) -> Subspace {
    Subspace {
        sources,
        max_sources: 4,
        smoothing: 2,
        normalise: true,
    }
}

/// The steering phasor `(re, im)` of microphone `mic` towards `u` at `w` rad per
/// sample, its lead over the array's centroid computed afresh in f64.
fn phasor(array: &MicArray, mic: usize, u: [f64; 3], w: f64, (fs, c): (f64, f64)) -> (f64, f64) {
    let pos = array.positions();
    let n = pos.len() as f64;
    let lead = (0..3)
        .map(|a| (pos[mic][a] - pos.iter().map(|p| p[a]).sum::<f64>() / n) * u[a])
        .sum::<f64>()
        / c
        * fs;
    ((w * lead).cos(), (w * lead).sin())
}

/// The chunked, recurrence-stepped kernel against a direct sum in f64 with every
/// steering phasor computed from its delay: `sum_v |e_v^H a_k(d)|^2`.
#[test]
fn the_steering_kernel_matches_a_direct_sum() {
    let array = MicArray::default();
    let grid = DirectionGrid::new(7.0, ElevationRange::ROBOT).unwrap();
    let (fs, c, frame_len, bins) = (48_000.0, 343.0, 1024, 5..171);
    let music = plan(&array, &grid, (fs, c), bins.clone(), frame_len, Some(2));
    let (m, dim, ng) = (array.len(), 2, music.centres.len());
    let mut uniform = lcg(7);
    let mut rnd = move || uniform() as f32;
    let vec_re: Vec<f32> = (0..ng * dim * m).map(|_| rnd()).collect();
    let vec_im: Vec<f32> = (0..ng * dim * m).map(|_| rnd()).collect();
    let nd_pad = grid.len().div_ceil(W) * W;
    let mut proj = vec![0.0; ng * nd_pad];
    let (mut a_re, mut a_im) = (vec![0.0; m * W], vec![0.0; m * W]);
    let t = Tables {
        start_re: &music.start_re,
        start_im: &music.start_im,
        step_re: &music.step_re,
        step_im: &music.step_im,
    };
    let (used, signal, floor) = (vec![dim; ng], vec![true; ng], vec![FLOOR; ng]);
    let vecs = Subspaces {
        re: &vec_re,
        im: &vec_im,
        stride: dim,
        used: &used,
        signal: &signal,
        floor: &floor,
    };
    steer_all(&t, &vecs, m, ng, &mut a_re, &mut a_im, &mut proj);
    // The portable build is the same source compiled without AVX2 (no fused
    // multiply-adds are formed): the same sums, bit for bit.
    let mut portable = vec![0.0; ng * nd_pad];
    steer_all_portable(&t, &vecs, m, ng, &mut a_re, &mut a_im, &mut portable);
    assert!(proj == portable, "dispatched and portable kernels differ");
    let mut worst = 0.0f64;
    for (k, &centre) in music.centres.iter().enumerate() {
        let w = std::f64::consts::TAU * (bins.start + centre) as f64 / frame_len as f64;
        for d in 0..grid.len() {
            let u = grid.unit(d);
            let mut want = 0.0;
            for v in 0..dim {
                let (mut re, mut im) = (0.0, 0.0);
                for mic in 0..m {
                    let (ar, ai) = phasor(&array, mic, u, w, (fs, c));
                    let i = (k * dim + v) * m + mic;
                    let (er, ei) = (f64::from(vec_re[i]), f64::from(vec_im[i]));
                    re += er * ar + ei * ai;
                    im += er * ai - ei * ar;
                }
                want += re * re + im * im;
            }
            let got = f64::from(proj[k * nd_pad + d]);
            worst = worst.max((got - want).abs());
        }
    }
    // Values are O(1); 33 f32 recurrence steps keep the phasors within 1e-5.
    assert!(worst < 1e-4, "largest difference {worst}");
}

/// The whole estimator against MUSIC computed directly in f64: per group the sample
/// covariance, its eigen-decomposition, the signal subspace estimated by the 10-dB rule,
/// `1 / (1 - |E_s^H a|^2 / M)` on every direction, NormMUSIC's per-group normalisation,
/// the mean over groups. Four sources of unequal power on six microphones (so most
/// groups hold a 4-dimensional signal subspace, and the estimator projects on the
/// 2-dimensional noise subspace instead), two sources (it projects on the signal
/// subspace), and one: the pseudo-spectrum is the same either way. The same on the
/// 4-microphone ReSpeaker (three sources: the noise subspace), whose broad peaks make
/// f32 less precise near a two-source spectrum's maxima (`1 - |E_s^H a|^2 / M` there is
/// a difference of nearly equal numbers).
#[test]
fn projecting_on_the_smaller_subspace_gives_musics_pseudo_spectrum() {
    let six = [(4usize, true), (2, false), (1, false)];
    let robot = DirectionGrid::new(5.0, ElevationRange::ROBOT).unwrap();
    check_against_f64_music(&MicArray::default(), &robot, &six, 1e-3);
    let four = [(3usize, true), (2, false), (1, false)];
    let respeaker = MicArray::preset("respeaker4").unwrap();
    check_against_f64_music(&respeaker, &robot, &four, 5e-3);
    // A grid without every antipode (elevations -20..40): every direction steered. Its
    // directions pass closer to the two sources' peak, where f32 is within 1.5e-3.
    let upward = ElevationRange {
        min_deg: -20.0,
        max_deg: 40.0,
        step_deg: 10.0,
    };
    let upward = DirectionGrid::new(5.0, upward).unwrap();
    check_against_f64_music(&MicArray::default(), &upward, &six[1..], 2e-3);
}

/// [`projecting_on_the_smaller_subspace_gives_musics_pseudo_spectrum`] on one array and
/// grid: for each `(sources, projects on the noise subspace)`, the estimator block by
/// block and all blocks at once against the f64 reference, within `tol`.
fn check_against_f64_music(
    array: &MicArray,
    grid: &DirectionGrid,
    cases: &[(usize, bool)],
    tol: f64,
) {
    use nalgebra::{Complex as C, DMatrix as M};
    let array = array.clone();
    let (fs, c, frame_len, bins) = (16_000.0, 343.0, 512, 100..140);
    let music = plan(&array, grid, (fs, c), bins.clone(), frame_len, None);
    let m = array.len();
    // The steering phasor of direction `u` at FFT bin `bin`, microphone `mic`.
    let steer = |u: [f64; 3], bin: f64, mic: usize| {
        let w = std::f64::consts::TAU * bin / frame_len as f64;
        let (re, im) = phasor(&array, mic, u, w, (fs, c));
        C::new(re, im)
    };
    let mut rnd = lcg(11);
    for &(sources, used_noise) in cases {
        let dirs: Vec<[f64; 3]> = (0..sources)
            .map(|s| grid.unit((s * 997 + 131) % grid.len()))
            .collect();
        let (frames, nb) = (12, bins.len());
        let mut data = vec![Complex32::default(); frames * m * nb];
        for f in 0..frames {
            for b in 0..nb {
                let amp: Vec<C<f64>> = (0..sources)
                    .map(|s| C::new(rnd(), rnd()) * (1.0 - 0.1 * s as f64))
                    .collect();
                for mic in 0..m {
                    let mut x = C::new(0.05 * rnd(), 0.05 * rnd());
                    for (s, u) in dirs.iter().enumerate() {
                        x += amp[s] * steer(*u, (bins.start + b) as f64, mic);
                    }
                    data[(f * m + mic) * nb + b] = Complex32::new(x.re as f32, x.im as f32);
                }
            }
        }
        let spec = Spectrogram::from_parts(frames, m, bins.clone(), data.clone());
        let mut got = vec![0.0f32; grid.len()];
        let mut scratch = MethodScratch::default();
        music.estimate_into(&spec, 0..frames, &mut got, &mut scratch);
        let s = &scratch.subspace;
        assert_eq!(
            s.signal.iter().any(|&x| !x),
            used_noise,
            "{sources} sources: subspaces {:?} {:?}",
            s.used,
            s.signal
        );
        // The reference, in f64.
        let mut want = vec![0.0f64; grid.len()];
        let ng = music.centres.len();
        for &centre in &music.centres {
            let mut cov = M::<C<f64>>::zeros(m, m);
            for f in 0..frames {
                for b in centre - 2..=centre + 2 {
                    for i in 0..m {
                        for j in 0..m {
                            let xi = data[(f * m + i) * nb + b];
                            let xj = data[(f * m + j) * nb + b];
                            cov[(i, j)] += C::new(f64::from(xi.re), f64::from(xi.im))
                                * C::new(f64::from(xj.re), -f64::from(xj.im));
                        }
                    }
                }
            }
            let eig = nalgebra::SymmetricEigen::new(cov);
            let mut order: Vec<usize> = (0..m).collect();
            order.sort_by(|&x, &y| eig.eigenvalues[y].total_cmp(&eig.eigenvalues[x]));
            let top = eig.eigenvalues[order[0]];
            let k = 1 + order[1..music.sources]
                .iter()
                .take_while(|&&e| eig.eigenvalues[e] >= 0.1 * top)
                .count();
            let bin = (bins.start + centre) as f64;
            let p: Vec<f64> = (0..grid.len())
                .map(|d| {
                    let u = grid.unit(d);
                    let proj: f64 = order[..k]
                        .iter()
                        .map(|&e| {
                            (0..m)
                                .map(|mic| eig.eigenvectors[(mic, e)].conj() * steer(u, bin, mic))
                                .sum::<C<f64>>()
                                .norm_sqr()
                        })
                        .sum();
                    1.0 / (1.0 - proj / m as f64).max(f64::from(FLOOR))
                })
                .collect();
            let max = p.iter().copied().fold(0.0, f64::max);
            for (w, v) in want.iter_mut().zip(&p) {
                *w += v / max / ng as f64;
            }
        }
        let worst = got
            .iter()
            .zip(&want)
            .map(|(&g, &w)| (f64::from(g) - w).abs())
            .fold(0.0, f64::max);
        // Values lie in (0, 1]; f32 sums and decompositions keep them within `tol`.
        assert!(worst < tol, "{sources} sources: largest difference {worst}");
        // All blocks at once (the projectors' pair terms, `Music::all_blocks`): the
        // whole recording against the reference, its halves against their own
        // block-by-block spectra.
        let blocks = [0..frames, 0..frames / 2, frames / 2..frames];
        let mut each: Vec<Vec<f32>> = Vec::new();
        let mut buf = vec![0.0f32; grid.len()];
        music.estimate_blocks(&spec, &blocks, &mut buf, &mut scratch, &mut |i, v| {
            assert_eq!(i, each.len(), "blocks in order");
            each.push(v.to_vec());
        });
        assert_eq!(each.len(), 3);
        let diff = |a: &[f32], b: &mut dyn Iterator<Item = f64>| {
            a.iter()
                .zip(b)
                .map(|(&x, y)| (f64::from(x) - y).abs())
                .fold(0.0, f64::max)
        };
        let worst = diff(&each[0], &mut want.iter().copied());
        assert!(worst < tol, "{sources} sources, all blocks: {worst}");
        for (i, frames) in blocks.iter().enumerate().skip(1) {
            music.estimate_into(&spec, frames.clone(), &mut buf, &mut scratch);
            let worst = diff(&each[i], &mut buf.iter().map(|&v| f64::from(v)));
            assert!(worst < tol, "{sources} sources, block {i}: {worst}");
        }
    }
}

/// The parts of the band summed in the band's own pass
/// ([`SpectrumEstimator::estimate_blocks_parts`]) are the spectra of plans of those
/// groups alone, scaled by their share of the band's groups, at the directions asked
/// for; and the band's spectrum is what it is without them. On a grid steered by halves
/// and on one steered whole.
#[test]
fn a_parts_spectrum_is_that_of_its_groups_alone() {
    let array = MicArray::default();
    let (fs, c, frame_len) = (16_000.0, 343.0, 512);
    // Groups of 5 bins (F = 2): the band's 20 groups, 6 in the first part, 11 in the
    // second, 3 in neither.
    let band = 20..120;
    let parts = [10..40, 40..95];
    let m = array.len();
    let mut rnd = lcg(5);
    let (frames, nb) = (12, band.len());
    let data: Vec<Complex32> = (0..frames * m * nb)
        .map(|_| Complex32::new(rnd() as f32, rnd() as f32))
        .collect();
    let spec = Spectrogram::from_parts(frames, m, band.clone(), data);
    let blocks = [0..5, 5..12];
    for (el, az) in [
        (ElevationRange::ROBOT, 5.0),
        (ElevationRange::PLANE, 360.0 / 7.0),
    ] {
        let grid = DirectionGrid::new(az, el).unwrap();
        let music = plan(&array, &grid, (fs, c), band.clone(), frame_len, None);
        let dirs: Vec<usize> = (0..grid.len()).step_by(3).collect();
        let (mut alone, mut with_parts) = (Vec::new(), Vec::new());
        let mut buf = vec![0.0f32; grid.len()];
        let mut scratch = MethodScratch::default();
        music.estimate_blocks(&spec, &blocks, &mut buf, &mut scratch, &mut |_, v| {
            alone.push(v.to_vec())
        });
        let gave = music.estimate_blocks_parts(
            &spec,
            &blocks,
            &parts,
            &mut buf,
            &mut scratch,
            &mut |_, v| with_parts.push(v.to_vec()),
        );
        assert!(gave);
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs());
        for (a, b) in alone.iter().flatten().zip(with_parts.iter().flatten()) {
            assert!(close(*a, *b), "the band: {a} against {b}");
        }
        for (p, part) in parts.iter().enumerate() {
            let bins = band.start + part.start..band.start + part.end;
            let own = plan(&array, &grid, (fs, c), bins.clone(), frame_len, None);
            let share = own.centres.len() as f32 / music.centres.len() as f32;
            assert_eq!((own.centres.len(), music.centres.len()), ([6, 11][p], 20));
            let mut sub = Spectrogram::default();
            spec.band_into(bins, &mut sub);
            // Read before and after the part's own plan runs on the same scratch: a
            // pass without parts leaves them.
            let mut part_out = Vec::new();
            music.part_spectra(p, &dirs, &mut scratch, &mut part_out);
            let mut want = Vec::new();
            own.estimate_blocks(&sub, &blocks, &mut buf, &mut scratch, &mut |_, v| {
                want.push(v.to_vec())
            });
            let mut again = Vec::new();
            music.part_spectra(p, &dirs, &mut scratch, &mut again);
            assert_eq!(part_out, again);
            assert_eq!(part_out.len(), blocks.len() * dirs.len());
            for (b, want) in want.iter().enumerate() {
                let at = b * dirs.len();
                for (i, &d) in dirs.iter().enumerate() {
                    let got = part_out[at + i];
                    assert!(
                        close(got, want[d] * share),
                        "part {p} block {b} direction {d}"
                    );
                }
            }
        }
    }
}

/// The steered half of a symmetric grid and its antipodes cover every direction once,
/// each antipode at `-u`; a grid without every antipode is steered whole.
#[test]
fn a_symmetric_grid_is_steered_by_halves() {
    let array = MicArray::default();
    let (fs, c) = (16_000.0, 343.0);
    let range = |min_deg, max_deg| ElevationRange {
        min_deg,
        max_deg,
        step_deg: 10.0,
    };
    for (el, az, symmetric) in [
        (ElevationRange::ROBOT, 1.0, true),
        (ElevationRange::PLANE, 5.0, true),
        (range(-20.0, 20.0), 10.0, true),
        (range(-30.0, 20.0), 10.0, false),
        (range(-20.0, 40.0), 5.0, false),
        (ElevationRange::PLANE, 360.0 / 7.0, false),
    ] {
        let grid = DirectionGrid::new(az, el).unwrap();
        let music = plan(&array, &grid, (fs, c), 10..30, 512, None);
        let Some(h) = &music.antipodes else {
            assert!(!symmetric, "{el:?} by {az}: steered whole");
            continue;
        };
        assert!(symmetric, "{el:?} by {az}: halved");
        let mut seen = vec![false; grid.len()];
        for (slot, &d) in h.order.iter().enumerate() {
            assert!(!std::mem::replace(&mut seen[d], true), "{d} twice");
            assert_eq!(h.slot_of[d], slot, "the inverse order");
        }
        assert!(seen.iter().all(|&s| s), "every direction");
        let half = grid.len() / 2;
        for k in 0..half {
            let (u, v) = (grid.unit(h.order[k]), grid.unit(h.order[half + k]));
            assert!((0..3).all(|a| (u[a] + v[a]).abs() < 1e-9), "{u:?} {v:?}");
        }
    }
}

/// The covariance summed a row at a time (up to 8 microphones) and entry by entry
/// (more) against a direct f64 sum of `x x^H`.
#[test]
fn the_covariance_is_the_sum_of_outer_products() {
    use nalgebra::Complex as C;
    for m in [4, 6, 8, 10] {
        let (frames, bins) = (7, 9);
        let mut rnd = lcg(m as u64);
        let data: Vec<Complex32> = (0..frames * m * bins)
            .map(|_| Complex32::new(rnd() as f32, rnd() as f32))
            .collect();
        let spec = Spectrogram::from_parts(frames, m, 20..20 + bins, data.clone());
        let mut cov = DMatrix::<Complex32>::zeros(m, m);
        covariance(&spec, 2..6, 3..8, &mut cov);
        for i in 0..m {
            for j in i..m {
                let mut want = C::<f64>::default();
                for f in 2..6 {
                    for b in 3..8 {
                        let (x, y) = (data[(f * m + i) * bins + b], data[(f * m + j) * bins + b]);
                        want += C::new(f64::from(x.re), f64::from(x.im))
                            * C::new(f64::from(y.re), -f64::from(y.im));
                    }
                }
                let got = cov[(i, j)];
                let err = (f64::from(got.re) - want.re).abs() + (f64::from(got.im) - want.im).abs();
                assert!(err < 1e-5, "{m} mics, ({i}, {j}): {got} against {want}");
            }
        }
    }
}

#[test]
fn the_subspace_is_capped_below_the_number_of_microphones() {
    let array = MicArray::preset("respeaker4").unwrap();
    let grid = DirectionGrid::new(10.0, ElevationRange::PLANE).unwrap();
    let m = Music::new(
        &array,
        &grid,
        16_000.0,
        343.0,
        7..256,
        512,
        subspace(Some(9)),
    );
    assert_eq!(m.sources(), Some(3));
    let m = Music::new(&array, &grid, 16_000.0, 343.0, 7..256, 512, subspace(None));
    assert_eq!(m.sources(), None);
}

/// MUSIC's floor is the residual that a source's own steering vector leaves in the noise
/// subspace estimated from `S` snapshots. Measured here by drawing them: a plane wave of
/// random phases (any unit-modulus vector is some direction's steering vector) in white
/// noise at each of six microphones, one source, 400 draws per case; the mean of the
/// residual `1 - |e_1^H a|^2 / M` and the mean of [`Music::resolution`] from the same
/// eigenvalues agree within a factor of 1.5, at 4 snapshots (a block's, fewer than
/// microphones) and at 16, from 0 to 20 dB per microphone (measured over predicted:
/// 0.70-0.83 at 4 snapshots, 1.06-1.08 at 16; numpy with 2000 draws, 0.73-0.79 and
/// 1.07-1.10). The first-order formula without its `(r - 1)^2` gives 1.1-1.5 at 16.
#[test]
fn musics_floor_is_the_residual_its_snapshots_leave() {
    let array = MicArray::default();
    let grid = DirectionGrid::new(10.0, ElevationRange::PLANE).unwrap();
    let music = Subspace {
        sources: Some(1),
        max_sources: 4,
        smoothing: 0,
        normalise: false,
    };
    let m = array.len();
    let music = Music::new(&array, &grid, 16_000.0, 343.0, 7..256, 512, music);
    let mut uniform = lcg(52);
    // A standard complex Gaussian (unit power), by Box-Muller.
    let mut gauss = move || {
        let (u, v) = (uniform() + 0.5, uniform() + 0.5);
        let r = (-u.max(1e-12).ln()).sqrt();
        let t = std::f64::consts::TAU * v;
        Complex::new(r * t.cos(), r * t.sin())
    };
    for snapshots in [4, 16] {
        for snr_db in [0.0, 10.0, 20.0] {
            let amp = 10f64.powf(snr_db / 20.0);
            let (mut measured, mut predicted) = (0.0, 0.0);
            for _ in 0..400 {
                let a: Vec<Complex<f64>> = (0..m)
                    .map(|_| {
                        let g = gauss();
                        g / g.norm()
                    })
                    .collect();
                let mut cov = DMatrix::<Complex<f64>>::zeros(m, m);
                for _ in 0..snapshots {
                    let s = gauss() * amp;
                    let x: Vec<Complex<f64>> = a.iter().map(|&ai| ai * s + gauss()).collect();
                    for i in 0..m {
                        for j in 0..m {
                            cov[(i, j)] += x[i] * x[j].conj();
                        }
                    }
                }
                let eig = SymmetricEigen::new(cov);
                let mut order: Vec<usize> = (0..m).collect();
                order.sort_by(|&x, &y| eig.eigenvalues[y].total_cmp(&eig.eigenvalues[x]));
                let e = eig.eigenvectors.column(order[0]);
                let along: Complex<f64> = e.iter().zip(&a).map(|(ei, ai)| ei.conj() * ai).sum();
                measured += 1.0 - along.norm_sqr() / m as f64;
                let vals: Vec<f32> = eig.eigenvalues.iter().map(|&v| v as f32).collect();
                predicted += f64::from(music.resolution(&vals, &order, 1, snapshots));
            }
            let ratio = measured / predicted;
            assert!(
                (0.67..1.5).contains(&ratio),
                "{snapshots} snapshots, {snr_db} dB: measured {:.4}, predicted {:.4} (ratio {ratio:.2})",
                measured / 400.0,
                predicted / 400.0
            );
        }
    }
}
