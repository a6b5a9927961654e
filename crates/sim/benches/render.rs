//! Benchmarks of the room renderer on the arrangement-I-like scene
//! (`fixtures/bench/arrangement_i.toml`: 11 x 10 x 3 m, RT60 0.5 s, ten sources, the iasm6
//! array, 3 s at 48 kHz): preparing the renderer (images, signal spectra), one stop (six
//! microphones), and one source-to-microphone response; and one stop of a floor plan
//! (`fixtures/heldout/l_west_wing.toml`: an L, RT60 0.7 s, three sources, 16 kHz), whose
//! time is the images' paths and the diffuse tail rather than the impulses.
//!
//! `cargo bench -p iasm-sim`; the whole 71-stop scene is timed with `iasm simulate` beside
//! pyroomacoustics (`scripts/pra_render_bench.py`); figures go to `BENCHMARKS.md`.

// criterion_group!/criterion_main! generate undocumented items (criterion.rs #774/#775).
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use iasm_sim::ism::{add_images, image_sources};
use iasm_sim::scene::{PreparedScene, Scene, mic_world};

fn scene() -> PreparedScene {
    load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/bench/arrangement_i.toml"
    ))
}

/// A scene file, less the suite's `[expect]` table (its thresholds, which `iasm regress`
/// reads).
fn load(path: &str) -> PreparedScene {
    let text = std::fs::read_to_string(path).expect("bench scene in the repository");
    let mut table: toml::Table = text.parse().expect("bench scene is TOML");
    table.remove("expect");
    let text = table.to_string();
    Scene::from_toml(&text)
        .expect("bench scene parses")
        .prepare(|name| {
            ssl::MicArray::preset(name)
                .ok()
                .map(|a| a.positions().to_vec())
        })
        .expect("bench scene is valid")
}

fn benches(c: &mut Criterion) {
    let sc = scene();
    let mut g = c.benchmark_group("render");
    g.sample_size(10);
    g.bench_function("arrangement_i/one_stop", |b| {
        sc.renderer(); // built once, as across the stops of a scene
        b.iter(|| black_box(sc.render_stop(black_box(35))));
    });
    g.bench_function("arrangement_i/prepare", |b| {
        b.iter(|| black_box(scene().renderer().image_counts()));
    });
    let fs = f64::from(sc.scene.fs);
    let mic = mic_world(sc.stops[35], sc.scene.array.height, sc.mics[0]);
    let iasm_sim::Space::Shoebox(room) = &sc.room else {
        panic!("the bench scene is a shoebox")
    };
    let images = image_sources(room, sc.scene.sources[0].pos, mic, 0.5 * 343.0, None);
    g.bench_function("arrangement_i/one_response", |b| {
        let mut h = vec![0.0; (0.5 * fs) as usize];
        b.iter(|| {
            h.fill(0.0);
            add_images(&mut h, black_box(&images), mic, fs, 343.0);
            black_box(h[100])
        });
    });
    let plan = load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/heldout/l_west_wing.toml"
    ));
    let middle = plan.stops.len() / 2;
    g.bench_function("l_west_wing/one_stop", |b| {
        plan.renderer(); // built once, as across the stops of a scene
        b.iter(|| black_box(plan.render_stop(black_box(middle))));
    });
    g.finish();
}

criterion_group!(render, benches);
criterion_main!(render);
