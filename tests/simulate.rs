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

/// A data set says which microphones recorded it: `iasm simulate` writes `array.toml`,
/// and the commands given the data set and no array read it, so a 4-microphone square
/// heard by the robot is localised with its own geometry, not the default 6-microphone
/// array (whose channel count the recordings would not match). `--array` still wins.
#[test]
fn a_simulated_data_set_carries_its_array() {
    let dir = tempdir();
    let (file, out) = (path(&dir, "sq.toml"), path(&dir, "sq"));
    let square = "[[0.05, 0.05, 0.0], [-0.05, 0.05, 0.0], [-0.05, -0.05, 0.0], [0.05, -0.05, 0.0]]";
    let scene = SMALL.replace("preset = \"iasm6\"", &format!("positions = {square}"));
    assert_ne!(scene, SMALL);
    std::fs::write(&file, scene).unwrap();
    let o = iasm(&["simulate", arg(&file), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", show(&o));
    let written = std::fs::read_to_string(out.join("array.toml")).unwrap();
    let parsed: toml::Table = toml::from_str(&written).unwrap();
    let want: toml::Table = toml::from_str(&format!("positions = {square}")).unwrap();
    assert_eq!(parsed["positions"], want["positions"], "{written}");
    // The source is at (1, 3); the stops 1.9-2.8 m from it.
    let o = iasm(&["map", "--dataset", arg(&out), "--num", "2", "--json"]);
    assert!(o.status.success(), "{}", show(&o));
    let v = json(&o);
    assert!(v["array"].as_str().unwrap().ends_with("array.toml"), "{v}");
    // Each stop's one DoA within 5 degrees of the source's bearing: the square's geometry.
    let o = iasm(&[
        "ssl",
        "--dataset",
        arg(&out),
        "--num",
        "1",
        "--score",
        "--min-score",
        "1",
    ]);
    assert!(o.status.success(), "{}", show(&o));
    // Named on the command line, another array is used, and the mismatch is refused.
    let o = iasm(&["ssl", "--dataset", arg(&out), "--array", "iasm6"]);
    assert!(!o.status.success(), "{}", show(&o));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("4 channels") && e.contains("6 microphones"),
        "{e}"
    );
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
        // A 10-km room: its occupancy map at 5 cm would be 4e10 cells (40 GB); refused
        // before anything is rendered (issue 49).
        (
            SMALL.replace("dims = [5.0, 4.0, 3.0]", "dims = [10000.0, 10000.0, 3.0]"),
            vec!["bad.toml", "room.dims", "200020 x 200020 cells"],
        ),
        (
            SMALL.replace("clip_s = 0.2", "clip_s = 0.2\nsnr_db = nan"),
            vec!["bad.toml", "snr_db"],
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

#[test]
fn a_kinects_linear_array_on_a_turning_robot_maps_each_talker_on_its_own_side() {
    // The `two_talkers` room, heard through a Kinect's four microphones on a line along the
    // heading: each DoA could be its mirror image in the line. The robot turns 25 degrees
    // per stop as it drives, so only the true side is consistent from stop to stop.
    let dir = tempdir();
    let poses: Vec<String> = (0..12)
        .map(|k| format!("[{:.1}, 2.5, {:.1}]", 0.8 + 0.4 * k as f64, 25.0 * k as f64))
        .collect();
    let scene = format!(
        r#"
seed = 7
fs = 16000
clip_s = 0.6
snr_db = 30.0
[room]
dims = [6.0, 5.0, 3.0]
rt60 = 0.3
[array]
positions = {KINECT}
height = 0.8
[[sources]]
pos = [2.0, 4.0, 0.9]
signal = "speech_shaped"
[[sources]]
pos = [4.5, 1.0, 0.9]
signal = "speech_shaped"
[trajectory]
poses = [{}]
"#,
        poses.join(", ")
    );
    let (file, out) = (path(&dir, "kt.toml"), path(&dir, "kt"));
    let array =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/arrays/kinect.toml");
    std::fs::write(&file, scene).unwrap();
    let o = iasm(&["simulate", arg(&file), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", show(&o));
    for method in ["gcc-phat", "mvdr"] {
        let o = iasm(&[
            "map",
            "--dataset",
            arg(&out),
            "--array",
            arg(&array),
            "--method",
            method,
            "--num",
            "3",
            "--json",
        ]);
        assert!(o.status.success(), "{}", show(&o));
        // The user is told what a linear array cannot hear.
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("is linear"),
            "{}",
            show(&o)
        );
        let v = json(&o);
        let sources = v["sources"].as_array().unwrap();
        assert_eq!(sources.len(), 2, "{method}: {v}");
        // The truth is (2.0, 4.0) and (4.5, 1.0); their mirror images in the path
        // (y = 2.5 at the first stop's heading) would be 1.5 m away from each.
        assert!(v["ospa"]["total"].as_f64().unwrap() < 0.15, "{method}: {v}");
        assert!(
            sources.iter().all(|s| s.get("mirror").is_none()),
            "{method}: {v}"
        );
        assert_eq!(
            v["params"]["mirror_axis_deg"].as_f64(),
            Some(0.0),
            "{method}"
        );
    }
}

/// A Kinect's microphones (m, array frame): a line along the heading.
const KINECT: &str =
    "[[-0.113, 0.0, 0.0], [0.036, 0.0, 0.0], [0.076, 0.0, 0.0], [0.113, 0.0, 0.0]]";

/// A room that is not a box: an L-shaped plan (a hall 8 x 3 m, a wing 3 x 4 m at its east
/// end). `iasm simulate` renders it and writes the plan's occupancy map (the corner outside
/// the L unknown, as a robot's range sensor leaves it behind the walls), and the map made
/// from its audio has every source in the room.
#[test]
fn a_floor_plan_is_rendered_and_mapped_inside_its_walls() {
    let dir = tempdir();
    let (file, out) = (path(&dir, "l.toml"), path(&dir, "l"));
    let scene = r#"
seed = 3
fs = 16000
clip_s = 0.5
snr_db = 30.0
[room]
plan = [[0.0, 0.0], [8.0, 0.0], [8.0, 7.0], [5.0, 7.0], [5.0, 3.0], [0.0, 3.0]]
height = 3.0
rt60 = 0.5
[array]
preset = "iasm6"
height = 0.8
[[sources]]
pos = [7.2, 6.0, 1.2]
signal = "speech_shaped"
[[sources]]
pos = [2.0, 0.6, 1.1]
signal = "speech_shaped"
[trajectory]
waypoints = [[0.8, 1.5], [6.0, 1.5], [6.0, 5.0]]
spacing = 0.5
"#;
    std::fs::write(&file, scene).unwrap();
    let o = iasm(&["simulate", arg(&file), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", show(&o));
    let pgm = std::fs::read(out.join("map/map.pgm")).unwrap();
    // P5, width, height, 255, then the cells, row 0 at the top; 0.05 m cells from
    // (-0.5, -0.5).
    let text = String::from_utf8_lossy(&pgm[..14]).into_owned();
    let header: Vec<&str> = text.split_whitespace().take(4).collect();
    let (w, h): (usize, usize) = (header[1].parse().unwrap(), header[2].parse().unwrap());
    let body = &pgm[pgm.len() - w * h..];
    let cell = |x: f64, y: f64| {
        let i = ((x + 0.5) / 0.05) as usize;
        let j = h - 1 - ((y + 0.5) / 0.05) as usize;
        body[j * w + i]
    };
    assert_eq!((w, h), (180, 160));
    assert_eq!(cell(2.0, 1.5), 254, "the hall is free");
    assert_eq!(cell(6.5, 5.0), 254, "the wing is free");
    assert_eq!(cell(2.0, 5.0), 205, "the corner outside the L is unknown");
    assert_eq!(cell(2.5, 3.0), 0, "the hall's north wall is occupied");
    assert_eq!(cell(5.0, 5.0), 0, "the wing's west wall is occupied");
    let o = iasm(&["map", "--dataset", arg(&out), "--num", "3", "--json"]);
    assert!(o.status.success(), "{}", show(&o));
    let v = json(&o);
    let sources = v["sources"].as_array().unwrap();
    assert!(!sources.is_empty(), "{v}");
    for s in sources {
        let (x, y) = (s["x"].as_f64().unwrap(), s["y"].as_f64().unwrap());
        // In the L, or within the room rule's 0.3 m of it.
        let in_l = |x: f64, y: f64| {
            (0.0..=8.0).contains(&x) && (0.0..=3.0).contains(&y)
                || (5.0..=8.0).contains(&x) && (0.0..=7.0).contains(&y)
        };
        let near = (0..16).any(|k| {
            let a = k as f64 * std::f64::consts::TAU / 16.0;
            in_l(x + 0.3 * a.cos(), y + 0.3 * a.sin())
        });
        assert!(
            in_l(x, y) || near,
            "a source at ({x:.2}, {y:.2}) outside the room: {v}"
        );
    }
    // The hall's talker is found (the wing's is heard only by reflection from the first
    // stops).
    assert!(
        sources.iter().any(|s| {
            (s["x"].as_f64().unwrap() - 2.0).hypot(s["y"].as_f64().unwrap() - 0.6) < 0.3
        }),
        "{v}"
    );
}

/// `iasm map --signatures`: what each source sounds like, from the recordings of the
/// stops that heard it. In `two_talkers` two noises with speech's long-term spectrum
/// (steady: broadband) stand at (2.0, 4.0) and (4.5, 1.0); in `one_source` a voiced hum
/// with a steady pitch (tonal) at (3.5, 3.2); in `speech_one_rt05` a recorded talker
/// (speech) at (3.5, 3.8). Each kind is in the JSON, the table, the figure's legend and the MCAP's
/// labels.
#[test]
fn a_maps_sources_say_what_they_sound_like() {
    let dir = tempdir();
    let rooms = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/rooms");
    for (scene, n, truth) in [
        (
            "two_talkers",
            "3",
            &[([2.0, 4.0], "broadband"), ([4.5, 1.0], "broadband")][..],
        ),
        ("one_source", "2", &[([3.5, 3.2], "tonal")][..]),
        ("speech_one_rt05", "2", &[([3.5, 3.8], "speech")][..]),
    ] {
        let data = path(&dir, scene);
        let o = iasm(&[
            "simulate",
            arg(&rooms.join(format!("{scene}.toml"))),
            "--out",
            arg(&data),
        ]);
        assert!(o.status.success(), "{}", show(&o));
        let fig = path(&dir, &format!("{scene}.svg"));
        let mcap_path = path(&dir, &format!("{scene}.mcap"));
        let args = [
            "map",
            "--dataset",
            arg(&data),
            "--method",
            "mvdr",
            "--num",
            n,
            "--signatures",
        ];
        let v = json(&iasm(
            &[
                &args[..],
                &["--json", "--png", arg(&fig), "--mcap", arg(&mcap_path)],
            ]
            .concat(),
        ));
        let sources = v["sources"].as_array().unwrap();
        for (at, kind) in truth {
            let s = sources
                .iter()
                .find(|s| {
                    (s["x"].as_f64().unwrap() - at[0]).hypot(s["y"].as_f64().unwrap() - at[1]) < 0.3
                })
                .unwrap_or_else(|| panic!("{scene}: no source near {at:?}: {v:#}"));
            let sig = &s["signature"];
            assert_eq!(sig["kind"], *kind, "{scene} {at:?}: {sig:#}");
            assert!(sig["stops"].as_u64().unwrap() >= 3, "{sig}");
            assert!(sig["level_db"].as_f64().unwrap() <= 0.0, "{sig}");
            assert!(!sig["spectrum_db"].as_array().unwrap().is_empty(), "{sig}");
        }
        // The loudest source is the level's reference.
        let top = sources
            .iter()
            .map(|s| s["signature"]["level_db"].as_f64().unwrap())
            .fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(top, 0.0);
        let table = String::from_utf8_lossy(&iasm(&args).stdout).into_owned();
        assert!(table.contains("What each source sounds like"), "{table}");
        let legend = svg_texts(&fig);
        for (_, kind) in truth {
            assert!(legend.iter().any(|t| t.contains(kind)), "{legend:?}");
        }
        let bytes = std::fs::read(&mcap_path).unwrap();
        let labels: Vec<String> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(|m| m.unwrap())
            .filter(|m| m.channel.topic == "/iasm/sources")
            .flat_map(|m| {
                <iasm_ros::msg::MarkerArray as iasm_ros::msg::Message>::from_cdr(&m.data)
                    .unwrap()
                    .markers
            })
            .filter(|m| m.ns == "labels")
            .map(|m| m.text)
            .collect();
        for (_, kind) in truth {
            assert!(labels.iter().any(|t| t.ends_with(kind)), "{labels:?}");
        }
    }
}
