//! TOPS, CSSM and WAVES against their definitions written out and known directions.

use super::*;
use crate::grid::{ElevationRange, unit_vector};
use crate::method::lcg;

const FS: f64 = 48_000.0;
const C: f64 = 343.0;
const FRAME: usize = 1024;
const BINS: (usize, usize) = (5, 171);

/// A spectrogram of plane waves from `sources` (azimuth, elevation in degrees; powers),
/// each an independent complex Gaussian-like amplitude per frame and bin, plus
/// independent noise of power `noise` at every microphone: the narrowband model every
/// subspace method assumes, exactly.
fn plane_waves(
    array: &MicArray,
    sources: &[(f64, f64, f64)],
    frames: usize,
    noise: f64,
) -> Spectrogram {
    let pos = array.positions();
    let m = pos.len();
    let centroid: [f64; 3] =
        std::array::from_fn(|a| pos.iter().map(|p| p[a]).sum::<f64>() / m as f64);
    let nb = BINS.1 - BINS.0;
    let mut rnd = lcg(11);
    let mut data = vec![Complex32::default(); frames * m * nb];
    for f in 0..frames {
        for b in 0..nb {
            let w = std::f64::consts::TAU * (BINS.0 + b) as f64 / FRAME as f64;
            let amps: Vec<C64> = sources
                .iter()
                .map(|s| C64::new(rnd(), rnd()) * s.2.sqrt())
                .collect();
            for mic in 0..m {
                let mut x = C64::new(rnd(), rnd()) * noise.sqrt();
                for (s, amp) in sources.iter().zip(&amps) {
                    let u = unit_vector(s.0, s.1);
                    let lead = (0..3)
                        .map(|a| (pos[mic][a] - centroid[a]) * u[a])
                        .sum::<f64>()
                        / C
                        * FS;
                    x += amp * C64::from_polar(1.0, w * lead);
                }
                data[(f * m + mic) * nb + b] = Complex32::new(x.re as f32, x.im as f32);
            }
        }
    }
    Spectrogram::from_parts(frames, m, BINS.0..BINS.1, data)
}

fn band(sources: Option<usize>) -> Band {
    Band {
        fs: FS,
        c: C,
        bins: BINS,
        frame_len: FRAME,
        sources,
        max_sources: 4,
        min_sep_deg: 10.0,
    }
}

/// The azimuth and elevation (degrees) of grid direction `d`.
fn az_el(grid: &DirectionGrid, d: usize) -> (f64, f64) {
    let n = grid.num_azimuths();
    (grid.azimuths()[d % n], grid.elevations()[d / n])
}

/// TOPS written out as Yoon, Kaplan & McClellan define it (without the projection, see
/// the module's docs), in f64, on every direction: `U_b = Phi_b(u) F_0`,
/// `D = [U_b^H W_b]` over every bin but the reference, each `W_b` from that bin's own
/// eigen-decomposition, and `1 / sigma_min(D)`. The estimator's pair sums and `K x K` eigenvalue
/// give the same spectrum, for `K` of 1, 2, 3 and (unset) N = 4.
#[test]
fn tops_is_its_definition_written_out() {
    let array = MicArray::default();
    let grid = DirectionGrid::new(10.0, ElevationRange::ROBOT).unwrap();
    let spec = plane_waves(&array, &[(40.0, -20.0, 1.0), (-100.0, 10.0, 0.5)], 40, 0.05);
    for sources in [None, Some(1), Some(2), Some(3)] {
        let tops = Tops::new(Plan::new(&array, &grid, band(sources)), &grid);
        let mut got = vec![0.0f32; grid.len()];
        tops.estimate_into(&spec, 0..40, &mut got, &mut MethodScratch::default());
        let p = &tops.plan;
        let covs = p.covariances(&spec, 0..40);
        let sub = tops.subspaces(&covs).unwrap();
        let (m, k) = (array.len(), sub.f0.ncols());
        assert_eq!(k, sources.unwrap_or(4), "K unset is N");
        let mut a0 = vec![C64::default(); m];
        let mut ab = vec![C64::default(); m];
        for (d, &got_d) in got.iter().enumerate() {
            p.steer(d, sub.b0, &mut a0);
            let mut cols: Vec<C64> = Vec::new();
            let mut n_cols = 0;
            for (b, r) in covs.iter().enumerate() {
                if b == sub.b0 {
                    continue;
                }
                p.steer(d, b, &mut ab);
                let phi = Mat::from_fn(m, m, |i, j| {
                    if i == j {
                        ab[i] / a0[i]
                    } else {
                        C64::default()
                    }
                });
                let u = phi * &sub.f0;
                let (_, vecs) = eigh_desc(r);
                let w = vecs.columns(k, m - k);
                let block = u.adjoint() * w;
                cols.extend(block.iter());
                n_cols += m - k;
            }
            let dmat = Mat::from_column_slice(k, n_cols, &cols);
            // sigma_min(D)^2 is the least eigenvalue of D D^H (nalgebra's complex SVD does
            // not always converge, dimforge/nalgebra#1172).
            let smin = SymmetricEigen::new(&dmat * dmat.adjoint())
                .eigenvalues
                .min()
                .sqrt();
            let want = 1.0 / smin;
            let rel = (f64::from(got_d) - want).abs() / want;
            assert!(
                rel < 2e-3,
                "K {sources:?}, {:?}: {} against {want} ({rel})",
                az_el(&grid, d),
                got_d
            );
        }
    }
}

