//! Scenes as a user writes them: sources, WAV signals, trajectories, the robot's own
//! sources, and the fields a bad scene names.

use super::*;

const SCENE: &str = r#"
seed = 3
fs = 8000
clip_s = 0.2
[room]
dims = [6.0, 4.0, 3.0]
absorption = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]
[array]
positions = [[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0]]
height = 1.0
[[sources]]
pos = [1.5, 3.0, 1.2]
[trajectory]
waypoints = [[1.0, 1.0], [3.0, 1.0], [3.0, 2.0]]
spacing = 0.5
"#;

fn two_mics(_: &str) -> Option<Vec<[f64; 3]>> {
    None
}

/// Writes a 16-bit WAV (two channels: a 500 Hz sine at half scale, then silence).
fn write_wav(path: &std::path::Path, fs: u32, n: usize) {
    let spec = hound::WavSpec {
        channels: 2,
        sample_rate: fs,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(path, spec).unwrap();
    for t in 0..n {
        let v = 0.5 * (std::f64::consts::TAU * 500.0 * t as f64 / f64::from(fs)).sin();
        w.write_sample((v * 32768.0).round() as i16).unwrap();
        w.write_sample(0i16).unwrap();
    }
    w.finalize().unwrap();
}

#[test]
fn a_wav_source_plays_its_first_channel_looped_at_its_level() {
    // 0.05 s of a sine (exactly 25 periods at 8 kHz) fills the 0.2 s clip four times;
    // at 70 dB SPL its RMS is 10^((70 - 94) / 20) Pa, so its peak is sqrt(2) times that.
    let dir = tempfile::tempdir().unwrap();
    write_wav(&dir.path().join("tone.wav"), 8000, 400);
    let text = SCENE.replace(
        "pos = [1.5, 3.0, 1.2]",
        "pos = [1.5, 3.0, 1.2]\nwav = \"tone.wav\"\nlevel_db = 70.0",
    );
    let mut scene = Scene::from_toml(&text).unwrap();
    scene.resolve_paths(dir.path());
    let p = scene.prepare(two_mics).unwrap();
    let x = &p.signals[0];
    assert_eq!(x.len(), 1600);
    let peak = 10f64.powf(-24.0 / 20.0) * std::f64::consts::SQRT_2;
    for (t, v) in x.iter().enumerate() {
        let want = peak * (std::f64::consts::TAU * 500.0 * t as f64 / 8000.0).sin();
        approx::assert_abs_diff_eq!(*v, want, epsilon = 1e-3 * peak);
    }
}

#[test]
fn a_bad_wav_source_names_the_field_and_the_file() {
    let dir = tempfile::tempdir().unwrap();
    write_wav(&dir.path().join("fast.wav"), 16000, 400);
    for (line, want) in [
        ("wav = \"missing.wav\"", "missing.wav"),
        ("wav = \"fast.wav\"", "16000 Hz, the scene at 8000 Hz"),
        ("wav = \"fast.wav\"\nsignal = \"voiced\"", "not both"),
    ] {
        let text = SCENE.replace(
            "pos = [1.5, 3.0, 1.2]",
            &format!("pos = [1.5, 3.0, 1.2]\n{line}"),
        );
        let e = refusal(&text, dir.path());
        assert!(e.contains("sources[0]") && e.contains(want), "{e}");
    }
}

#[test]
fn a_source_stops_and_the_room_rings_on() {
    // Active for the first 0.1 s of the 0.2 s clip: its signal is silent after, and the
    // microphones hear a decay that falls, but has not vanished, after the direct
    // sound (about 2 m, 6 ms) has passed.
    let text = SCENE.replace(
        "pos = [1.5, 3.0, 1.2]",
        "pos = [1.5, 3.0, 1.2]\nactive_s = [0.0, 0.1]",
    );
    let p = Scene::from_toml(&text).unwrap().prepare(two_mics).unwrap();
    assert!(p.signals[0][800..].iter().all(|&v| v == 0.0));
    assert!(p.signals[0][..800].iter().any(|&v| v != 0.0));
    let audio = p.render_stop(0);
    let power = |r: std::ops::Range<usize>| {
        let n = r.len() as f64;
        audio[0][r].iter().map(|v| v * v).sum::<f64>() / n
    };
    let (on, tail, late) = (power(400..800), power(900..1000), power(1500..1600));
    assert!(tail > 1e-6 * on && tail < 0.5 * on, "{on} {tail}");
    assert!(late < tail, "{tail} {late}");
    let bad = SCENE.replace(
        "pos = [1.5, 3.0, 1.2]",
        "pos = [1.5, 3.0, 1.2]\nactive_s = [0.3, 0.4]",
    );
    let e = refusal(&bad, std::path::Path::new("."));
    assert!(e.contains("sources[0].active_s"), "{e}");
}

#[test]
fn a_source_heard_at_some_stops_only_leaves_the_others_to_the_sensor_noise() {
    // Playing at stops 0 and 1 only, SNR 20 dB: at stop 3 the array hears the sensor
    // noise alone, at the level the source would have set there (1 % of its power).
    let text = SCENE.replace(
        "pos = [1.5, 3.0, 1.2]",
        "pos = [1.5, 3.0, 1.2]\nat_stops = [0, 1]",
    );
    let text = format!("snr_db = 20.0\n{text}");
    let p = Scene::from_toml(&text).unwrap().prepare(two_mics).unwrap();
    assert!(p.stops.len() > 3);
    let power = |x: &[Vec<f64>]| {
        x.iter().flatten().map(|v| v * v).sum::<f64>() / (x.len() * x[0].len()) as f64
    };
    let mics: Vec<[f64; 3]> = p
        .mics
        .iter()
        .map(|&m| mic_world(p.stops[3], p.scene.array.height, m))
        .collect();
    let would_hear = power(&p.renderer().render(&mics));
    let silent = power(&p.render_stop(3));
    let ratio = silent / would_hear;
    assert!((ratio - 0.01).abs() < 0.002, "noise / source power {ratio}");
    let heard = power(&p.render_stop(1));
    assert!(heard > 50.0 * silent, "{heard} {silent}");
    // A range beyond the stops is refused, naming the field.
    let bad = SCENE.replace(
        "pos = [1.5, 3.0, 1.2]",
        "pos = [1.5, 3.0, 1.2]\nat_stops = [2, 40]",
    );
    let e = refusal(&bad, std::path::Path::new("."));
    assert!(e.contains("sources[0].at_stops"), "{e}");
}

#[test]
fn a_source_that_moves_is_heard_at_each_place_from_its_stop_on() {
    // A talker at (1.5, 3.0) who walks to (4.5, 2.5) before stop 3: the array hears at
    // stops 0-2 what it hears of a talker who stays at the first place, and from stop 3 on
    // what it hears of one who stood at the second all along (no sensor noise: the same
    // samples, to rounding).
    let moving = SCENE.replace(
        "pos = [1.5, 3.0, 1.2]",
        "pos = [1.5, 3.0, 1.2]\nmoves = [{ from_stop = 3, pos = [4.5, 2.5, 1.2] }]",
    );
    let p = Scene::from_toml(&moving)
        .unwrap()
        .prepare(two_mics)
        .unwrap();
    let first = Scene::from_toml(SCENE).unwrap().prepare(two_mics).unwrap();
    let second = SCENE.replace("pos = [1.5, 3.0, 1.2]", "pos = [4.5, 2.5, 1.2]");
    let second = Scene::from_toml(&second)
        .unwrap()
        .prepare(two_mics)
        .unwrap();
    let n = p.stops.len();
    assert!(n > 4);
    assert_eq!(
        p.places(),
        vec![
            Place {
                source: 0,
                pos: [1.5, 3.0, 1.2],
                stops: [0, 2]
            },
            Place {
                source: 0,
                pos: [4.5, 2.5, 1.2],
                stops: [3, n - 1]
            },
        ]
    );
    assert_eq!(p.places_at(n - 1).len(), 1);
    let close = |a: &[Vec<f64>], b: &[Vec<f64>]| {
        let peak = b.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| (x - y).abs() <= 1e-9 * peak)
    };
    for k in 0..n {
        let want = if k < 3 { &first } else { &second };
        assert!(close(&p.render_stop(k), &want.render_stop(k)), "stop {k}");
    }
    // A move before the source plays, at a stop out of order, or out of the room is
    // refused, naming the move.
    for (moves, says) in [
        ("[{ from_stop = 0, pos = [4.5, 2.5, 1.2] }]", "moves[0]"),
        (
            "[{ from_stop = 3, pos = [4.5, 2.5, 1.2] }, { from_stop = 2, pos = [2.0, 2.0, 1.0] }]",
            "moves[1]",
        ),
        (
            "[{ from_stop = 3, pos = [9.0, 2.5, 1.2] }]",
            "outside the room",
        ),
    ] {
        let bad = SCENE.replace(
            "pos = [1.5, 3.0, 1.2]",
            &format!("pos = [1.5, 3.0, 1.2]\nmoves = {moves}"),
        );
        let e = refusal(&bad, std::path::Path::new("."));
        assert!(e.contains(says), "{moves}: {e}");
    }
}

