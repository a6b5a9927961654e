//! Benchmarks of the mapper: DBSCAN and one filter step across sizes, and a whole I-ASM
//! map of an arrangement-II-like scene across particle counts and stop counts.
//!
//! `cargo bench -p iasm-asm`; figures go to `BENCHMARKS.md`.

// criterion_group!/criterion_main! generate undocumented items (criterion.rs #774/#775).
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use iasm_asm::dbscan::dbscan;
use iasm_asm::map::{Cell, OccupancyMap};
use iasm_asm::pf::{Likelihood, ParticleFilter};
use iasm_asm::{IasmConfig, MapRng, Mapper, Pose, wrap_rad};
use rand::{Rng, SeedableRng, rngs::StdRng};

const SEED: u64 = 23;

/// A 16 x 12.8 m map (320 x 256 cells at 0.05 m, as arrangement II's), all known; ten
/// sources in two rows 1.2 m apart; `k` stops along the middle; DoAs exact but for
/// 2-degree noise, one false DoA in four.
fn scene(k: usize) -> (OccupancyMap, Vec<Pose>, Vec<Vec<f64>>) {
    let mut rng = StdRng::seed_from_u64(SEED);
    let map = OccupancyMap::new(320, 256, 0.05, [-4.0, -5.0], vec![Cell::Free; 320 * 256]);
    let truth: Vec<[f64; 2]> = (0..10)
        .map(|i| {
            [
                1.25 * (1 + i / 2) as f64,
                if i % 2 == 0 { 0.6 } else { -0.6 },
            ]
        })
        .collect();
    let poses: Vec<Pose> = (0..k)
        .map(|i| Pose {
            x: 7.0 * i as f64 / k as f64,
            y: 0.0,
            theta: 0.1 * i as f64,
        })
        .collect();
    let doas = poses
        .iter()
        .map(|p| {
            let mut row: Vec<f64> = (0..3)
                .map(|_| {
                    let s = truth[rng.random_range(0..truth.len())];
                    wrap_rad(
                        (s[1] - p.y).atan2(s[0] - p.x) - p.theta + rng.random_range(-0.035..0.035),
                    )
                })
                .collect();
            row.push(rng.random_range(-std::f64::consts::PI..std::f64::consts::PI));
            row
        })
        .collect();
    (map, poses, doas)
}

fn bench_dbscan(c: &mut Criterion) {
    let mut g = c.benchmark_group("asm/dbscan");
    for &n in &[1000usize, 4200, 16_000] {
        let mut rng = StdRng::seed_from_u64(SEED);
        // A converged cloud: half the points in a 0.3 m blob, the rest spread over 10 m.
        let pts: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    [rng.random_range(0.0..0.3), rng.random_range(0.0..0.3)]
                } else {
                    [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)]
                }
            })
            .collect();
        g.bench_with_input(BenchmarkId::from_parameter(n), &pts, |b, p| {
            b.iter(|| dbscan(black_box(p), 0.1, n / 10))
        });
    }
    g.finish();
}

fn bench_pf_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("asm/pf-step");
    let lik = Likelihood::new(5f64.to_radians(), Some(2.5));
    for &m in &[1000usize, 4200, 16_000] {
        // The generator the pipeline's maps use (its normal deviates are the step's cost).
        let mut rng = MapRng::seed_from_u64(SEED);
        let cells: Vec<[f64; 2]> = (0..m)
            .map(|_| [rng.random_range(-4.0..12.0), rng.random_range(-5.0..7.8)])
            .collect();
        let pf0 = ParticleFilter::from_cells(&cells, m, &mut rng);
        g.bench_with_input(BenchmarkId::from_parameter(m), &pf0, |b, pf0| {
            b.iter_batched(
                || pf0.clone(),
                |mut pf| {
                    pf.predict(0.01, &mut rng);
                    pf.update([1.0, 0.0], &[0.3, 1.2, -2.0, 2.9], &lik);
                    if pf.neff() < m as f64 / 10.0 {
                        pf.resample(&mut rng);
                    }
                    pf.max_cov_eigenvalue()
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

fn bench_map(c: &mut Criterion) {
    let mut g = c.benchmark_group("asm/map");
    g.sample_size(10);
    // Particle count: D = 36, 9 (the paper's, M = 9102 here), 3.
    let (map, poses, doas) = scene(40);
    for d in [36.0, 9.0, 3.0] {
        let mapper = Mapper::new(
            &map,
            &IasmConfig {
                density_d: d,
                ..IasmConfig::default()
            },
        )
        .unwrap();
        g.bench_function(BenchmarkId::new("K40-M", mapper.num_particles()), |b| {
            b.iter(|| {
                mapper
                    .run(&poses, &doas, &mut MapRng::seed_from_u64(SEED))
                    .unwrap()
            })
        });
    }
    // Stop count at the paper's density.
    for k in [20usize, 71] {
        let (map, poses, doas) = scene(k);
        let mapper = Mapper::new(&map, &IasmConfig::default()).unwrap();
        g.bench_function(BenchmarkId::new("M9102-K", k), |b| {
            b.iter(|| {
                mapper
                    .run(&poses, &doas, &mut MapRng::seed_from_u64(SEED))
                    .unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_dbscan, bench_pf_step, bench_map);
criterion_main!(benches);
