//! Benchmarks of the SSL front end: one whole recording (file read included) per method,
//! the STFT across frame lengths, one block's spectrum across grids, and deflation's cost
//! on a compact array.
//!
//! `cargo bench -p iasm-ssl`; figures go to `BENCHMARKS.md`.

// criterion_group!/criterion_main! generate undocumented items (criterion.rs #774/#775).
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use iasm_ssl::{Audio, Localizer, Method, MicArray, SslConfig, Stft};
use sim::farfield::{PlaneWave, render};
use sim::signal::Signal;

const SEED: u64 = 11;
const FS: u32 = 48_000;

/// A paper-like recording: 3 s, 6 channels, 48 kHz, four sources (two voiced).
fn recording(seconds: f64) -> Vec<Vec<f64>> {
    let waves: Vec<PlaneWave> = [
        (-120.0, Signal::Noise),
        (-20.0, Signal::Harmonic(130.0)),
        (45.0, Signal::Noise),
        (150.0, Signal::Harmonic(210.0)),
    ]
    .iter()
    .map(|&(azimuth_deg, signal)| PlaneWave {
        azimuth_deg,
        elevation_deg: 0.0,
        signal,
    })
    .collect();
    let array = MicArray::default();
    render(
        array.positions(),
        &waves,
        FS,
        (seconds * f64::from(FS)) as usize,
        343.0,
        Some(20.0),
        SEED,
    )
}

fn write_wav(path: &std::path::Path, channels: &[Vec<f64>]) {
    let spec = hound::WavSpec {
        channels: channels.len() as u16,
        sample_rate: FS,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(path, spec).unwrap();
    for t in 0..channels[0].len() {
        for ch in channels {
            w.write_sample((ch[t] * 3000.0) as i16).unwrap();
        }
    }
    w.finalize().unwrap();
}

fn whole_recording(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let wav = dir.path().join("rec.wav");
    write_wav(&wav, &recording(3.0));
    let array = MicArray::default();
    let mut g = c.benchmark_group("ssl/recording-3s-6ch-48k");
    g.sample_size(30);
    g.bench_function("read-wav", |b| {
        b.iter(|| iasm_ssl::read_wav(black_box(&wav)).unwrap())
    });
    for method in Method::ALL {
        let loc = Localizer::new(
            &array,
            FS,
            &SslConfig {
                method,
                ..SslConfig::default()
            },
        )
        .unwrap();
        g.bench_function(BenchmarkId::new("read+locate", method), |b| {
            b.iter(|| {
                loc.locate(&iasm_ssl::read_wav(black_box(&wav)).unwrap())
                    .unwrap()
            })
        });
    }
    g.finish();
}

/// Deflation's cost where it is meant to run: the ReSpeaker 4-mic hearing two talkers,
/// 2 s at 16 kHz, N = 2 (the row holds both and is not cut), with and without it.
fn deflation(c: &mut Criterion) {
    const RATE: u32 = 16_000;
    let array = MicArray::preset("respeaker4").unwrap();
    let n = 2 * RATE as usize;
    // (azimuth, amplitude) of each talker, each rendered with its own seed and noise.
    let talkers = [(90.0, 1.0), (30.0, 0.7)];
    let mut channels = vec![vec![0.0f32; n]; array.positions().len()];
    for (k, &(azimuth_deg, gain)) in talkers.iter().enumerate() {
        let wave = PlaneWave {
            azimuth_deg,
            elevation_deg: 0.0,
            signal: Signal::SpeechShaped,
        };
        let mics = render(
            array.positions(),
            &[wave],
            RATE,
            n,
            343.0,
            Some(30.0),
            SEED + k as u64,
        );
        for (out, mic) in channels.iter_mut().zip(mics) {
            for (o, x) in out.iter_mut().zip(mic) {
                *o += (0.1 * gain * x) as f32;
            }
        }
    }
    let audio = Audio::new(RATE, channels).unwrap();
    let mut g = c.benchmark_group("ssl/deflate-respeaker4-2s-16k");
    g.sample_size(30);
    for method in [Method::GccPhat, Method::Mvdr] {
        for deflate in [false, true] {
            let config = SslConfig {
                method,
                num_peaks: 2,
                deflate: Some(deflate),
                ..SslConfig::default()
            };
            let loc = Localizer::new(&array, RATE, &config).unwrap();
            let name = if deflate { "deflate" } else { "plain" };
            g.bench_function(BenchmarkId::new(name, method), |b| {
                b.iter(|| loc.locate(black_box(&audio)).unwrap())
            });
        }
    }
    g.finish();
}

fn stft(c: &mut Criterion) {
    let rec = recording(3.0);
    let audio = Audio::new(
        FS,
        rec.iter()
            .map(|ch| ch.iter().map(|&v| v as f32).collect())
            .collect(),
    )
    .unwrap();
    let mut g = c.benchmark_group("ssl/stft-3s-6ch");
    for frame in [512usize, 1024, 4096] {
        let s = Stft::new(frame, frame / 2).unwrap();
        g.bench_with_input(BenchmarkId::from_parameter(frame), &frame, |b, &f| {
            b.iter(|| s.analyze(black_box(&audio), 1..f / 2).unwrap())
        });
    }
    g.finish();
}

fn block_spectrum(c: &mut Criterion) {
    let rec = recording(0.2);
    let audio = Audio::new(
        FS,
        rec.iter()
            .map(|ch| ch.iter().map(|&v| v as f32).collect())
            .collect(),
    )
    .unwrap();
    let array = MicArray::default();
    let mut g = c.benchmark_group("ssl/block-spectrum");
    for method in Method::ALL {
        for az_step in [5.0, 1.0] {
            let config = SslConfig {
                method,
                az_step_deg: az_step,
                ..SslConfig::default()
            };
            let loc = Localizer::new(&array, FS, &config).unwrap();
            let frame = config.frame_len_at(FS);
            let spacing = f64::from(FS) / frame as f64;
            let bins =
                (config.fmin_hz / spacing).ceil() as usize..(config.fmax_hz / spacing) as usize + 1;
            let spec = loc.stft().analyze(&audio, bins).unwrap();
            let mut out = vec![0.0f32; loc.grid().len()];
            let mut scratch = iasm_ssl::MethodScratch::default();
            g.bench_function(
                BenchmarkId::new(method.name(), format!("{}cells", loc.grid().len())),
                |b| {
                    b.iter(|| {
                        loc.estimator().estimate_into(
                            black_box(&spec),
                            0..config.block_frames,
                            &mut out,
                            &mut scratch,
                        )
                    })
                },
            );
        }
    }
    g.finish();
}

criterion_group!(benches, whole_recording, stft, block_spectrum, deflation);
criterion_main!(benches);