#[test]
fn a_source_on_the_robot_goes_where_the_robot_goes() {
    let fan = "\n[[sources]]\non_robot = true\npos = [-0.3, 0.1, -0.2]\nsignal = \"pink_noise\"\n";
    let anechoic = SCENE.replace(
        "0.5, 0.5, 0.5, 0.5, 0.5, 0.5",
        "1.0, 1.0, 1.0, 1.0, 1.0, 1.0",
    );
    let with = |text: &str| {
        Scene::from_toml(&format!("{text}{fan}"))
            .unwrap()
            .prepare(two_mics)
            .unwrap()
    };
    let without = |text: &str| Scene::from_toml(text).unwrap().prepare(two_mics).unwrap();
    let diff = |a: &[Vec<f64>], b: &[Vec<f64>]| -> Vec<Vec<f64>> {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.iter().zip(y).map(|(x, y)| x - y).collect())
            .collect()
    };
    let far = |a: &[Vec<f64>], b: &[Vec<f64>]| {
        let d: f64 = diff(a, b).iter().flatten().map(|v| v * v).sum();
        let p: f64 = a.iter().flatten().map(|v| v * v).sum();
        (d / p).sqrt()
    };
    let p = with(&anechoic);
    assert_eq!(
        p.room_sources().count(),
        1,
        "the fan is not a source of the room"
    );
    assert!(p.has_robot_sources());
    // Stop 0 faces +x at (1, 1), stop 6 faces +y at (3, 2): in an anechoic room the
    // fan, carried along, sounds the same at both.
    let (a, b) = (
        p.render_robot_alone(0).unwrap(),
        p.render_robot_alone(6).unwrap(),
    );
    assert!(far(&a, &b) < 1e-9, "{}", far(&a, &b));
    // What a stop hears is the room's sources and the fan: the part the fan adds is
    // the same at both stops, and a fresh stretch of it is not the recording alone.
    let q = without(&anechoic);
    let part = |k| diff(&p.render_stop(k), &q.render_stop(k));
    assert!(far(&part(0), &part(6)) < 1e-9);
    assert!(
        far(&part(0), &a) > 0.5,
        "another stretch of the fan's noise"
    );
    assert_eq!(
        a[0].len(),
        (ROBOT_ALONE_S * 8000.0) as usize,
        "a few seconds alone"
    );
    // In a room with walls its reflections move with the robot.
    let lively = with(SCENE);
    let (a, b) = (
        lively.render_robot_alone(0).unwrap(),
        lively.render_robot_alone(6).unwrap(),
    );
    assert!(far(&a, &b) > 0.05, "{}", far(&a, &b));
    assert!(without(SCENE).render_robot_alone(0).is_none());
    // A robot whose fan would leave the room is refused, the field named.
    let out = format!("{SCENE}\n[[sources]]\non_robot = true\npos = [0.0, -1.5, 0.0]\n");
    let e = Scene::from_toml(&out)
        .unwrap()
        .prepare(two_mics)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sources[1].pos") && e.contains("on the robot at stop"),
        "{e}"
    );
    let only = SCENE.replace(
        "pos = [1.5, 3.0, 1.2]",
        "pos = [0.1, 0.0, 0.0]\non_robot = true",
    );
    let e = Scene::from_toml(&only)
        .unwrap()
        .prepare(two_mics)
        .unwrap_err()
        .to_string();
    assert!(e.contains("at least one source in the room"), "{e}");
}

