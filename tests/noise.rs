//! The robot's own noise through the binary: a simulated robot whose fan is as loud at the
//! array as its two talkers, mapped with and without the recording of the robot alone that
//! `iasm simulate` writes into `noise/` (`ssl::noise`).

use crate::util::*;

/// `two_talkers` (talkers at (2.0, 4.0) and (4.5, 1.0)) with a fan on the robot, 60 dB
/// SPL at 1 m, 0.36 m behind and below the array: 69 dB there, the talkers 58-62 dB.
fn fan_scene() -> String {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/rooms/two_talkers.toml"),
    )
    .unwrap();
    let base = &base[..base.find("[expect]").unwrap()];
    format!(
        "{base}\n[[sources]]\non_robot = true\npos = [-0.2, 0.0, -0.3]\nsignal = \"pink_noise\"\nlevel_db = 60.0\n"
    )
}

const TALKERS: [[f64; 2]; 2] = [[2.0, 4.0], [4.5, 1.0]];

/// `iasm map` of the data set `dir` with `method`, N = 3, JSON, and `more` arguments.
fn map(dir: &std::path::Path, method: &str, more: &[&str]) -> std::process::Output {
    let mut args = vec![
        "map",
        "--dataset",
        arg(dir),
        "--method",
        method,
        "--num",
        "3",
        "--json",
    ];
    args.extend_from_slice(more);
    iasm(&args)
}

/// The distance from each true talker to the nearest source of the map.
fn misses(map: &serde_json::Value) -> Vec<f64> {
    let found = sources_of(map);
    TALKERS
        .iter()
        .map(|t| {
            found
                .iter()
                .map(|s| (s[0] - t[0]).hypot(s[1] - t[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

#[test]
fn the_robots_fan_is_subtracted_with_the_recording_of_the_robot_alone() {
    let dir = tempdir();
    let (scene, out) = (path(&dir, "fan.toml"), path(&dir, "fan"));
    std::fs::write(&scene, fan_scene()).unwrap();
    let o = iasm(&["simulate", arg(&scene), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", show(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("1 on the robot"),
        "{}",
        show(&o)
    );
    // The robot alone: 4 s at the array's six channels; the truth holds the talkers only.
    let alone = ssl::read_wav(&out.join("noise/robot.wav")).unwrap();
    assert_eq!((alone.num_channels(), alone.num_samples()), (6, 4 * 16_000));
    let truth = std::fs::read_to_string(out.join("src_gt.csv")).unwrap();
    assert_eq!(truth.lines().count(), 1 + 2, "{truth}");
    let mut with_noise = Vec::new();
    for method in ["gcc-phat", "mvdr"] {
        // The data set's noise/ is found and subtracted: both talkers found, 0.12 m off
        // on average and neither 0.25 m off (the fan 9 dB above them at the array).
        let o = map(&out, method, &[]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(err.contains("robot.wav holds it, subtracted"), "{err}");
        let v = json(&o);
        let m = misses(&v);
        assert!(
            m.iter().all(|&d| d < 0.25) && m.iter().sum::<f64>() / 2.0 < 0.12,
            "{method} with the noise: {m:?}\n{v}"
        );
        assert_eq!(sources_of(&v).len(), 2, "{method}: {v}");
        with_noise.push(v);
    }
    // Named with --noise from elsewhere, the same recording gives the same maps.
    let elsewhere = path(&dir, "robot_alone.wav");
    std::fs::rename(out.join("noise/robot.wav"), &elsewhere).unwrap();
    std::fs::remove_dir(out.join("noise")).unwrap();
    let o = map(&out, "gcc-phat", &["--noise", arg(&elsewhere)]);
    let v = json(&o);
    assert_eq!(sources_of(&v), sources_of(&with_noise[0]));
    assert_eq!(
        v["noise"].as_str(),
        Some(arg(&elsewhere)),
        "the map says which: {v}"
    );
    // Without it the fan takes the talkers' place: a talker missed by 0.3 m or more, or
    // a third source, by both methods.
    for method in ["gcc-phat", "mvdr"] {
        let o = map(&out, method, &[]);
        let v = json(&o);
        let m = misses(&v);
        assert!(
            m.iter().any(|&d| d > 0.3) || sources_of(&v).len() != 2,
            "{method} without the noise found both talkers: {m:?}\n{v}"
        );
    }
}

#[test]
fn a_noise_recording_that_does_not_fit_is_a_clear_error() {
    let dir = tempdir();
    let ds = path(&dir, "ds");
    std::fs::create_dir_all(ds.join("audio")).unwrap();
    std::fs::create_dir_all(ds.join("pose")).unwrap();
    let mics = iasm6();
    let poses = [(1.0, 1.0, 0.0), (2.0, 1.0, 0.0), (3.0, 1.0, 0.0)];
    let mut table = String::from("x,y,theta\n");
    for (k, p) in poses.iter().enumerate() {
        write_wav(
            &ds.join(format!("audio/stop{k}.wav")),
            &plane_wave_recording(&mics, &[60.0 - 20.0 * k as f64], SEED + k as u64),
            FS,
        );
        table.push_str(&format!("{},{},{}\n", p.0, p.1, p.2));
    }
    std::fs::write(ds.join("pose/poses.csv"), table).unwrap();
    // Four channels for a six-microphone array.
    let four = path(&dir, "four.wav");
    write_wav(&four, &plane_wave_recording(&mics[..4], &[0.0], 1), FS);
    let o = iasm(&["map", "--dataset", arg(&ds), "--noise", arg(&four)]);
    assert_clear_error(&o, &["four.wav", "4 channels", "6 microphones"]);
    // Too short to say what the robot sounds like (0.5 s holds 32 frames at 48 kHz, 0.1 s
    // does not).
    let short = path(&dir, "short.wav");
    let mut rec = plane_wave_recording(&mics, &[0.0], 1);
    rec.iter_mut().for_each(|c| c.truncate(FS as usize / 10));
    write_wav(&short, &rec, FS);
    let o = iasm(&["ssl", "--dataset", arg(&ds), "--noise", arg(&short)]);
    assert_clear_error(&o, &["short.wav", "record the robot alone"]);
    // Another sample rate.
    let slow = path(&dir, "slow.wav");
    write_wav(&slow, &plane_wave_recording(&mics, &[0.0], 1), 16_000);
    let o = iasm(&["map", "--dataset", arg(&ds), "--noise", arg(&slow)]);
    assert_clear_error(&o, &["slow.wav", "16000 Hz", "48000 Hz"]);
    // A missing file.
    let o = iasm(&[
        "eval",
        "--dataset",
        arg(&ds),
        "--noise",
        "/nonexistent/robot.wav",
    ]);
    assert_clear_error(&o, &["/nonexistent/robot.wav"]);
    // A noise/ folder with two recordings: which one is the robot alone?
    std::fs::create_dir_all(ds.join("noise")).unwrap();
    for name in ["a.wav", "b.wav"] {
        write_wav(
            &ds.join("noise").join(name),
            &plane_wave_recording(&mics, &[0.0], 1),
            FS,
        );
    }
    let o = iasm(&["map", "--dataset", arg(&ds)]);
    assert_clear_error(&o, &["noise", "2 WAVs", "--noise"]);
}
