//! Every reader of outside input against mutated files: WAV, PGM, map YAML, pose and DoA
//! tables (CSV and XLSX), ground truth, array TOML and JSON, settings TOML, scene TOML.
//!
//! Each starts from valid files and reads thousands of seeded random byte-level mutations of
//! them (truncations, flipped bits and bytes, inserted, deleted and duplicated runs, numbers
//! and header fields replaced by extreme values), and asserts for every case: a result or an
//! error that names the file, never a panic; no case running past [`HANG_S`]; no case
//! allocating more than [`ALLOC_FACTOR`] times its file's size plus [`ALLOC_SLACK`] at its
//! peak (a header that declares more data than the file holds must not reserve it).
//!
//! Deterministic: case `k` of a format is the same mutation on every run. The default is
//! [`DEFAULT_CASES`] per format; `IASM_FUZZ_CASES=N` runs N (by hand, for a longer search).
//! A failure names the format, the case and where its input was saved.
//!
//! Its own test binary: it counts the heap through a global allocator, and its tests take
//! turns (one lock) so that the count is one case's.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

const DEFAULT_CASES: usize = 2000;
/// A case running longer than this is a hang (the slowest valid reads take milliseconds).
const HANG_S: f64 = 10.0;
/// Peak heap per case at most `ALLOC_FACTOR * file size + ALLOC_SLACK` bytes.
const ALLOC_FACTOR: usize = 64;
const ALLOC_SLACK: usize = 4 << 20;

/// A scene file describes work rather than holding data: its memory is bounded by the
/// simulator's caps (`sim::scene::MAX_SIGNAL_SAMPLES` of f64 signal, 256 MiB), not by its size.
const SCENE_SLACK: usize = 320 << 20;

/// The system allocator, counting the bytes in use and their peak.
struct Counting;

static IN_USE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is passed on to `System` unchanged; the counters are only statistics.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as `System.alloc`, with the caller's layout.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = IN_USE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) };
        IN_USE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as `System.realloc`, with the caller's arguments.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                let now = IN_USE.fetch_add(new_size - layout.size(), Ordering::Relaxed) + new_size
                    - layout.size();
                PEAK.fetch_max(now, Ordering::Relaxed);
            } else {
                IN_USE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// One format's tests at a time, so that the heap count is one case's.
static TURN: Mutex<()> = Mutex::new(());

fn cases() -> usize {
    std::env::var("IASM_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_CASES)
}

/// Extreme values for numbers in text.
const TEXT_EXTREMES: &[&str] = &[
    "999999999999999999999999",
    "199999999999.5",
    "1e308",
    "-1e308",
    "1e-320",
    "-1",
    "0",
    "-0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4294967296",
    "18446744073709551616",
    "\"\"",
    "[]",
    "{}",
    "\u{ff}",
];

/// Extreme values for binary header fields.
const U32_EXTREMES: &[u32] = &[
    0,
    1,
    2,
    0xFFFF,
    0x1_0000,
    0x7FFF_FFFF,
    0x8000_0000,
    0xFFFF_FFFF,
];

/// One seeded mutation of `seed` (one to four edits stacked).
fn mutate(rng: &mut StdRng, seed: &[u8], text: bool) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..rng.random_range(1..=4) {
        let n = b.len();
        match rng.random_range(0..8) {
            0 => b.truncate(rng.random_range(0..=n)),
            1 if n > 0 => {
                for _ in 0..rng.random_range(1..=8) {
                    let i = rng.random_range(0..n);
                    b[i] ^= 1 << rng.random_range(0..8);
                }
            }
            2 if n > 0 => {
                let i = rng.random_range(0..n);
                b[i] = rng.random();
            }
            3 => {
                let at = rng.random_range(0..=n);
                let k = rng.random_range(1..=16);
                let ins: Vec<u8> = (0..k).map(|_| rng.random()).collect();
                b.splice(at..at, ins);
            }
            4 if n > 0 => {
                let a = rng.random_range(0..n);
                let e = (a + rng.random_range(1..=64)).min(n);
                b.drain(a..e);
            }
            5 if n > 0 => {
                let a = rng.random_range(0..n);
                let e = (a + rng.random_range(1..=256)).min(n);
                let chunk = b[a..e].to_vec();
                let at = rng.random_range(0..=n);
                b.splice(at..at, chunk);
            }
            _ if text => replace_number(rng, &mut b),
            _ if n >= 4 => {
                // A header field: the first 96 bytes hold them (an extensible WAV header is 68).
                let limit = (n - 4).min(96);
                let i = rng.random_range(0..=limit) & !1;
                let v = U32_EXTREMES[rng.random_range(0..U32_EXTREMES.len())];
                if rng.random_bool(0.5) {
                    b[i..i + 4].copy_from_slice(&v.to_le_bytes());
                } else {
                    b[i..i + 2].copy_from_slice(&(v as u16).to_le_bytes());
                }
            }
            _ => {}
        }
    }
    b
}

/// Replaces one number (a run of digits, signs, dots and exponents) in `b` with an extreme
/// value, or inserts one where there is none.
fn replace_number(rng: &mut StdRng, b: &mut Vec<u8>) {
    let is_num = |c: u8| c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'E');
    let starts: Vec<usize> = (0..b.len())
        .filter(|&i| b[i].is_ascii_digit() && (i == 0 || !is_num(b[i - 1])))
        .collect();
    let v = TEXT_EXTREMES[rng.random_range(0..TEXT_EXTREMES.len())].as_bytes();
    if starts.is_empty() {
        let at = rng.random_range(0..=b.len());
        b.splice(at..at, v.iter().copied());
        return;
    }
    let a = starts[rng.random_range(0..starts.len())];
    let mut e = a;
    while e < b.len() && is_num(b[e]) {
        e += 1;
    }
    b.splice(a..e, v.iter().copied());
}

