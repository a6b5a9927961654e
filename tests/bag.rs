//! `iasm bag`: a robot run recorded in a ROS 1 bag, made a data set and mapped.
//!
//! The run is a simulated room (`sim`): at each of the scene's stops the robot stands
//! 1.4 s while the array hears the two talkers, and between stops it drives 0.6 s. It is
//! written as `rosbag record` writes a run (the format of <http://wiki.ros.org/Bags/Format/2.0>,
//! one uncompressed chunk per second): 16-bit audio in 0.1-s `AudioDataStamped` buffers
//! stamped when full, `AudioInfo`, and `nav_msgs/Odometry` at 20 Hz. The reader itself is
//! checked against bags that rosbags wrote (`crates/bag/tests`); this writer only has to
//! follow the same format.

use std::path::Path;

use crate::util::{arg, iasm, json, show, sources_of};

/// The scene: two talkers beside a straight drive (the suite's `two_talkers`, with clips
/// long enough for a stop's settling and margins).
const SCENE: &str = r#"
name = "two_talkers_bag"
seed = 7
fs = 16000
clip_s = 1.4
snr_db = 30.0
[room]
dims = [6.0, 5.0, 3.0]
rt60 = 0.3
[array]
preset = "iasm6"
height = 0.8
[[sources]]
pos = [2.0, 4.0, 0.9]
signal = "speech_shaped"
level_db = 65.0
[[sources]]
pos = [4.5, 1.0, 0.9]
signal = "speech_shaped"
level_db = 65.0
[trajectory]
waypoints = [[0.8, 2.5], [5.2, 2.5]]
spacing = 0.4
"#;

const T0: i64 = 1_700_000_000_000_000_000;
const STILL_S: f64 = 1.4;
const DRIVE_S: f64 = 0.6;

/// Header fields: each a length, then `name=value`.
fn fields(f: &[(&str, &[u8])]) -> Vec<u8> {
    let mut out = Vec::new();
    for (k, v) in f {
        out.extend(((k.len() + 1 + v.len()) as u32).to_le_bytes());
        out.extend(k.as_bytes());
        out.push(b'=');
        out.extend(*v);
    }
    out
}

/// One record: its header's fields and its data, each with its length.
fn record(out: &mut Vec<u8>, f: &[(&str, &[u8])], data: &[u8]) {
    let header = fields(f);
    out.extend((header.len() as u32).to_le_bytes());
    out.extend(header);
    out.extend((data.len() as u32).to_le_bytes());
    out.extend(data);
}

fn time(ns: i64) -> Vec<u8> {
    let mut b = ((ns / 1_000_000_000) as u32).to_le_bytes().to_vec();
    b.extend(((ns % 1_000_000_000) as u32).to_le_bytes());
    b
}

fn header_msg(ns: i64, frame: &str) -> Vec<u8> {
    let mut b = 0u32.to_le_bytes().to_vec();
    b.extend(time(ns));
    b.extend((frame.len() as u32).to_le_bytes());
    b.extend(frame.as_bytes());
    b
}

