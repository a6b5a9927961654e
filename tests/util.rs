//! Helpers shared by the integration tests: synthetic recordings and running the binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use sim::farfield::{PlaneWave, render};
use sim::signal::Signal;

/// Seed of every synthetic recording.
pub const SEED: u64 = 7;
/// Sample rate of synthetic recordings (Hz).
pub const FS: u32 = 48_000;

/// The paper's array, as the `ssl` crate knows it.
pub fn iasm6() -> Vec<[f64; 3]> {
    ssl::MicArray::default().positions().to_vec()
}

/// Writes `channels` (channel-major, in [-1, 1)) as a 16-bit PCM WAV.
pub fn write_wav(path: &Path, channels: &[Vec<f64>], fs: u32) {
    let spec = hound::WavSpec {
        channels: channels.len() as u16,
        sample_rate: fs,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(path, spec).unwrap();
    for t in 0..channels[0].len() {
        for ch in channels {
            w.write_sample((ch[t] * 32767.0).round().clamp(-32768.0, 32767.0) as i16)
                .unwrap();
        }
    }
    w.finalize().unwrap();
}

/// Rewrites the WAV at `path` with its channels (channel-major) changed by `change`.
pub fn rewrite_wav(path: &Path, change: impl FnOnce(&mut Vec<Vec<f64>>)) {
    let audio = ssl::read_wav(path).unwrap();
    let mut channels: Vec<Vec<f64>> = audio
        .channels()
        .iter()
        .map(|c| c.iter().map(|&v| f64::from(v)).collect())
        .collect();
    change(&mut channels);
    write_wav(path, &channels, audio.sample_rate());
}

/// Rewrites the WAV at `path` with its channel `channel` (from 0) all zeros: a dead
/// microphone.
pub fn zero_channel(path: &Path, channel: usize) {
    rewrite_wav(path, |c| c[channel].iter_mut().for_each(|v| *v = 0.0));
}

/// A 0.5 s recording at the given microphones of noise sources at the given azimuths.
pub fn plane_wave_recording(mics: &[[f64; 3]], azimuths_deg: &[f64], seed: u64) -> Vec<Vec<f64>> {
    let waves: Vec<PlaneWave> = azimuths_deg
        .iter()
        .map(|&azimuth_deg| PlaneWave {
            azimuth_deg,
            elevation_deg: 0.0,
            signal: Signal::Noise,
        })
        .collect();
    let mut a = render(mics, &waves, FS, FS as usize / 2, 343.0, Some(30.0), seed);
    for ch in &mut a {
        ch.iter_mut().for_each(|v| *v *= 0.1);
    }
    a
}

/// Runs the `iasm` binary.
pub fn iasm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_iasm"))
        .args(args)
        .output()
        .expect("the iasm binary runs")
}

/// A path as a `&str` argument.
pub fn arg(p: &Path) -> &str {
    p.to_str().expect("UTF-8 temp path")
}

/// Stdout and stderr of a finished command, for failure messages.
pub fn show(o: &Output) -> String {
    format!(
        "status {:?}\n--- stdout\n{}\n--- stderr\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The positions of the sources a map's JSON (`iasm map --json`) holds.
pub fn sources_of(map: &serde_json::Value) -> Vec<[f64; 2]> {
    map["sources"]
        .as_array()
        .expect("a sources array")
        .iter()
        .map(|s| [s["x"].as_f64().unwrap(), s["y"].as_f64().unwrap()])
        .collect()
}

/// The JSON a successful command printed.
pub fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", show(o));
    serde_json::from_slice(&o.stdout).expect("JSON on stdout")
}

/// The JSON in a file.
pub fn json_file(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// Asserts that `o` failed with exit 2, no panic, and a message holding each of `needles`.
pub fn assert_clear_error(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{}", show(o));
    assert!(!err.contains("panicked"), "{}", show(o));
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}:\n{}", show(o));
    }
}