#[test]
fn waypoints_are_walked_at_the_spacing_with_their_heading() {
    let p = Scene::from_toml(SCENE).unwrap().prepare(two_mics).unwrap();
    let xs: Vec<[f64; 2]> = p.stops.iter().map(Pose::position).collect();
    assert_eq!(
        xs,
        vec![
            [1.0, 1.0],
            [1.5, 1.0],
            [2.0, 1.0],
            [2.5, 1.0],
            [3.0, 1.0],
            [3.0, 1.5],
            [3.0, 2.0]
        ]
    );
    assert_eq!(p.stops[0].theta, 0.0);
    approx::assert_abs_diff_eq!(p.stops[6].theta, std::f64::consts::FRAC_PI_2);
}

#[test]
fn the_same_seed_gives_the_same_audio() {
    let a = Scene::from_toml(SCENE)
        .unwrap()
        .prepare(two_mics)
        .unwrap()
        .render_stop(2);
    let b = Scene::from_toml(SCENE)
        .unwrap()
        .prepare(two_mics)
        .unwrap()
        .render_stop(2);
    assert_eq!(a, b);
    assert_eq!((a.len(), a[0].len()), (2, 1600));
}

#[test]
fn the_array_turns_with_the_robot() {
    // Heading 90 degrees: the array's +x microphone points along world +y.
    let w = mic_world(
        Pose::new(1.0, 2.0, std::f64::consts::FRAC_PI_2),
        0.5,
        [0.1, 0.0, 0.2],
    );
    approx::assert_abs_diff_eq!(w[0], 1.0, epsilon = 1e-12);
    approx::assert_abs_diff_eq!(w[1], 2.1, epsilon = 1e-12);
    approx::assert_abs_diff_eq!(w[2], 0.7, epsilon = 1e-12);
}