/// What a format's run saw.
#[derive(Debug, Default)]
struct Tally {
    ok: usize,
    err: usize,
    slowest_ms: f64,
    /// The largest peak heap of a case (bytes) and its file's size.
    largest_peak: (usize, usize),
}

/// Reads `cases()` mutations of `seeds` through `read`: each is written to `dir/name` and
/// `read` is given that path. Asserts no panic, no hang, bounded heap and a clear error.
fn fuzz(
    format: &str,
    dir: &Path,
    name: &str,
    seeds: Vec<Vec<u8>>,
    text: bool,
    slack: usize,
    read: fn(&Path) -> Result<(), String>,
) -> Tally {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let n = cases();
    let file = dir.join(name);
    // Every seed is a valid input: the mutations start from files the reader accepts.
    for (i, seed) in seeds.iter().enumerate() {
        std::fs::write(&file, seed).unwrap();
        if let Err(e) = read(&file) {
            panic!("{format}: seed {i} is refused: {e}");
        }
    }
    let started = std::sync::Arc::new(Mutex::new((usize::MAX, Instant::now())));
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    // The worker reads the cases; this thread watches for a hang.
    let worker = {
        let (file, started, done, format, name) = (
            file.clone(),
            started.clone(),
            done.clone(),
            format.to_owned(),
            name.to_owned(),
        );
        std::thread::spawn(move || -> Result<Tally, String> {
            let mut t = Tally::default();
            let mut rng = StdRng::seed_from_u64(0x1A5A_0000 ^ fxhash(&format));
            for k in 0..n {
                let seed = &seeds[k % seeds.len()];
                let bytes = mutate(&mut rng, seed, text);
                std::fs::write(&file, &bytes).map_err(|e| e.to_string())?;
                *started.lock().unwrap() = (k, Instant::now());
                let base = IN_USE.load(Ordering::Relaxed);
                PEAK.store(base, Ordering::Relaxed);
                let t0 = Instant::now();
                let r = std::panic::catch_unwind(|| read(&file));
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                let peak = PEAK.load(Ordering::Relaxed).saturating_sub(base);
                let keep = |why: &str| {
                    let saved = kept(&format, k, &name);
                    let _ = std::fs::write(&saved, &bytes);
                    format!(
                        "{format}, case {k} of {n}: {why}; input saved to {}",
                        saved.display()
                    )
                };
                match r {
                    Err(_) => return Err(keep("the reader panicked")),
                    Ok(Ok(())) => t.ok += 1,
                    Ok(Err(msg)) => {
                        if !msg.contains(&name) {
                            return Err(keep(&format!("the error does not name the file: {msg}")));
                        }
                        t.err += 1;
                    }
                }
                let limit = ALLOC_FACTOR * bytes.len() + slack;
                if peak > limit {
                    return Err(keep(&format!(
                        "{peak} bytes allocated at the peak for a {}-byte file",
                        bytes.len()
                    )));
                }
                t.slowest_ms = t.slowest_ms.max(ms);
                if peak > t.largest_peak.0 {
                    t.largest_peak = (peak, bytes.len());
                }
            }
            done.store(true, Ordering::Relaxed);
            Ok(t)
        })
    };
    while !done.load(Ordering::Relaxed) && !worker.is_finished() {
        std::thread::sleep(Duration::from_millis(20));
        let (k, t0) = *started.lock().unwrap();
        if k != usize::MAX && t0.elapsed().as_secs_f64() > HANG_S && !worker.is_finished() {
            let saved = kept(format, k, name);
            let _ = std::fs::copy(&file, &saved);
            panic!(
                "{format}, case {k}: still reading after {HANG_S} s; input saved to {}",
                saved.display()
            );
        }
    }
    let tally = match worker.join() {
        Ok(Ok(t)) => t,
        Ok(Err(msg)) => panic!("{msg}"),
        Err(_) => panic!("{format}: the worker died"),
    };
    eprintln!(
        "{format}: {n} cases, {} read, {} refused with an error naming the file; 0 panics, 0 hangs; \
         slowest {:.1} ms; largest peak heap {:.1} KiB (a {}-byte file)",
        tally.ok,
        tally.err,
        tally.slowest_ms,
        tally.largest_peak.0 as f64 / 1024.0,
        tally.largest_peak.1
    );
    assert_eq!(tally.ok + tally.err, n);
    tally
}