/// A fresh temporary folder.
pub fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// `dir/name`.
pub fn path(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

/// A mapping data set in the published layout under `root`: an open 8 x 6 m room
/// (`map/room.yaml` + `room.pgm`, origin (-1, -3)), `pose/poses.csv` (x, y, theta in
/// degrees), `src_gt.txt`, and `doas.csv` with the exact bearing (array frame, degrees) of
/// every source from every pose.
pub fn mapping_dataset(root: &Path, sources: &[[f64; 2]], poses: &[(f64, f64, f64)]) {
    std::fs::create_dir_all(root.join("map")).unwrap();
    std::fs::create_dir_all(root.join("pose")).unwrap();
    let (w, h) = (160usize, 120usize);
    let mut pgm = format!("P5\n{w} {h}\n255\n").into_bytes();
    pgm.extend(std::iter::repeat_n(254u8, w * h));
    std::fs::write(root.join("map/room.pgm"), pgm).unwrap();
    std::fs::write(
        root.join("map/room.yaml"),
        "image: room.pgm\nresolution: 0.05\norigin: [-1.0, -3.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    let mut csv = String::new();
    let mut doas = String::new();
    for &(x, y, th) in poses {
        csv.push_str(&format!("{x},{y},{th}\n"));
        let row: Vec<String> = sources
            .iter()
            .map(|s| {
                format!(
                    "{:.3}",
                    ssl::wrap_deg((s[1] - y).atan2(s[0] - x).to_degrees() - th)
                )
            })
            .collect();
        doas.push_str(&row.join(","));
        doas.push('\n');
    }
    std::fs::write(root.join("pose/poses.csv"), csv).unwrap();
    std::fs::write(root.join("doas.csv"), doas).unwrap();
    let gt: String = sources
        .iter()
        .enumerate()
        .map(|(i, s)| format!("s{} [{}, {}, 0]\n", i + 1, s[0], s[1]))
        .collect();
    std::fs::write(root.join("src_gt.txt"), gt).unwrap();
}

/// Twenty stops along y = 0 with turning headings.
pub fn drive() -> Vec<(f64, f64, f64)> {
    (0..20)
        .map(|k| (0.3 * k as f64, 0.0, 9.0 * k as f64 - 90.0))
        .collect()
}

/// Two sources for [`audio_dataset`].
pub const AUDIO_TRUTH: [[f64; 2]; 2] = [[2.0, 2.5], [4.5, -2.0]];

/// [`mapping_dataset`] along [`drive`], plus `audio/subK.wav`: each stop hears the sources
/// as plane waves from their bearings on the `iasm6` array.
pub fn audio_dataset(root: &Path, truth: &[[f64; 2]]) {
    let poses = drive();
    mapping_dataset(root, truth, &poses);
    std::fs::create_dir_all(root.join("audio")).unwrap();
    for (k, &(x, y, th)) in poses.iter().enumerate() {
        let az: Vec<f64> = truth
            .iter()
            .map(|s| ssl::wrap_deg((s[1] - y).atan2(s[0] - x).to_degrees() - th))
            .collect();
        write_wav(
            &root.join(format!("audio/sub{}.wav", k + 1)),
            &plane_wave_recording(&iasm6(), &az, SEED + k as u64),
            FS,
        );
    }
}

/// Every text element of an SVG file, trimmed.
pub fn svg_texts(path: &Path) -> Vec<String> {
    let s = std::fs::read_to_string(path).unwrap();
    s.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_owned())
        })
        .collect()
}

/// A count of the `rules` census in `iasm ssl --rules` or `iasm compare --rules` JSON.
pub fn census_count(c: &serde_json::Value, key: &str) -> u64 {
    c[key]
        .as_u64()
        .unwrap_or_else(|| panic!("no count {key} in the census {c}"))
}

/// Asserts that the census `c` files every missed (stop, near source) pair under exactly one
/// heading: the headings sum to the pairs less those found.
pub fn assert_every_miss_filed_once(c: &serde_json::Value) {
    let filed: u64 = [
        "no_peak",
        "cut_at_n",
        "low",
        "coherent",
        "prominence",
        "sidelobe",
        "insignificant",
        "jointly",
    ]
    .iter()
    .map(|k| census_count(c, k))
    .sum();
    assert_eq!(
        filed,
        census_count(c, "pairs") - census_count(c, "found"),
        "{c}"
    );
}