fn odometry(ns: i64, x: f64, y: f64, yaw: f64) -> Vec<u8> {
    let mut b = header_msg(ns, "odom");
    b.extend(9u32.to_le_bytes());
    b.extend(b"base_link");
    let pose = [x, y, 0.0, 0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
    let rest = pose
        .iter()
        .copied()
        .chain(std::iter::repeat_n(0.0, 36 + 6 + 36));
    b.extend(rest.flat_map(f64::to_le_bytes));
    b
}

/// A bag of the run: (receipt time, connection, message) sorted by time, in chunks.
fn write_bag(path: &Path, messages: &mut [(i64, u32, Vec<u8>)], connections: &[(&str, &str)]) {
    messages.sort_by_key(|m| m.0);
    let mut body = Vec::new();
    let mut chunk = Vec::new();
    let conn_record = |out: &mut Vec<u8>, id: u32| {
        let (topic, ty) = connections[id as usize];
        // A connection's data is the fields of the connection header its publisher sent.
        let data = fields(&[
            ("topic", topic.as_bytes()),
            ("type", ty.as_bytes()),
            ("md5sum", b"*"),
        ]);
        record(
            out,
            &[
                ("op", &[0x07]),
                ("conn", &id.to_le_bytes()),
                ("topic", topic.as_bytes()),
            ],
            &data,
        );
    };
    let mut chunks = 0;
    let flush = |chunk: &mut Vec<u8>, body: &mut Vec<u8>| {
        let size = (chunk.len() as u32).to_le_bytes();
        record(
            body,
            &[("op", &[0x05]), ("compression", b"none"), ("size", &size)],
            chunk,
        );
        chunk.clear();
    };
    let mut seen = vec![false; connections.len()];
    let mut chunk_start = messages[0].0;
    for (t, conn, data) in messages.iter() {
        if !seen[*conn as usize] {
            conn_record(&mut chunk, *conn);
            seen[*conn as usize] = true;
        }
        record(
            &mut chunk,
            &[
                ("op", &[0x02]),
                ("conn", &conn.to_le_bytes()),
                ("time", &time(*t)),
            ],
            data,
        );
        if t - chunk_start > 1_000_000_000 {
            flush(&mut chunk, &mut body);
            chunks += 1;
            chunk_start = *t;
        }
    }
    flush(&mut chunk, &mut body);
    chunks += 1;
    // The bag header record, padded with spaces to 4096 bytes; the index (which this
    // writer leaves out, as a recorder that was stopped does) would follow the chunks.
    let mut out = b"#ROSBAG V2.0\n".to_vec();
    let index_pos = (out.len() + 4096 + body.len()) as u64;
    let count = (connections.len() as u32).to_le_bytes();
    let chunk_count = (chunks as u32).to_le_bytes();
    let header = fields(&[
        ("op", &[0x03]),
        ("index_pos", &index_pos.to_le_bytes()),
        ("conn_count", &count),
        ("chunk_count", &chunk_count),
    ]);
    let pad = 4096 - 8 - header.len();
    out.extend((header.len() as u32).to_le_bytes());
    out.extend(header);
    out.extend((pad as u32).to_le_bytes());
    out.extend(vec![b' '; pad]);
    out.extend(body);
    std::fs::write(path, out).unwrap();
}

/// Asserts that channel `channel` of `wav` holds `clip` (Pa) from `from_s` on, scaled by
/// `gain` and rounded to 16 bits as the bag holds it, at the samples `at`.
fn assert_clip_from(
    wav: &ssl::Audio,
    clip: &[f64],
    channel: usize,
    gain: f64,
    from_s: f64,
    at: &[usize],
) {
    let first = (from_s * 16_000.0).round() as usize;
    for &i in at {
        let want = (clip[first + i] * gain * 32767.0).round() / 32768.0;
        let got = f64::from(wav.channels()[channel][i]);
        assert!(
            (got - want).abs() < 1e-6,
            "sample {i}: {got} against {want}"
        );
    }
}

/// Asserts that `map` (`iasm map --json`) holds the scene's two talkers, each within
/// `tol` m, and no other source.
fn assert_talkers(map: &serde_json::Value, tol: f64) {
    let found = sources_of(map);
    assert_eq!(found.len(), 2, "{found:?}");
    for truth in [[2.0, 4.0], [4.5, 1.0]] {
        let d = found
            .iter()
            .map(|f| (f[0] - truth[0]).hypot(f[1] - truth[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(
            d < tol,
            "talker at {truth:?}: nearest source {d:.3} m away ({found:?})"
        );
    }
}

/// A simulated run written as a bag (see the module docs), and what went into it.
struct SimulatedBag {
    dir: tempfile::TempDir,
    bag: std::path::PathBuf,
    /// Each stop's clip (channel-major, Pa).
    clips: Vec<Vec<Vec<f64>>>,
    /// Pa to full scale.
    gain: f64,
}

/// The scene's stops as a robot records them; with `lead_in` (a clip and a pose), the
/// robot first stands there for the clip's length, then drives to the first stop.
fn simulated_bag(
    scene: &sim::scene::PreparedScene,
    lead_in: Option<(&[Vec<f64>], geom::Pose)>,
) -> SimulatedBag {
    let fs = 16_000usize;
    let clips: Vec<Vec<Vec<f64>>> = (0..scene.stops.len())
        .map(|i| scene.render_stop(i))
        .collect();
    let peak = clips
        .iter()
        .flatten()
        .chain(lead_in.iter().flat_map(|(c, _)| c.iter()))
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let gain = 0.5 / peak;

    // The run: the lead-in, a drive, then stop k's clip from lead + k * (STILL + DRIVE)
    // s, silence while driving; it ends with the last stop.
    let lead = lead_in.map_or(0.0, |(c, _)| c[0].len() as f64 / fs as f64 + DRIVE_S);
    let period = STILL_S + DRIVE_S;
    let total = lead + (scene.stops.len() - 1) as f64 * period + STILL_S;
    let frames = (total * fs as f64).round() as usize;
    let mut pcm = vec![0i16; frames * 6];
    let mut put = |at: usize, clip: &[Vec<f64>]| {
        for (c, ch) in clip.iter().enumerate() {
            for (i, v) in ch.iter().enumerate() {
                pcm[(at + i) * 6 + c] = (v * gain * 32767.0).round() as i16;
            }
        }
    };
    if let Some((clip, _)) = lead_in {
        put(0, clip);
    }
    for (k, clip) in clips.iter().enumerate() {
        put(
            ((lead + k as f64 * period) * fs as f64).round() as usize,
            clip,
        );
    }
    let mut messages = Vec::new();
    let mut info = vec![6u8];
    info.extend(16_000u32.to_le_bytes());
    info.extend(5u32.to_le_bytes());
    info.extend(b"S16LE");
    info.extend((16_000u32 * 6 * 16).to_le_bytes());
    info.extend(4u32.to_le_bytes());
    info.extend(b"wave");
    messages.push((T0, 0u32, info));
    for (k, buf) in pcm.chunks(1600 * 6).enumerate() {
        let end = T0 + ((k * 1600 + buf.len() / 6) as f64 / fs as f64 * 1e9).round() as i64;
        let mut m = header_msg(end, "mic");
        m.extend(((buf.len() * 2) as u32).to_le_bytes());
        m.extend(buf.iter().flat_map(|v| v.to_le_bytes()));
        messages.push((end + 2_000_000, 1, m));
    }
    for j in 0..=(total * 20.0) as usize {
        let t = j as f64 / 20.0;
        let pose = match lead_in {
            Some((_, at)) if t < lead => {
                // Standing, then driving to the first stop.
                let u = ((t - (lead - DRIVE_S)) / DRIVE_S).clamp(0.0, 1.0);
                let b = scene.stops[0];
                geom::Pose::new(at.x + u * (b.x - at.x), at.y + u * (b.y - at.y), at.theta)
            }
            _ => {
                let t = t - lead;
                let k = ((t / period) as usize).min(scene.stops.len() - 1);
                let u = ((t - k as f64 * period - STILL_S) / DRIVE_S).clamp(0.0, 1.0);
                let (a, b) = (
                    scene.stops[k],
                    scene.stops[(k + 1).min(scene.stops.len() - 1)],
                );
                geom::Pose::new(a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.theta)
            }
        };
        let ns = T0 + (t * 1e9).round() as i64;
        messages.push((ns + 1_000_000, 2, odometry(ns, pose.x, pose.y, pose.theta)));
    }
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("run.bag");
    write_bag(
        &bag,
        &mut messages,
        &[
            ("/audio_info", "audio_common_msgs/AudioInfo"),
            ("/audio", "audio_common_msgs/AudioDataStamped"),
            ("/odom", "nav_msgs/Odometry"),
        ],
    );
    SimulatedBag {
        dir,
        bag,
        clips,
        gain,
    }
}

#[test]
fn a_run_recorded_in_a_bag_is_mapped_from_the_stops_it_finds() {
    let (scene, _) = iasm::scenes::parse_scene(SCENE).unwrap();
    let scene = iasm::scenes::prepare(scene).unwrap();
    let fs = 16_000usize;
    let SimulatedBag {
        dir,
        bag,
        clips,
        gain,
    } = simulated_bag(&scene, None);

    let data = dir.path().join("run");
    let out = iasm(&["bag", arg(&bag), "--out", arg(&data), "--array", "iasm6"]);
    assert!(out.status.success(), "{}", show(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let n = scene.stops.len();
    assert!(stdout.contains(&format!("{n} stops")), "{stdout}");

    // Each stop's WAV is its clip from 0.3 s (the settling left out) for 0.9 s, and its pose
    // the scene's.
    let poses = iasm::dataset::read_poses(&data.join("pose/poses.csv"), false).unwrap();
    for (k, p) in poses.iter().enumerate() {
        assert!(
            (p.x - scene.stops[k].x).abs() < 1e-4 && (p.y - scene.stops[k].y).abs() < 1e-4,
            "stop {k}: {p:?}"
        );
        let wav = ssl::read_wav(&data.join(format!("audio/stop{:02}.wav", k + 1))).unwrap();
        assert_eq!(wav.num_channels(), 6);
        assert_eq!(
            wav.num_samples(),
            (0.9 * fs as f64).round() as usize,
            "stop {k}"
        );
        let last = wav.num_samples() - 1;
        assert_clip_from(&wav, &clips[k][3], 3, gain, 0.3, &[0, 1000, 9000, last]);
    }

    // And the data set maps the two talkers.
    let map = iasm(&[
        "map",
        "--dataset",
        arg(&data),
        "--method",
        "mvdr",
        "--num",
        "3",
        "--json",
    ]);
    let v = json(&map);
    assert_talkers(&v, 0.1);
}

/// A robot with a fan (60 dB SPL at 1 m, 0.36 m from the array: 9 dB above the talkers
/// there) first stands 4 s alone, then drives the scene's stops: `--noise-window` takes
/// the robot alone out of the bag as `noise/robot.wav`, and the map subtracts it.
#[test]
fn the_robot_alone_is_cut_from_the_bag_and_subtracted() {
    let fan = "[[sources]]\non_robot = true\npos = [-0.2, 0.0, -0.3]\nsignal = \"pink_noise\"\nlevel_db = 60.0\n";
    let text = SCENE.replace("[trajectory]", &format!("{fan}[trajectory]"));
    let (scene, _) = iasm::scenes::parse_scene(&text).unwrap();
    let scene = iasm::scenes::prepare(scene).unwrap();
    let alone = scene.render_robot_alone(0).unwrap();
    assert_eq!(alone[0].len(), 4 * 16_000);
    let at = geom::Pose::new(0.4, 2.5, 0.0);
    let SimulatedBag { dir, bag, gain, .. } = simulated_bag(&scene, Some((&alone, at)));
    let n = scene.stops.len();

    // Listed, the robot alone is a stop like the others.
    let out = iasm(&["bag", arg(&bag)]);
    assert!(out.status.success(), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains(&format!("{} stops", n + 1)));

    let data = dir.path().join("run");
    let out = iasm(&[
        "bag",
        arg(&bag),
        "--out",
        arg(&data),
        "--array",
        "iasm6",
        "--noise-window",
        "0.3-3.8",
    ]);
    assert!(out.status.success(), "{}", show(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("the robot alone: 0.30 - 3.80 s (3.5 s"),
        "{stdout}"
    );
    assert!(stdout.contains("the stop within it left out"), "{stdout}");
    assert!(stdout.contains(&format!("{n} stops")), "{stdout}");
    // noise/robot.wav is the robot alone from 0.3 s to 3.8 s, sample for sample.
    let wav = ssl::read_wav(&data.join("noise/robot.wav")).unwrap();
    assert_eq!((wav.num_channels(), wav.num_samples()), (6, 56_000));
    assert_clip_from(&wav, &alone[2], 2, gain, 0.3, &[0, 777, 30_000, 55_999]);
    // The map subtracts it and finds both talkers.
    let map = iasm(&[
        "map",
        "--dataset",
        arg(&data),
        "--method",
        "gcc-phat",
        "--num",
        "3",
        "--json",
    ]);
    let v = json(&map);
    assert!(
        v["noise"]
            .as_str()
            .is_some_and(|p| p.ends_with("noise/robot.wav")),
        "{v}"
    );
    assert_talkers(&v, 0.25);

    // Windows that do not fit are clear errors.
    for (window, why) in [
        ("1.0-1.5", "at least 1 s"),
        ("30-34", "no continuous audio holds it"),
    ] {
        let out = iasm(&[
            "bag",
            arg(&bag),
            "--out",
            arg(&data),
            "--force",
            "--noise-window",
            window,
        ]);
        assert_eq!(out.status.code(), Some(2), "{}", show(&out));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--noise-window") && err.contains(why), "{err}");
    }
    let out = iasm(&["bag", arg(&bag), "--noise-window", "5-2"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("must end after it starts"));
}

#[test]
fn a_bag_without_stops_or_with_a_missing_topic_is_a_clear_error() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    // The fixture's stops are 0.7 s long: none is when 1 s of audio is asked for.
    let r = iasm(&[
        "bag",
        arg(&fixtures.join("run_lz4.bag")),
        "--out",
        arg(&out),
        "--min-listen",
        "1",
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(
        err.contains("nothing written") && err.contains("no stops found (a stop: the robot within"),
        "{err}"
    );
    assert!(!out.exists());
    let r = iasm(&[
        "bag",
        arg(&fixtures.join("run_lz4.bag")),
        "--pose-topic",
        "/amcl_pose",
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run_lz4.bag") && err.contains("--pose-topic /amcl_pose: no such topic"),
        "{err}"
    );
    // More channels than the array has microphones: the hint names --channels.
    let r = iasm(&[
        "bag",
        arg(&fixtures.join("run_lz4.bag")),
        "--array",
        "iasm6",
        "--out",
        arg(&out),
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("6 microphones") && err.contains("gives 4 channels"),
        "{err}"
    );
    let r = iasm(&[
        "bag",
        arg(&fixtures.join("run_lz4.bag")),
        "--array",
        "respeaker4",
        "--channels",
        "1-5",
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("channel 5") && err.contains("channels 1 to 4"),
        "{err}"
    );
    // Not a bag at all.
    let wav = dir.path().join("x.wav");
    std::fs::write(&wav, b"RIFF\x24\0\0\0WAVEfmt ").unwrap();
    let r = iasm(&["bag", arg(&wav)]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("x.wav") && err.contains("not a ROS bag"),
        "{err}"
    );
}

#[test]
fn the_robots_map_is_written_as_a_ros_map_file_and_reads_back() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    let r = iasm(&[
        "bag",
        arg(&fixtures.join("run_bz2.bag")),
        "--out",
        arg(&out),
    ]);
    assert!(r.status.success(), "{}", show(&r));
    assert!(String::from_utf8_lossy(&r.stdout).contains("map: /map (40 x 30 cells of 0.1 m"));
    let yaml = std::fs::read_to_string(out.join("map/map.yaml")).unwrap();
    assert!(
        yaml.contains("resolution: 0.1\n") && yaml.contains("origin: [-1, -0.5, 0.0]"),
        "{yaml}"
    );
    // The grid (scripts/make_bag_fixtures.py): its border occupied, the 5 x 4 cells from
    // (10, 10) unknown, cell (20, 15) at 50 % unknown, the rest free; row 0 at the origin.
    let map = iasm::dataset::load_map(&out.join("map/map.yaml")).unwrap();
    assert_eq!((map.width(), map.height()), (40, 30));
    let cell = |x: f64, y: f64| {
        let (i, j) = map.world_to_cell([x, y]).unwrap();
        map.cell(i, j)
    };
    use asm::map::Cell;
    // Cell (i, k) of the grid has its centre at (-1 + 0.1 (i + 0.5), -0.5 + 0.1 (k + 0.5)).
    let c = |i: f64, k: f64| cell(-1.0 + 0.1 * (i + 0.5), -0.5 + 0.1 * (k + 0.5));
    assert_eq!(c(0.0, 0.0), Cell::Occupied);
    assert_eq!(c(39.0, 29.0), Cell::Occupied);
    assert_eq!(c(10.0, 10.0), Cell::Unknown);
    assert_eq!(c(14.0, 13.0), Cell::Unknown);
    assert_eq!(c(20.0, 15.0), Cell::Unknown);
    assert_eq!(c(5.0, 5.0), Cell::Free);
    assert_eq!(c(15.0, 13.0), Cell::Free);
    // The same run as a ROS 2 bag in MCAP and in SQLite (their folders), uncompressed and
    // as `ros2 bag record --compression-format zstd` compresses them (file by file, message
    // by message): the same poses and map as the ROS 1 bag's, and the same audio as each
    // other (all stamped S16LE; the ROS 1 bag's is S32LE, timed by receipt).
    let ros2_bags = [
        "run_ros2",
        "run_db3",
        "run_db3_zstd",
        "run_mcap_zstd_file",
        "run_mcap_zstd_msg",
    ];
    for ros2 in ros2_bags {
        let r = iasm(&[
            "bag",
            arg(&fixtures.join(ros2)),
            "--out",
            arg(&dir.path().join(ros2)),
        ]);
        assert!(r.status.success(), "{}", show(&r));
        for file in ["pose/poses.csv", "map/map.yaml", "map/map.pgm"] {
            let theirs = std::fs::read(dir.path().join(ros2).join(file)).unwrap();
            assert_eq!(
                std::fs::read(out.join(file)).unwrap(),
                theirs,
                "{ros2}: {file}"
            );
        }
    }
    for stop in ["audio/stop01.wav", "audio/stop02.wav"] {
        let mcap = std::fs::read(dir.path().join("run_ros2").join(stop)).unwrap();
        for other in &ros2_bags[1..] {
            assert_eq!(
                mcap,
                std::fs::read(dir.path().join(other).join(stop)).unwrap(),
                "{other}: {stop}"
            );
        }
    }
    // A bag whose poses are only in /tf: the chain map -> odom -> base_link, with the map.
    let out3 = dir.path().join("d3");
    let r = iasm(&[
        "bag",
        arg(&fixtures.join("run_zstd.mcap")),
        "--out",
        arg(&out3),
    ]);
    assert!(r.status.success(), "{}", show(&r));
    assert_eq!(
        std::fs::read_to_string(out3.join("pose/poses.csv")).unwrap(),
        "x,y,theta_deg\n3.0000,0.0000,90.0000\n3.0000,0.1500,120.0000\n"
    );
    assert!(out3.join("map/map.yaml").exists());
    // The odometry bag's map is in another frame than its poses: none is written.
    let r = iasm(&[
        "bag",
        arg(&fixtures.join("run_lz4.bag")),
        "--out",
        arg(&out),
    ]);
    assert!(r.status.success(), "{}", show(&r));
    assert!(String::from_utf8_lossy(&r.stdout).contains("the map is left out"));
    assert!(!out.join("map").exists());
}