/// Where a failing case's input is kept (beyond the temporary folder's life).
fn kept(format: &str, case: usize, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-failures");
    let _ = std::fs::create_dir_all(&dir);
    dir.join(format!(
        "{}-case{case}-{name}",
        format.replace([' ', '/'], "_")
    ))
}

fn fxhash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

fn tempdir() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("iasm-fuzz")
        .tempdir()
        .unwrap()
}

fn text(err: anyhow::Error) -> String {
    format!("{err:#}")
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// A small 6-channel WAV as bytes: 16-bit integer or 32-bit float samples.
fn wav_bytes(float: bool) -> Vec<u8> {
    let spec = hound::WavSpec {
        channels: 6,
        sample_rate: 16_000,
        bits_per_sample: if float { 32 } else { 16 },
        sample_format: if float {
            hound::SampleFormat::Float
        } else {
            hound::SampleFormat::Int
        },
    };
    let mut cur = std::io::Cursor::new(Vec::new());
    {
        let mut w = hound::WavWriter::new(&mut cur, spec).unwrap();
        let mut rng = StdRng::seed_from_u64(3);
        for _ in 0..800 * 6 {
            let v: f32 = rng.random_range(-0.5..0.5);
            if float {
                w.write_sample(v).unwrap();
            } else {
                w.write_sample((v * 32767.0) as i16).unwrap();
            }
        }
        w.finalize().unwrap();
    }
    cur.into_inner()
}

#[test]
fn wav_reader_survives_mutations() {
    let dir = tempdir();
    let t = fuzz(
        "WAV",
        dir.path(),
        "rec.wav",
        vec![wav_bytes(false), wav_bytes(true)],
        false,
        ALLOC_SLACK,
        |p| ssl::read_wav(p).map(drop).map_err(|e| e.to_string()),
    );
    assert!(t.ok > 0 && t.err > 0, "{t:?}");
}

const YAML: &str = "image: m.pgm\nresolution: 0.05\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

fn pgm_bytes() -> Vec<u8> {
    let (w, h) = (40usize, 30usize);
    let mut b = format!("P5\n# a comment\n{w} {h}\n255\n").into_bytes();
    b.extend((0..w * h).map(|i| if i % 7 == 0 { 0u8 } else { 254 }));
    b
}

#[test]
fn map_yaml_reader_survives_mutations() {
    let dir = tempdir();
    std::fs::write(dir.path().join("m.pgm"), pgm_bytes()).unwrap();
    let block = "image: \"m.pgm\"  # quoted\nresolution: 0.05\norigin:\n  - -1.0\n  - -2.0\n  - 0.0\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
    fuzz(
        "map YAML",
        dir.path(),
        "map.yaml",
        vec![YAML.into(), block.into()],
        true,
        ALLOC_SLACK,
        |p| iasm::dataset::load_map(p).map(drop).map_err(text),
    );
}

#[test]
fn pgm_reader_survives_mutations() {
    let dir = tempdir();
    std::fs::write(dir.path().join("map.yaml"), YAML).unwrap();
    let ascii = {
        let mut s = String::from("P2\n5 4\n255\n");
        for i in 0..20 {
            s.push_str(&format!("{} ", if i % 3 == 0 { 0 } else { 254 }));
        }
        s.into_bytes()
    };
    fuzz(
        "PGM",
        dir.path(),
        "m.pgm",
        vec![pgm_bytes(), ascii],
        false,
        ALLOC_SLACK,
        |p| {
            iasm::dataset::load_map(&p.with_file_name("map.yaml"))
                .map(drop)
                .map_err(|e| {
                    // The YAML names the image; the error must name the image.
                    text(e)
                })
        },
    );
}

#[test]
fn pose_csv_reader_survives_mutations() {
    let dir = tempdir();
    let plain = "0,0,0\n0.3,0,9\n0.6,0.1,18\n0.9,0.1,27\n";
    let named = "x,y,yaw\n0,0,0\n0.3,0,0.15\n0.6,0.1,0.3\n";
    let ros = "%time,field.pose.position.x,field.pose.position.y,field.pose.position.z,\
field.pose.orientation.x,field.pose.orientation.y,field.pose.orientation.z,field.pose.orientation.w\n\
1,0.0,0.0,0,0,0,0,1\n2,0.5,0.1,0,0,0,0.0998,0.995\n";
    fuzz(
        "pose CSV",
        dir.path(),
        "poses.csv",
        vec![plain.into(), named.into(), ros.into()],
        true,
        ALLOC_SLACK,
        |p| iasm::dataset::read_poses(p, false).map(drop).map_err(text),
    );
}

#[test]
fn doa_csv_reader_survives_mutations() {
    let dir = tempdir();
    let doas = "az1,az2,az3,az4\n10.5,-120,45,\n-179.9,180,0,33.3\n,,,\n";
    fuzz(
        "DoA CSV",
        dir.path(),
        "doas.csv",
        vec![doas.into(), "1;2;3\n4;5;6\n".into()],
        true,
        ALLOC_SLACK,
        |p| iasm::dataset::read_table(p).map(drop).map_err(text),
    );
}

#[test]
fn xlsx_reader_survives_mutations() {
    let dir = tempdir();
    let seed = std::fs::read(repo("fixtures/tables/poses.xlsx")).unwrap();
    let t = fuzz(
        "pose/DoA XLSX",
        dir.path(),
        "poses.xlsx",
        vec![seed],
        false,
        ALLOC_SLACK,
        |p| {
            iasm::dataset::read_table(p).map_err(text)?;
            iasm::dataset::read_poses(p, false).map(drop).map_err(text)
        },
    );
    assert!(t.ok > 0, "{t:?}");
}

/// A workbook names each cell: one stray cell at `XFD1048576`, the last a sheet can have,
/// makes a 5-KB file claim a grid of 1048576 x 16384 cells (17e9). It is refused by its
/// extent, the message naming the file and the cell, with no more heap than a small file's.
#[test]
fn a_workbook_cell_at_the_end_of_the_sheet_is_refused_before_a_grid_is_made() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let path = repo("fixtures/tables/poses_stray_cell.xlsx");
    let base = IN_USE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let err = text(iasm::dataset::read_table(&path).unwrap_err());
    let peak = PEAK.load(Ordering::Relaxed).saturating_sub(base);
    let size = std::fs::metadata(&path).unwrap().len() as usize;
    assert!(
        err.contains("poses_stray_cell.xlsx")
            && err.contains("1048576 rows x 16384 columns")
            && err.contains("XFD1048576"),
        "{err}"
    );
    assert!(peak <= ALLOC_FACTOR * size + ALLOC_SLACK, "{peak} bytes");
    // The same table without the stray cell reads as it always did.
    let t = iasm::dataset::read_poses(&repo("fixtures/tables/poses.xlsx"), false).unwrap();
    assert_eq!(t.len(), 8);
}