/// The message with which a scene (paths relative to `base`) is refused.
fn refusal(text: &str, base: &std::path::Path) -> String {
    let mut scene = Scene::from_toml(text).unwrap();
    scene.resolve_paths(base);
    scene.prepare(two_mics).unwrap_err().to_string()
}

#[test]
fn bad_scenes_name_the_field() {
    let e = Scene::from_toml(&SCENE.replace("seed = 3", "seed = 3\ncolour = 1"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("colour"), "{e}");
    let here = std::path::Path::new(".");
    for (from, to, want) in [
        (
            "pos = [1.5, 3.0, 1.2]",
            "pos = [1.5, 9.0, 1.2]",
            &["sources[0].pos", "outside the room"][..],
        ),
        (
            "[0.5, 0.5, 0.5, 0.5, 0.5, 0.5]",
            "[0.5, 0.5, 1.5, 0.5, 0.5, 0.5]",
            &["absorption[2]"],
        ),
        (
            "absorption = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]",
            "rt60 = 0.05",
            &["room.rt60"],
        ),
        (
            "height = 1.0",
            "height = 3.5",
            &["trajectory stop 0", "outside the room"],
        ),
        // See: issue 13 (a waypoint far outside the room once hung the path walk).
        (
            "[3.0, 1.0], [3.0, 2.0]",
            "[3.0, 1.0], [3.0, 199999999999.5]",
            &["trajectory.waypoints[2]", "outside the room"],
        ),
        (
            "spacing = 0.5",
            "spacing = 0.00001",
            &["trajectory.spacing", "stops"],
        ),
        // Sizes a mutated scene once asked for (issue 13's mutation test): each is
        // refused before anything is allocated or enumerated.
        (
            "absorption = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]",
            "rt60 = 1600000000000.0",
            &["room.rt60", "(0, 20] s"],
        ),
        (
            "absorption = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]",
            "rt60 = 12.0",
            &["room.rt60", "image sources"],
        ),
        ("clip_s = 0.2", "clip_s = 1e9", &["clip_s", "(0, 60] s"]),
        // Noise of NaN dB once made every sample NaN (issue 49).
        (
            "clip_s = 0.2",
            "clip_s = 0.2\nsnr_db = nan",
            &["snr_db", "NaN dB"],
        ),
        (
            "clip_s = 0.2",
            "clip_s = 0.2\nsnr_db = -inf",
            &["snr_db", "-inf dB"],
        ),
        ("fs = 8000", "fs = 4000000000", &["fs", "384000"]),
        (
            "fs = 8000",
            "fs = 384000\nrir_s = 19.0",
            &["rir_s", "image sources"],
        ),
    ] {
        let e = refusal(&SCENE.replace(from, to), here);
        assert!(want.iter().all(|w| e.contains(w)), "{e}");
    }
}
