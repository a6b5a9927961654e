//! What the live node spends on the run itself, beside localising and mapping: a step of
//! [`iasm_bag::live::Recorder`] (the run so far read as a bag, its stops found) on the paper's
//! array at 48 kHz: 6 channels of 16-bit audio in 0.1-s `AudioStamped` buffers and 50-Hz
//! odometry, a stop of 3.5 s after a drive of 1.5 s.
//!
//! `cargo bench -p iasm-bag --bench live`; figures go to `BENCHMARKS.md`.

// criterion_group!/criterion_main! generate undocumented items (criterion.rs #774/#775).
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use iasm_bag::live::Recorder;
use iasm_bag::{ReadOptions, StopOptions};
use iasm_ros::cdr::Writer;

const FS: i32 = 48_000;
const CH: i32 = 6;
const T0: i64 = 1_700_000_000_000_000_000;

/// A ROS 2 audio_common AudioStamped of `frames` frames ending at `ns`.
fn audio(ns: i64, frames: usize, k: usize) -> Vec<u8> {
    let mut w = Writer::new();
    w.i32((ns / 1_000_000_000) as i32);
    w.u32((ns % 1_000_000_000) as u32);
    w.string("mic");
    for v in [8, CH, FS, frames as i32] {
        w.i32(v);
    }
    w.len(0); // float32
    w.len(0); // int32
    w.len(frames * CH as usize);
    for i in 0..frames * CH as usize {
        // int16 samples, aligned as the sequence's count leaves them.
        let v = (((i + k * 7919) * 2_654_435_761) % 65_536) as i32 - 32_768;
        w.u8((v & 0xff) as u8);
        w.u8(((v >> 8) & 0xff) as u8);
    }
    w.len(0); // int8
    w.len(0); // uint8
    w.finish()
}

/// An Odometry at `ns` at x.
fn odom(ns: i64, x: f64) -> Vec<u8> {
    let mut w = Writer::new();
    w.i32((ns / 1_000_000_000) as i32);
    w.u32((ns % 1_000_000_000) as u32);
    w.string("odom");
    w.string("base_link");
    for v in [x, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
        w.f64(v);
    }
    for _ in 0..36 + 6 + 36 {
        w.f64(0.0);
    }
    w.finish()
}

/// The run's messages up to `end_s`: cycles of (still 3.5 s, drive 1.5 s), in time order.
fn messages(end_s: f64) -> Vec<(i64, &'static str, &'static str, Vec<u8>)> {
    let cycle = 5.0;
    let frames = (FS / 10) as usize;
    let mut msgs = Vec::new();
    let mut k = 0;
    while (k + 1) as f64 * 0.1 <= end_s {
        let ns = T0 + ((k + 1) as i64) * 100_000_000;
        msgs.push((
            ns + 2_000_000,
            "/audio",
            "audio_common_msgs/msg/AudioStamped",
            audio(ns, frames, k),
        ));
        k += 1;
    }
    let mut j = 0;
    while j as f64 * 0.02 <= end_s {
        let t = j as f64 * 0.02;
        let c = (t / cycle).floor();
        let u = ((t - c * cycle - 3.5) / 1.5).clamp(0.0, 1.0);
        let ns = T0 + (t * 1e9) as i64;
        msgs.push((
            ns + 1_000_000,
            "/odom",
            "nav_msgs/msg/Odometry",
            odom(ns, c + u),
        ));
        j += 1;
    }
    msgs.sort_by_key(|m| m.0);
    msgs
}

/// A recorder fed the run up to each of `steps` (s), a step taken at each: what it holds
/// then, and the stops each step handed on.
fn fed(steps: &[f64]) -> (Recorder, Vec<usize>) {
    let options = StopOptions::default();
    let all = messages(*steps.last().expect("a step"));
    let mut r = Recorder::new(ReadOptions::default());
    let mut handed = Vec::new();
    let mut at = 0;
    for &t in steps {
        let until = T0 + (t * 1e9) as i64;
        while at < all.len() && all[at].0 <= until {
            let (ns, topic, ty, data) = &all[at];
            r.push(topic, ty, *ns, data).unwrap();
            at += 1;
        }
        handed.push(r.finished_stops(&options, false).unwrap().len());
    }
    (r, handed)
}

fn bench(c: &mut Criterion) {
    let options = StopOptions::default();
    // The first stop handed on as the robot drives off (at 4.0 s); the second stop's audio
    // (5.0-8.5 s) held when the robot has driven on (at 9.5 s): the step that hands on a
    // 3-s stop of 48-kHz audio, with 5.5 s of audio buffered since the first.
    let (at_stop, handed) = fed(&[4.0, 8.4]);
    assert_eq!(handed, [1, 0]);
    let more = messages(9.5);
    let mut at_stop = at_stop;
    for (ns, topic, ty, data) in more.iter().filter(|m| m.0 > T0 + 8_400_000_000) {
        at_stop.push(topic, ty, *ns, data).unwrap();
    }
    c.bench_function("recorder step, a 3-s stop handed on", |b| {
        b.iter_batched(
            || at_stop.clone(),
            |mut r| {
                let s = r.finished_stops(&options, false).unwrap();
                assert_eq!(s.len(), 1);
                black_box(s.len())
            },
            BatchSize::LargeInput,
        )
    });
    // Mid-drive, nothing to hand on (1 s of audio since the last stop): five times a second.
    let (driving, handed) = fed(&[4.0, 9.5, 10.0]);
    assert_eq!(handed, [1, 1, 0]);
    c.bench_function("recorder step, driving (nothing finished)", |b| {
        b.iter_batched(
            || driving.clone(),
            |mut r| black_box(r.finished_stops(&options, false).unwrap().len()),
            BatchSize::LargeInput,
        )
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