#[test]
fn ground_truth_reader_survives_mutations() {
    let dir = tempdir();
    fuzz(
        "ground truth",
        dir.path(),
        "src_gt.txt",
        vec![
            "s1 [1.5, 0.6, 0.3]\ns2 [2.5, -0.6, 0.3]\n".into(),
            "x,y,z\n1.5,0.6,0.3\n2.5,-0.6,0.3\n".into(),
        ],
        true,
        ALLOC_SLACK,
        |p| iasm::dataset::read_sources(p).map(drop).map_err(text),
    );
}

/// An array file (TOML or JSON by the extension) through the `ssl` crate's reader.
fn read_array(p: &Path) -> Result<(), String> {
    ssl::MicArray::from_file(p)
        .map(drop)
        .map_err(|e| e.to_string())
}

#[test]
fn array_file_readers_survive_mutations() {
    let dir = tempdir();
    let toml = std::fs::read(repo("fixtures/arrays/iasm6.toml")).unwrap();
    fuzz(
        "array TOML",
        dir.path(),
        "arr.toml",
        vec![toml],
        true,
        ALLOC_SLACK,
        read_array,
    );
    let json = r#"{"name": "square", "positions": [[0.03, 0.03, 0.0], [-0.03, 0.03, 0.0], [-0.03, -0.03, 0.0], [0.03, -0.03, 0.0]]}"#;
    fuzz(
        "array JSON",
        dir.path(),
        "arr.json",
        vec![json.into()],
        true,
        ALLOC_SLACK,
        read_array,
    );
}