/// A focusing matrix is unitary (white noise stays white), maps a single direction's
/// steering vector at its bin exactly onto its own at the reference bin, and for several
/// directions is the unitary matrix that maps them best (orthogonal Procrustes): no
/// other unitary matrix tried brings `T A_b` nearer to `A_0`.
#[test]
fn focusing_is_the_unitary_map_of_the_directions_onto_the_reference_bin() {
    let array = MicArray::default();
    let grid = DirectionGrid::new(5.0, ElevationRange::ROBOT).unwrap();
    let plan = Plan::new(&array, &grid, band(None));
    let lags = Arc::new(PairLags::new(&array, &grid, FS, C, BINS.0..BINS.1, FRAME));
    let cssm = Focused::new(plan.clone(), lags, false, 4);
    let m = array.len();
    let steering = |dirs: &[usize], b: usize| {
        let mut a = Mat::zeros(m, dirs.len());
        let mut col = vec![C64::default(); m];
        for (j, &d) in dirs.iter().enumerate() {
            plan.steer(d, b, &mut col);
            a.column_mut(j).copy_from_slice(&col);
        }
        a
    };
    let mut rnd = lcg(5);
    for b in [0, 40, 165] {
        let one = cssm.focusing(&[300], b, 90).unwrap();
        let e1 = (&one * steering(&[300], b) - steering(&[300], 90)).norm();
        assert!(e1 < 1e-6, "one direction, bin {b}: {e1}");
        let beta = [7usize, 300, 555];
        let t = cssm.focusing(&beta, b, 90).unwrap();
        assert!(
            (t.adjoint() * &t - Mat::identity(m, m)).norm() < 1e-6,
            "unitary"
        );
        let (ab, a0) = (steering(&beta, b), steering(&beta, 90));
        let best = (&t * &ab - &a0).norm();
        for _ in 0..20 {
            let x = Mat::from_fn(m, m, |_, _| C64::new(rnd(), rnd()));
            let q = x.qr().q();
            assert!(best <= (&q * &ab - &a0).norm() + 1e-6, "bin {b}");
        }
    }
}

/// Each method's strongest peaks are the sources' directions (to within the grid's 2
/// degrees, azimuth and elevation within 10), `K` set to their number, SNR 10 dB: two
/// sources 3 dB apart for all three, and a third 5 dB below the first for TOPS. CSSM and
/// WAVES find what their preliminary directions let them focus on, and SRP-PHAT's
/// whitening gives every bin to its strongest source, so a third that never dominates a
/// bin is not among them; TOPS needs no preliminary directions.
#[test]
fn each_method_finds_plane_waves() {
    let array = MicArray::default();
    let grid = DirectionGrid::new(2.0, ElevationRange::ROBOT).unwrap();
    let lags = || Arc::new(PairLags::new(&array, &grid, FS, C, BINS.0..BINS.1, FRAME));
    let three = [(40.0, -20.0, 1.0), (-100.0, 10.0, 0.5), (160.0, -30.0, 0.3)];
    for truth in [&three[..2], &three[..]] {
        let spec = plane_waves(&array, truth, 60, 0.03);
        let plan = || Plan::new(&array, &grid, band(Some(truth.len())));
        let mut methods: Vec<Box<dyn SpectrumEstimator>> = vec![Box::new(Tops::new(plan(), &grid))];
        if truth.len() == 2 {
            methods.push(Box::new(Focused::new(plan(), lags(), false, 4)));
            methods.push(Box::new(Focused::new(plan(), lags(), true, 4)));
        }
        for est in methods {
            let mut out = vec![0.0f32; grid.len()];
            est.estimate_into(&spec, 0..60, &mut out, &mut MethodScratch::default());
            let peaks = plan().peaks(&out, truth.len());
            for &(az, el, _) in truth {
                let hit = peaks.iter().any(|&d| {
                    let (a, e) = az_el(&grid, d);
                    crate::spectrum::wrap_deg(a - az).abs() <= 2.0 && (e - el).abs() <= 10.0
                });
                let found: Vec<_> = peaks.iter().map(|&d| az_el(&grid, d)).collect();
                assert!(hit, "{}: ({az}, {el}) not among {found:?}", est.name());
            }
        }
    }
}
