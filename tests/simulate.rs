//! `iasm simulate` through the binary: a scene file becomes a data set that the mapper
//! reads like real recordings.

use crate::util::*;

const SMALL: &str = r#"
seed = 5
fs = 16000
clip_s = 0.2
[room]
dims = [5.0, 4.0, 3.0]
absorption = [0.6, 0.6, 0.6, 0.6, 0.6, 0.6]
[array]
preset = "iasm6"
height = 0.8
[[sources]]
pos = [1.0, 3.0, 1.0]
[trajectory]
poses = [[1.0, 1.0, 0.0], [2.0, 1.0, 30.0], [3.0, 1.2, 60.0]]
"#;

#[test]
fn a_simulated_room_is_mapped_back_to_its_sources() {
    let dir = tempdir();
    let out = path(&dir, "sim");
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/rooms/two_talkers.toml");
    let o = iasm(&["simulate", arg(&scene), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", show(&o));
    let o = iasm(&["map", "--dataset", arg(&out), "--num", "2", "--json"]);
    assert!(o.status.success(), "{}", show(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
    // The truth is (2.0, 4.0) and (4.5, 1.0).
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.2, "{v}");
}

#[test]
fn the_same_scene_gives_the_same_bytes() {
    let dir = tempdir();
    let scene = path(&dir, "small.toml");
    std::fs::write(&scene, SMALL).unwrap();
    let (a, b) = (path(&dir, "a"), path(&dir, "b"));
    for out in [&a, &b] {
        let o = iasm(&["simulate", arg(&scene), "--out", arg(out)]);
        assert!(o.status.success(), "{}", show(&o));
    }
    for f in [
        "audio/sub01.wav",
        "audio/sub03.wav",
        "pose/poses.csv",
        "map/map.pgm",
        "src_gt.csv",
    ] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}"
        );
    }
    let audio = ssl::read_wav(&a.join("audio/sub02.wav")).unwrap();
    assert_eq!(
        (
            audio.num_channels(),
            audio.num_samples(),
            audio.sample_rate()
        ),
        (6, 3200, 16000)
    );
}

#[test]
fn bad_scenes_are_clear_errors() {
    let dir = tempdir();
    let scene = path(&dir, "bad.toml");
    let out = path(&dir, "o");
    for (edit, needles) in [
        (
            SMALL.replace("seed = 5", "seed = 5\nspeed = 1"),
            vec!["bad.toml", "speed"],
        ),
        (
            SMALL.replace("pos = [1.0, 3.0, 1.0]", "pos = [1.0, 5.0, 1.0]"),
            vec!["sources[0].pos", "outside the room"],
        ),
        (
            SMALL.replace(
                "[0.6, 0.6, 0.6, 0.6, 0.6, 0.6]",
                "[0.6, 0.6, 0.6, 0.6, 0.6, -0.1]",
            ),
            vec!["absorption[5]", "outside [0, 1]"],
        ),
        (
            SMALL.replace("absorption = [0.6, 0.6, 0.6, 0.6, 0.6, 0.6]", "rt60 = 0.01"),
            vec!["room.rt60", "shorter than"],
        ),
        (
            SMALL.replace(
                "pos = [1.0, 3.0, 1.0]",
                "pos = [1.0, 3.0, 1.0]\nwav = \"talk.wav\"",
            ),
            vec!["sources[0].wav", "talk.wav"],
        ),
    ] {
        std::fs::write(&scene, edit).unwrap();
        assert_clear_error(
            &iasm(&["simulate", arg(&scene), "--out", arg(&out)]),
            &needles,
        );
    }
}

// See: issue 13
#[test]
fn r13_a_waypoint_far_outside_the_room_is_refused_at_once() {
    // The path used to be cut into stops before anything checked it against the room:
    // 5e11 stops. The bound on time is only there to catch a hang, not to measure speed.
    let dir = tempdir();
    let scene = path(&dir, "far.toml");
    let text = SMALL.replace(
        "poses = [[1.0, 1.0, 0.0], [2.0, 1.0, 30.0], [3.0, 1.2, 60.0]]",
        "waypoints = [[0.8, 199999999999.5], [3.0, 1.0]]\nspacing = 0.4",
    );
    std::fs::write(&scene, text).unwrap();
    let t0 = std::time::Instant::now();
    let o = iasm(&["simulate", arg(&scene), "--out", arg(&path(&dir, "o"))]);
    assert_clear_error(
        &o,
        &["far.toml", "trajectory.waypoints[0]", "outside the room"],
    );
    assert!(t0.elapsed().as_secs_f64() < 5.0, "{:?}", t0.elapsed());
}

// See: issue 13
#[test]
fn r13_simulate_replaces_its_own_output_whole_and_refuses_other_folders() {
    let dir = tempdir();
    let scene = path(&dir, "small.toml");
    std::fs::write(&scene, SMALL).unwrap();
    let out = path(&dir, "sim");
    let run = |extra: &[&str]| {
        let mut args = vec!["simulate", arg(&scene), "--out", arg(&out)];
        args.extend_from_slice(extra);
        iasm(&args)
    };
    // A folder of the user's own is refused, and left as it was.
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    assert_clear_error(&run(&[]), &["sim", "not empty", "--force"]);
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    // With --force it is replaced whole.
    let o = run(&["--force"]);
    assert!(o.status.success(), "{}", show(&o));
    assert!(!out.join("notes.txt").exists());
    assert_eq!(std::fs::read_dir(out.join("audio")).unwrap().count(), 3);
    // An earlier output is replaced whole: a recording the new scene does not make (an
    // earlier run's fourth stop) does not survive beside the new ones.
    std::fs::copy(out.join("audio/sub01.wav"), out.join("audio/sub04.wav")).unwrap();
    let o = run(&[]);
    assert!(o.status.success(), "{}", show(&o));
    assert_eq!(std::fs::read_dir(out.join("audio")).unwrap().count(), 3);
    // Nothing is left beside the output: no temporary or old folder.
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["sim", "small.toml"]);
}