#[test]
fn settings_reader_survives_mutations() {
    let dir = tempdir();
    let mbss = std::fs::read(repo("fixtures/ssl-mbss-like.toml")).unwrap();
    let both = "[ssl]\nmethod = \"mvdr\"\nnum_peaks = 3\nfmin_hz = 200.0\nfmax_hz = 6000.0\nframe_len = 2048\n\n\
[iasm]\nvariant = \"ca\"\nsigma_deg = 5.0\nbeta_m = 2.0\ndbscan_eps_m = 0.3\n";
    fuzz(
        "settings TOML",
        dir.path(),
        "settings.toml",
        vec![mbss, both.into()],
        true,
        ALLOC_SLACK,
        |p| {
            iasm::settings::Settings::load(Some(p))
                .map(drop)
                .map_err(text)
        },
    );
}

#[test]
fn scene_reader_survives_mutations() {
    let dir = tempdir();
    let seeds = ["two_talkers.toml", "rows_ten.toml", "sparse_ten.toml"]
        .iter()
        .map(|n| std::fs::read(repo(&format!("fixtures/rooms/{n}"))).unwrap())
        .collect();
    fuzz(
        "scene TOML",
        dir.path(),
        "scene.toml",
        seeds,
        true,
        SCENE_SLACK,
        |p| iasm::scenes::load_scene(p).map(drop).map_err(text),
    );
}
