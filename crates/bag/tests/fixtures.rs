//! The bags of `fixtures/bags`, written by rosbags (`scripts/make_bag_fixtures.py`), an
//! implementation of the format independent of ours. Every expected number below follows
//! from the script's definition of the run: still at (1.0, 2.0), heading 0, until 1.2 s;
//! driving to (1.15, 2.0), heading 30 degrees, until 1.8 s; still until 3.0 s; 4 channels
//! at 8 kHz whose frame i, channel c holds (37 i + 1000 c) mod 4096 - 2048.

use std::path::PathBuf;

use approx::assert_abs_diff_eq;
use geom::Pose;
use iasm_bag::{Error, ReadOptions, SampleFormat, StopOptions, TimedPose};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/bags")
        .join(name)
}

fn pattern(i: usize, c: usize) -> f32 {
    ((37 * i + 1000 * c) % 4096) as f32 - 2048.0
}

/// The run's one segment holds the 3 s of the pattern, full scale at 1 (every 997th frame
/// of every channel checked).
fn assert_every_sample(run: &iasm_bag::Run) {
    assert_eq!(run.segments[0].frames, 24_000);
    for (c, channel) in run.samples(0, 0..24_000).iter().enumerate() {
        for i in (0..24_000).step_by(997) {
            assert_eq!(channel[i], pattern(i, c) / 32768.0, "frame {i} channel {c}");
        }
    }
}

#[test]
fn the_lz4_bag_gives_every_sample_and_both_stops() {
    check_lz4_run(&iasm_bag::read_file(&fixture("run_lz4.bag"), &ReadOptions::default()).unwrap());
}

#[test]
fn a_bag_split_in_two_files_is_read_as_one_run() {
    // run_lz4.bag cut at 1.5 s as rosbag record --split cuts a run: the AudioInfo is in the
    // first file only, the audio runs on across the cut as one segment.
    check_lz4_run(&iasm_bag::read_file(&fixture("run_split"), &ReadOptions::default()).unwrap());
}

/// Everything run_lz4.bag holds (scripts/make_bag_fixtures.py).
fn check_lz4_run(run: &iasm_bag::Run) {
    assert_eq!(run.audio_topic, "/audio");
    assert_eq!(run.pose_topic, "/odom");
    assert_eq!(run.odom_topic, None);
    assert_eq!((run.format.channels, run.format.sample_rate), (4, 8000));
    assert_eq!(run.format.sample, SampleFormat::S16LE);
    assert_eq!(run.truncated, None);
    let counts: Vec<(&str, usize)> = run
        .topics
        .iter()
        .map(|t| (t.topic.as_str(), t.messages))
        .collect();
    assert_eq!(
        counts,
        vec![
            ("/audio_info", 1),
            ("/audio", 30),
            ("/odom", 61),
            ("/map", 1)
        ]
    );
    // The robot's map is in the frame "map", the odometry in "odom": not taken.
    assert_eq!(run.pose_frame.as_deref(), Some("odom"));
    assert_eq!(run.map_topic.as_deref(), Some("/map"));
    assert!(run.map.is_none());
    assert!(
        run.notes.iter().any(|n| n.contains("the map is left out")),
        "{:?}",
        run.notes
    );

    // One continuous segment from the run's start (the stamps end each 0.1-s buffer).
    assert_eq!(run.segments.len(), 1);
    let seg = &run.segments[0];
    assert_abs_diff_eq!(seg.start_s, 0.0, epsilon = 1e-9);
    assert_eq!(seg.frames, 24_000);
    assert_every_sample(run);

    let stops = run.stops(&StopOptions::default()).unwrap();
    assert_eq!(stops.len(), 2);
    let expected = [
        ((0.0, 1.2), (0.3, 1.0), (1.0, 2.0, 0.0)),
        ((1.8, 3.0), (2.1, 2.8), (1.15, 2.0, 30.0)),
    ];
    for (s, (still, listen, (x, y, deg))) in stops.iter().zip(expected) {
        assert_abs_diff_eq!(s.still_s.0, still.0, epsilon = 1e-6);
        assert_abs_diff_eq!(s.still_s.1, still.1, epsilon = 1e-6);
        assert_abs_diff_eq!(s.listen_s.0, listen.0, epsilon = 1e-6);
        assert_abs_diff_eq!(s.listen_s.1, listen.1, epsilon = 1e-6);
        assert_abs_diff_eq!(s.pose.x, x, epsilon = 1e-9);
        assert_abs_diff_eq!(s.pose.y, y, epsilon = 1e-9);
        assert_abs_diff_eq!(s.pose.theta_deg(), deg, epsilon = 1e-9);
        // The window's samples are the run's at those times.
        let first = (listen.0 * 8000.0_f64).round() as usize;
        let audio = run.stop_audio(s);
        assert_eq!(audio.len(), 4);
        assert_eq!(
            audio[0].len(),
            ((listen.1 - listen.0) * 8000.0_f64).round() as usize
        );
        assert_eq!(audio[2][0], pattern(first, 2) / 32768.0);
    }
}

#[test]
fn the_bz2_bag_takes_the_map_frame_poses_and_finds_stops_by_odometry() {
    let run = iasm_bag::read_file(&fixture("run_bz2.bag"), &ReadOptions::default()).unwrap();
    assert_eq!(run.audio_topic, "/mic/audio");
    assert_eq!(run.format.sample, SampleFormat::S32LE);
    assert_eq!(
        run.pose_topic, "/robot_pose",
        "the one pose topic that is not odometry"
    );
    assert_eq!(run.odom_topic.as_deref(), Some("/odom"));
    assert!(
        run.notes.iter().any(|n| n.contains("/robot_pose")),
        "{:?}",
        run.notes
    );
    // Unstamped audio: timed by receipt, 3 ms after each buffer ends.
    assert_abs_diff_eq!(run.segments[0].start_s, 0.003, epsilon = 1e-9);
    assert_eq!(run.samples(0, 1234..1235)[3][0], pattern(1234, 3) / 32768.0);
    let stops = run.stops(&StopOptions::default()).unwrap();
    assert_eq!(stops.len(), 2);
    // The poses are /robot_pose's: 10 m further along x than the odometry's.
    assert_abs_diff_eq!(stops[0].pose.x, 11.0, epsilon = 1e-9);
    assert_abs_diff_eq!(stops[1].pose.x, 11.15, epsilon = 1e-9);
    assert_abs_diff_eq!(stops[1].pose.theta_deg(), 30.0, epsilon = 1e-9);

    // Named: the odometry as the poses.
    let opts = ReadOptions {
        pose_topic: Some("/odom".into()),
        ..Default::default()
    };
    let run = iasm_bag::read_file(&fixture("run_bz2.bag"), &opts).unwrap();
    assert_eq!(run.odom_topic, None);
    assert_abs_diff_eq!(
        run.stops(&StopOptions::default()).unwrap()[1].pose.x,
        1.15,
        epsilon = 1e-9
    );
}

#[test]
fn a_pose_from_before_the_stop_is_carried_to_it_by_the_odometry() {
    // The localiser's last estimate came at 1.5 s, mid-drive, in a frame turned by 90
    // degrees and shifted from the odometry's; the robot then drove on to its stop.
    let mut run = iasm_bag::read_file(&fixture("run_bz2.bag"), &ReadOptions::default()).unwrap();
    let odom_mid = run
        .odometry
        .iter()
        .find(|p| (p.t - 1.5).abs() < 1e-6)
        .unwrap()
        .pose;
    let map_from_odom = |p: Pose| {
        let (x, y) = (-p.y + 5.0, p.x - 1.0);
        Pose::new(x, y, p.theta + std::f64::consts::FRAC_PI_2)
    };
    run.poses = vec![TimedPose {
        t: 1.5,
        pose: map_from_odom(odom_mid),
    }];
    let stops = run.stops(&StopOptions::default()).unwrap();
    // The second stop, in the map's frame: the odometry's (1.15, 2.0, 30 deg) mapped.
    let want = map_from_odom(Pose::from_degrees(1.15, 2.0, 30.0));
    assert_abs_diff_eq!(stops[1].pose.x, want.x, epsilon = 1e-9);
    assert_abs_diff_eq!(stops[1].pose.y, want.y, epsilon = 1e-9);
    assert_abs_diff_eq!(stops[1].pose.theta, want.theta, epsilon = 1e-9);
}

#[test]
fn a_topic_that_is_not_there_or_not_a_pose_names_the_candidates() {
    let e = iasm_bag::read_file(
        &fixture("run_bz2.bag"),
        &ReadOptions {
            pose_topic: Some("/amcl_pose".into()),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("--pose-topic /amcl_pose: no such topic"), "{e}");
    assert!(
        e.contains("/odom (nav_msgs/Odometry, 61 messages)") && e.contains("/robot_pose"),
        "{e}"
    );
    let e = iasm_bag::read_file(
        &fixture("run_bz2.bag"),
        &ReadOptions {
            pose_topic: Some("/mic/audio".into()),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("is not a pose message"), "{e}");
}

#[test]
fn a_format_given_by_hand_that_does_not_fit_is_an_error() {
    // The bag's frames are 4 channels of 32 bits (16 bytes; 384 000 bytes in 3 s at 8 kHz).
    let read = |channels, sample_rate, sample| {
        let format = iasm_bag::AudioFormat {
            channels,
            sample_rate,
            sample,
        };
        let opts = ReadOptions {
            format: Some(format),
            ..Default::default()
        };
        iasm_bag::read_file(&fixture("run_bz2.bag"), &opts)
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    // 7 x 2 bytes do not divide the bytes.
    let e = read(7, 8000, SampleFormat::S16LE).unwrap_err();
    assert!(
        e.contains("not whole frames") && e.contains("/mic/audio"),
        "{e}"
    );
    // 6 x 2 bytes do, but make 4 s of the 3 s the messages span (the span counts the
    // first message as long as the format given makes it); 4 x 2 bytes at 8 kHz
    // make 6 s, and the right frames at 16 kHz 1.5 s.
    for (ch, fs, sample, heard) in [
        (6, 8000, SampleFormat::S16LE, "4.00 s"),
        (4, 8000, SampleFormat::S16LE, "6.00 s"),
        (4, 16000, SampleFormat::S32LE, "1.50 s"),
    ] {
        let e = read(ch, fs, sample).unwrap_err();
        assert!(
            e.contains(&format!("would last {heard}")) && e.contains("messages span"),
            "{e}"
        );
    }
    assert!(read(4, 8000, SampleFormat::S32LE).is_ok());
}

#[test]
fn a_bag_cut_off_anywhere_reads_up_to_its_last_whole_record_or_says_why_not() {
    let bytes = std::fs::read(fixture("run_lz4.bag")).unwrap();
    let whole = iasm_bag::read(bytes.as_slice(), &ReadOptions::default()).unwrap();
    let mut read_some = 0;
    for cut in (0..bytes.len()).step_by(211) {
        match iasm_bag::read(&bytes[..cut], &ReadOptions::default()) {
            Ok(run) => {
                assert!(run.truncated.is_some() || cut == bytes.len());
                let frames: usize = run.segments.iter().map(|s| s.frames).sum();
                assert!(frames <= whole.segments[0].frames);
                read_some += 1;
            }
            Err(Error::NotABag { .. } | Error::Topic(_) | Error::Audio(_)) => {}
            Err(e) => panic!("cut at {cut}: {e}"),
        }
    }
    assert!(read_some > 0, "some cut-off bag still holds a run");
}

#[test]
fn files_that_are_not_ros_1_bags_say_what_they_are() {
    let e = |b: &[u8]| {
        iasm_bag::read(b, &ReadOptions::default())
            .unwrap_err()
            .to_string()
    };
    assert!(e(b"SQLite format 3\0....").contains("iasm_bag::read_file"));
    assert!(e(b"\x89MCAP0\r\n").contains("MCAP"));
    assert!(e(b"#ROSBAG V1.2\n").contains("format 1.2"));
    assert!(e(b"RIFF....WAVEfmt ").contains("not #ROSBAG V2.0"));
    assert!(e(b"").contains("empty"));
}

#[test]
fn the_robots_map_in_the_poses_frame_is_read_cell_for_cell() {
    let run = iasm_bag::read_file(&fixture("run_bz2.bag"), &ReadOptions::default()).unwrap();
    assert_eq!(run.pose_frame.as_deref(), Some("map"));
    let g = run.map.expect("the map, in the poses' frame");
    assert_eq!((g.width, g.height, g.frame_id.as_str()), (40, 30, "map"));
    assert_eq!(g.resolution, 0.1);
    assert_eq!((g.origin.x, g.origin.y, g.origin.theta), (-1.0, -0.5, 0.0));
    let at = |i: usize, j: usize| g.data[j * g.width + i];
    assert_eq!(
        (at(0, 0), at(39, 29), at(5, 0), at(0, 7)),
        (100, 100, 100, 100)
    );
    assert_eq!(
        (at(10, 10), at(14, 13), at(15, 13), at(20, 15), at(5, 5)),
        (-1, -1, 0, 50, 0)
    );
    // Asked for none, none is taken.
    let opts = ReadOptions {
        map_topic: Some(String::new()),
        ..Default::default()
    };
    assert!(
        iasm_bag::read_file(&fixture("run_bz2.bag"), &opts)
            .unwrap()
            .map
            .is_none()
    );
}

#[test]
fn the_ros2_mcap_bag_gives_the_same_run_in_cdr() {
    // The folder, and its .mcap file alone.
    // (And the same bag in rosbag2's SQLite storage, Humble's default; and both as
    // `ros2 bag record --compression-format zstd` compresses them: the SQLite file whole,
    // the MCAP file whole in two zstd frames, and the MCAP bag message by message.)
    for path in [
        fixture("run_ros2"),
        fixture("run_ros2/run_ros2.mcap"),
        fixture("run_db3"),
        fixture("run_db3/run_db3.db3"),
        fixture("run_db3_zstd"),
        fixture("run_db3_zstd/run_db3_zstd.db3.zstd"),
        fixture("run_mcap_zstd_file"),
        fixture("run_mcap_zstd_file/run_mcap_zstd_file.mcap.zstd"),
        fixture("run_mcap_zstd_msg"),
        fixture("run_mcap_zstd_msg/run_mcap_zstd_msg.mcap"),
    ] {
        let run = iasm_bag::read_file(&path, &ReadOptions::default()).unwrap();
        assert_eq!(run.audio_topic, "/mic/audio");
        assert_eq!((run.format.channels, run.format.sample_rate), (4, 8000));
        assert_eq!(run.format.sample, SampleFormat::S16LE);
        assert_eq!(run.pose_topic, "/robot_pose");
        assert_eq!(run.odom_topic.as_deref(), Some("/odom"));
        assert_eq!(run.pose_frame.as_deref(), Some("map"));
        let counts: Vec<(&str, usize)> = run
            .topics
            .iter()
            .map(|t| (t.topic.as_str(), t.messages))
            .collect();
        for want in [
            ("/mic/audio", 30),
            ("/odom", 61),
            ("/robot_pose", 16),
            ("/map", 1),
            ("/mic/audio_info", 1),
        ] {
            assert!(counts.contains(&want), "{want:?} in {counts:?}");
        }
        // Stamped at each buffer's end: the audio starts with the run.
        assert_eq!(run.segments.len(), 1);
        assert_abs_diff_eq!(run.segments[0].start_s, 0.0, epsilon = 1e-9);
        assert_eq!(run.segments[0].frames, 24_000);
        assert_every_sample(&run);
        let stops = run.stops(&StopOptions::default()).unwrap();
        assert_eq!(stops.len(), 2);
        assert_abs_diff_eq!(stops[0].listen_s.0, 0.3, epsilon = 1e-6);
        assert_abs_diff_eq!(stops[1].listen_s.1, 2.8, epsilon = 1e-6);
        assert_abs_diff_eq!(stops[1].pose.x, 11.15, epsilon = 1e-9);
        assert_abs_diff_eq!(stops[1].pose.theta_deg(), 30.0, epsilon = 1e-9);
        let g = run.map.expect("the map, in the poses' frame");
        assert_eq!((g.width, g.height, g.resolution), (40, 30, 0.1));
        assert_eq!(
            (
                g.data[0],
                g.data[10 * 40 + 10],
                g.data[15 * 40 + 20],
                g.data[5 * 40 + 5]
            ),
            (100, -1, 50, 0)
        );
    }
}

#[test]
fn a_compressed_bag_that_does_not_decompress_is_named_and_leaves_no_file_behind() {
    let dir = std::env::temp_dir().join(format!("iasm-bag-zstd-{}", std::process::id()));
    let temporaries = || {
        std::fs::read_dir(std::env::temp_dir())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".db3"))
            .filter(|e| e.file_name().to_string_lossy().starts_with("iasm-bag-"))
            .count()
    };
    let before = temporaries();
    std::fs::create_dir_all(&dir).unwrap();
    // Decompressed beside its compressed original (as `zstd -d` leaves it): read once.
    let both = dir.join("both");
    std::fs::create_dir_all(&both).unwrap();
    let zstd = std::fs::read(fixture("run_db3_zstd/run_db3_zstd.db3.zstd")).unwrap();
    std::fs::write(both.join("run_db3_zstd.db3.zstd"), zstd).unwrap();
    std::fs::copy(
        fixture("run_db3/run_db3.db3"),
        both.join("run_db3_zstd.db3"),
    )
    .unwrap();
    let run = iasm_bag::read_file(&both, &ReadOptions::default()).unwrap();
    let audio = run.topics.iter().find(|t| t.topic == "/mic/audio").unwrap();
    assert_eq!(audio.messages, 30);
    // A whole SQLite file read once more: its temporary copy is gone after.
    iasm_bag::read_file(&fixture("run_db3_zstd"), &ReadOptions::default()).unwrap();
    assert_eq!(temporaries(), before);
    for (name, len) in [
        ("run_db3_zstd/run_db3_zstd.db3.zstd", 10_000),
        ("run_mcap_zstd_file/run_mcap_zstd_file.mcap.zstd", 20_000),
    ] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        let file = name.split('/').next_back().unwrap();
        // Cut off inside its (first) frame, and a zstd header over bytes that are not.
        for (k, damaged) in [
            bytes[..len].to_vec(),
            [&bytes[..4], b"not a zstd frame at all".as_slice()].concat(),
        ]
        .into_iter()
        .enumerate()
        {
            let sub = dir.join(format!("{k}"));
            std::fs::create_dir_all(&sub).unwrap();
            let p = sub.join(file);
            std::fs::write(&p, damaged).unwrap();
            for path in [&p, &sub] {
                let e = iasm_bag::read_file(path, &ReadOptions::default()).unwrap_err();
                let text = e.to_string();
                assert!(
                    text.contains(&p.display().to_string()) && text.contains("zstd"),
                    "{file} ({k}): {text}"
                );
            }
        }
    }
    assert_eq!(temporaries(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_ros2_bag_cut_off_is_read_up_to_the_cut() {
    let bytes = std::fs::read(fixture("run_zstd.mcap")).unwrap();
    let dir = std::env::temp_dir().join(format!("iasm-bag-cut-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut read_some = 0;
    for cut in (0..bytes.len()).step_by(1021) {
        let p = dir.join("cut.mcap");
        std::fs::write(&p, &bytes[..cut]).unwrap();
        match iasm_bag::read_file(&p, &ReadOptions::default()) {
            Ok(run) => {
                assert!(run.truncated.is_some());
                read_some += 1;
            }
            Err(Error::NotABag { .. } | Error::Topic(_) | Error::Audio(_)) => {}
            Err(e) => panic!("cut at {cut}: {e}"),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(read_some > 0, "some cut-off bag still holds a run");
}

#[test]
fn a_ros2_sqlite_bag_that_is_not_one_or_is_compressed_says_so() {
    let dir = std::env::temp_dir().join(format!("iasm-bag-db3-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // SQLite's magic and nothing else: SQLite refuses it, and the error says so.
    std::fs::write(dir.join("run_0.db3"), b"SQLite format 3\0").unwrap();
    let e = iasm_bag::read_file(&dir, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("SQLite database"), "{e}");
    // A bag compressed file by file, whose file is a zstd frame's magic alone.
    std::fs::remove_file(dir.join("run_0.db3")).unwrap();
    std::fs::write(dir.join("run_0.db3.zstd"), b"(\xb5/\xfd").unwrap();
    let e = iasm_bag::read_file(&dir, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        e.contains("run_0.db3.zstd: a zstd-compressed file that does not decompress"),
        "{e}"
    );
}

#[test]
fn poses_from_tf_compose_the_localiser_and_the_odometry() {
    // /tf: map -> odom is (5.0, -1.0) turned by 90 degrees, odom -> base_link the odometry;
    // /tf_static: base_link -> laser 0.2 m ahead. The stops in the map: the odometry's
    // (1.0, 2.0, 0) and (1.15, 2.0, 30 deg) turned by 90 degrees and moved by (5, -1).
    // Named in the bags that have pose topics too; the zstd bag's (written by Foxglove's
    // MCAP writer in zstd chunks, as ros2 bag record compresses by default) are only in /tf,
    // which is then taken without being named.
    for path in [
        fixture("run_bz2.bag"),
        fixture("run_ros2"),
        fixture("run_zstd.mcap"),
    ] {
        let named = !path.ends_with("run_zstd.mcap");
        let opts = ReadOptions {
            pose_topic: named.then(|| "/tf".into()),
            ..Default::default()
        };
        let run = iasm_bag::read_file(&path, &opts).unwrap();
        if !named {
            // Every sample of the zstd chunks, as the run wrote it.
            assert_eq!(run.segments[0].frames, 24_000);
            assert_every_sample(&run);
        }
        assert_eq!(run.pose_topic, "/tf (map -> base_link)");
        assert_eq!(run.odom_topic.as_deref(), Some("/tf (odom -> base_link)"));
        assert_eq!(run.pose_frame.as_deref(), Some("map"));
        assert!(run.map.is_some(), "the map is in the poses' frame");
        let stops = run.stops(&StopOptions::default()).unwrap();
        assert_eq!(stops.len(), 2, "{path:?}");
        for (s, (x, y, deg)) in stops.iter().zip([(3.0, 0.0, 90.0), (3.0, 0.15, 120.0)]) {
            assert_abs_diff_eq!(s.pose.x, x, epsilon = 1e-9);
            assert_abs_diff_eq!(s.pose.y, y, epsilon = 1e-9);
            assert_abs_diff_eq!(s.pose.theta_deg(), deg, epsilon = 1e-9);
        }
        // The laser's frame, 0.2 m ahead of the base through the static link.
        let opts = ReadOptions {
            base_frame: Some("laser".into()),
            ..opts
        };
        let run = iasm_bag::read_file(&path, &opts).unwrap();
        let s = &run.stops(&StopOptions::default()).unwrap()[1];
        let a = 120f64.to_radians();
        assert_abs_diff_eq!(s.pose.x, 3.0 + 0.2 * a.cos(), epsilon = 1e-9);
        assert_abs_diff_eq!(s.pose.y, 0.15 + 0.2 * a.sin(), epsilon = 1e-9);
        // A frame the tree does not have is named in the error, with the frames it has.
        let opts = ReadOptions {
            base_frame: Some("base_footprint".into()),
            ..opts
        };
        let e = iasm_bag::read_file(&path, &opts).unwrap_err().to_string();
        assert!(
            e.contains("no transform has base_footprint as its child"),
            "{e}"
        );
    }
}

#[test]
fn a_bag_with_bytes_changed_anywhere_is_read_or_refused_never_a_panic() {
    // 400 copies of each fixture with 1-8 bytes overwritten at places drawn by a fixed
    // generator: a corrupt length, op, count, stamp or sample must give a run or an error,
    // and soon (mcap 0.24's own zstd path spun forever on one of these).
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let dir = std::env::temp_dir().join(format!("iasm-bag-mutate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for name in [
        "run_lz4.bag",
        "run_bz2.bag",
        "run_zstd.mcap",
        "run_ros2/run_ros2.mcap",
        "run_audiostamped.mcap",
        "run_db3/run_db3.db3",
        "run_db3_zstd/run_db3_zstd.db3.zstd",
        "run_mcap_zstd_msg/run_mcap_zstd_msg.mcap",
    ] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        for _ in 0..400 {
            let mut b = bytes.clone();
            for _ in 0..1 + next() % 8 {
                let at = (next() % b.len() as u64) as usize;
                b[at] = next() as u8;
            }
            let path = dir.join(name.replace('/', "_"));
            std::fs::write(&path, &b).unwrap();
            let _ = iasm_bag::read_file(&path, &ReadOptions::default()).map(|run| {
                run.stops(&StopOptions::default())
                    .map(|stops| stops.iter().map(|s| run.stop_audio(s).len()).sum::<usize>())
            });
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn audio_stamped_messages_carry_their_own_format() {
    // The ROS 2 audio_common of audio_capturer_node: AudioStamped, int16 samples, no
    // AudioInfo topic; the format is each message's own.
    let run =
        iasm_bag::read_file(&fixture("run_audiostamped.mcap"), &ReadOptions::default()).unwrap();
    assert_eq!(run.audio_topic, "/audio/in");
    assert_eq!((run.format.channels, run.format.sample_rate), (4, 8000));
    assert_eq!(run.format.sample, SampleFormat::S16LE);
    assert_eq!(run.segments.len(), 1);
    // The run starts with its first message, the odometry's at 1 ms; the audio's stamps
    // put its first sample at 0, 1 ms before.
    assert_abs_diff_eq!(run.segments[0].start_s, -0.001, epsilon = 1e-9);
    assert_eq!(run.segments[0].frames, 24_000);
    assert_every_sample(&run);
    let stops = run.stops(&StopOptions::default()).unwrap();
    assert_eq!(stops.len(), 2);
    assert_abs_diff_eq!(stops[1].pose.x, 1.15, epsilon = 1e-9);
    assert!(run.map.is_none());
}

#[test]
fn an_mcap_chunk_whose_checksum_fails_is_refused() {
    // run_zstd.mcap's first chunk carries the CRC-32 0x428fbdb2 of its records (Foxglove's
    // writer computes it); changed by one bit, the chunk is refused, not read.
    let mut bytes = std::fs::read(fixture("run_zstd.mcap")).unwrap();
    let crc = 0x428f_bdb2u32.to_le_bytes();
    let at = bytes
        .windows(4)
        .position(|w| w == crc)
        .expect("the first chunk's CRC");
    bytes[at] ^= 1;
    let dir = std::env::temp_dir().join(format!("iasm-bag-crc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("crc.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let e = iasm_bag::read_file(&path, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(
        e.contains("checksum is 428fbdb2 where its header says 428fbdb3"),
        "{e}"
    );
}

/// A run fed to [`iasm_bag::live::Recorder`] message by message, asking for finished stops
/// after each, hands on the stops the whole bag has, each once, as soon as the robot has
/// left it (the first while the robot drives, at 1.2-1.8 s; the last only when the run
/// ends), with the same pose and audio.
#[test]
fn a_run_fed_live_gives_each_stop_once_as_soon_as_the_robot_leaves_it() {
    for name in ["run_ros2", "run_audiostamped.mcap", "run_zstd.mcap"] {
        let whole = iasm_bag::read_file(&fixture(name), &ReadOptions::default()).unwrap();
        let want = whole.stops(&StopOptions::default()).unwrap();
        assert_eq!(want.len(), 2, "{name}");
        let mut live = iasm_bag::live::Recorder::new(ReadOptions::default());
        let mut got: Vec<(i64, iasm_bag::live::LiveStop)> = Vec::new();
        iasm_bag::ros2::scan_files(&fixture(name), |m| {
            live.push(
                &m.connection.topic,
                &m.connection.msg_type,
                m.time_ns,
                m.data,
            )
            .unwrap();
            if live.run().is_ok() {
                for s in live.finished_stops(&StopOptions::default(), false).unwrap() {
                    got.push((m.time_ns, s));
                }
            }
            Ok(())
        })
        .unwrap();
        assert_eq!(
            got.len(),
            1,
            "{name}: only the first stop is left while recording"
        );
        let t0 = whole.start_ns;
        let handed = (got[0].0 - t0) as f64 * 1e-9;
        assert!(
            (1.2..1.9).contains(&handed),
            "{name}: handed on at {handed} s"
        );
        got.extend(
            live.finished_stops(&StopOptions::default(), true)
                .unwrap()
                .into_iter()
                .map(|s| (0, s)),
        );
        assert_eq!(got.len(), 2, "{name}");
        for ((_, g), w) in got.iter().zip(&want) {
            assert_eq!(g.run_start_ns, t0);
            assert_eq!(g.stop.pose, w.pose, "{name}");
            // Times on the clock of the audio left after the first stop: equal to rounding.
            assert_abs_diff_eq!(g.stop.listen_s.0, w.listen_s.0, epsilon = 1e-9);
            assert_abs_diff_eq!(g.stop.listen_s.1, w.listen_s.1, epsilon = 1e-9);
            assert_eq!(g.audio, whole.stop_audio(w), "{name}");
            assert_eq!(g.sample_rate, 8000);
        }
    }
}

/// A ROS 2 bag's folder names its files in `metadata.yaml`: a stray MCAP of another run
/// left beside them (here the AudioStamped run, whose topics differ) is not read into
/// this one, and a listed file that is missing is named.
// See: issue 49
#[test]
fn a_ros2_bag_folder_reads_the_files_its_metadata_names() {
    let dir = std::env::temp_dir().join(format!("iasm-bag-meta-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for f in ["metadata.yaml", "run_ros2.mcap"] {
        std::fs::copy(fixture("run_ros2").join(f), dir.join(f)).unwrap();
    }
    std::fs::copy(fixture("run_audiostamped.mcap"), dir.join("other_run.mcap")).unwrap();
    let run = iasm_bag::read_file(&dir, &ReadOptions::default()).unwrap();
    let alone = iasm_bag::read_file(&fixture("run_ros2"), &ReadOptions::default()).unwrap();
    assert_eq!(run.topics, alone.topics);
    assert!(run.topics.iter().all(|t| t.topic != "/audio/in"));
    std::fs::remove_file(dir.join("run_ros2.mcap")).unwrap();
    let e = iasm_bag::read_file(&dir, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("metadata.yaml") && e.contains("run_ros2.mcap"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Moves the header stamp of a CDR message (bytes 4..12 after the encapsulation: `sec`,
/// `nanosec`) by `shift_ns`.
fn shift_header_stamp(data: &mut [u8], shift_ns: i64) {
    let sec = i64::from(i32::from_le_bytes(data[4..8].try_into().unwrap()));
    let nsec = i64::from(u32::from_le_bytes(data[8..12].try_into().unwrap()));
    let t = sec * 1_000_000_000 + nsec + shift_ns;
    data[4..8].copy_from_slice(&(t.div_euclid(1_000_000_000) as i32).to_le_bytes());
    data[8..12].copy_from_slice(&(t.rem_euclid(1_000_000_000) as u32).to_le_bytes());
}

/// `msgs` with every `every`-th message of `topic` delivered twice.
fn twice(
    msgs: &[(String, String, i64, Vec<u8>)],
    topic: &str,
    every: usize,
) -> Vec<(String, String, i64, Vec<u8>)> {
    let mut out = Vec::new();
    let mut k = 0;
    for x in msgs {
        out.push(x.clone());
        if x.0 == topic {
            k += 1;
            if k % every == 0 {
                out.push(x.clone());
            }
        }
    }
    out
}

/// The clock faults a robot brings, generated on `sim_run.mcap` (6 stops, stamped
/// AudioStamped and Odometry): each message's header stamp (the CDR bytes 4..12, after the
/// encapsulation: `sec`, `nanosec`) moved as the fault says, the run fed to the live
/// recorder message by message as the node takes them, its stops handed on as the robot
/// leaves them. Whatever the fault, the run keeps its six stops, each paired with its own
/// pose and listening window, and one note names the topic whose stamps lied.
// See: issue 71
#[test]
fn r71_stamps_that_step_or_lie_never_pair_a_stop_with_another_place() {
    type Fault = fn(&str, i64, usize) -> i64;
    // (name, topic named in the note, the shift of a message's stamp (ns) from its topic,
    // its log time (ns since the run's start) and its index in the topic).
    let faults: [(&str, &str, Fault); 4] = [
        ("odometry stepped 3 s back at 4 s", "/odom", |t, at, _| {
            if t == "/odom" && at >= 4_000_000_000 {
                -3_000_000_000
            } else {
                0
            }
        }),
        ("odometry stepped 2 s ahead at 3 s", "/odom", |t, at, _| {
            if t == "/odom" && at >= 3_000_000_000 {
                2_000_000_000
            } else {
                0
            }
        }),
        ("one audio message 5 s early", "/audio", |t, _, i| {
            if t == "/audio" && i == 20 {
                -5_000_000_000
            } else {
                0
            }
        }),
        ("audio stepped 1.5 s back at 5 s", "/audio", |t, at, _| {
            if t == "/audio" && at >= 5_000_000_000 {
                -1_500_000_000
            } else {
                0
            }
        }),
    ];
    let path = fixture("sim_run.mcap");
    let clean = iasm_bag::read_file(&path, &ReadOptions::default()).unwrap();
    let want = clean.stops(&StopOptions::default()).unwrap();
    assert_eq!(want.len(), 6);
    for (name, topic, fault) in faults {
        let mut live = iasm_bag::live::Recorder::new(ReadOptions::default());
        let mut got = Vec::new();
        let mut index: std::collections::HashMap<String, usize> = Default::default();
        iasm_bag::ros2::scan_files(&path, |m| {
            let mut data = m.data.to_vec();
            let i = index.entry(m.connection.topic.clone()).or_default();
            let shift = fault(&m.connection.topic, m.time_ns - clean.start_ns, *i);
            *i += 1;
            if shift != 0 {
                shift_header_stamp(&mut data, shift);
            }
            live.push(
                &m.connection.topic,
                &m.connection.msg_type,
                m.time_ns,
                &data,
            )
            .unwrap();
            // As the node does: stops handed on as the robot leaves them, and what they
            // no longer need forgotten.
            if live.run().is_ok() {
                got.extend(live.finished_stops(&StopOptions::default(), false).unwrap());
            }
            Ok(())
        })
        .unwrap();
        let run = live.run().unwrap();
        got.extend(live.finished_stops(&StopOptions::default(), true).unwrap());
        assert_eq!(got.len(), want.len(), "{name}: {:?}", run.notes);
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g.stop.pose, w.pose, "{name}");
            assert_abs_diff_eq!(g.stop.listen_s.0, w.listen_s.0, epsilon = 0.05);
            assert_abs_diff_eq!(g.stop.listen_s.1, w.listen_s.1, epsilon = 0.05);
        }
        let notes = live.take_notes();
        assert!(
            notes.len() == 1 && notes[0].starts_with(topic) && notes[0].contains("timed by when"),
            "{name}: {notes:?}"
        );
    }
}

/// Audio with no pose is kept for PENDING_AUDIO_S at most: a live run whose poses never
/// come holds a bounded stretch of audio, and says it dropped the rest.
// See: issue 71
#[test]
fn r71_audio_awaiting_poses_is_bounded() {
    use iasm_bag::live::{PENDING_AUDIO_S, Recorder};
    let path = fixture("sim_run.mcap");
    let mut audio: Vec<(String, String, Vec<u8>)> = Vec::new();
    iasm_bag::ros2::scan_files(&path, |m| {
        if m.connection.topic == "/audio" {
            audio.push((
                m.connection.topic.clone(),
                m.connection.msg_type.clone(),
                m.data.to_vec(),
            ));
        }
        Ok(())
    })
    .unwrap();
    // The run's audio messages (0.1 s each) pushed over and over, ten a second, for
    // 3 minutes, and no pose.
    let mut live = Recorder::new(ReadOptions::default());
    let n = 1800;
    for k in 0..n {
        let (topic, ty, data) = &audio[k % audio.len()];
        live.push(topic, ty, k as i64 * 100_000_000, data).unwrap();
    }
    let notes = live.take_notes();
    assert!(
        notes.len() == 1 && notes[0].contains("no pose came"),
        "{notes:?}"
    );
    assert!(live.take_notes().is_empty(), "said once");
    // A bound of the user's: what is kept spans that instead.
    let mut short = Recorder::new(ReadOptions::default())
        .with_pending_audio(10.0)
        .unwrap();
    for k in 0..n {
        let (topic, ty, data) = &audio[k % audio.len()];
        short.push(topic, ty, k as i64 * 100_000_000, data).unwrap();
    }
    assert!(
        (9.8..=10.2).contains(&short.kept_audio_s()),
        "{}",
        short.kept_audio_s()
    );
    assert!(
        Recorder::new(ReadOptions::default())
            .with_pending_audio(0.0)
            .is_err()
    );
    // What is kept spans at most the bound (and a message).
    let kept = live.kept_audio_s();
    assert!(
        (PENDING_AUDIO_S - 0.2..=PENDING_AUDIO_S + 0.2).contains(&kept),
        "{kept}"
    );
}

/// Messages as a loaded network delivers them, generated on `sim_run.mcap` and fed to the
/// live recorder as the node takes them: every 10th audio message delivered twice, pairs
/// of audio messages swapped, odometry stamps jittered by up to 40 ms, every 7th odometry
/// message twice. The run keeps its six stops, each with its own pose, and the audio of
/// each stop is the clean run's (a duplicate is not heard twice, a swapped pair is put
/// back in order; jittered poses move a window by milliseconds, no more).
// See: issue 71
#[test]
fn r71_messages_duplicated_reordered_or_jittered_keep_every_stop() {
    let path = fixture("sim_run.mcap");
    let clean = iasm_bag::read_file(&path, &ReadOptions::default()).unwrap();
    let want = clean.stops(&StopOptions::default()).unwrap();
    let mut msgs: Vec<(String, String, i64, Vec<u8>)> = Vec::new();
    iasm_bag::ros2::scan_files(&path, |m| {
        msgs.push((
            m.connection.topic.clone(),
            m.connection.msg_type.clone(),
            m.time_ns,
            m.data.to_vec(),
        ));
        Ok(())
    })
    .unwrap();
    type Delivery = fn(&[(String, String, i64, Vec<u8>)]) -> Vec<(String, String, i64, Vec<u8>)>;
    let deliveries: [(&str, Delivery); 4] = [
        ("audio messages twice", |m| twice(m, "/audio", 10)),
        ("odometry twice", |m| twice(m, "/odom", 7)),
        ("audio pairs swapped", |m| {
            let mut out: Vec<_> = m.to_vec();
            let idx: Vec<usize> = (0..out.len()).filter(|&i| out[i].0 == "/audio").collect();
            for pair in idx.chunks(2).step_by(3) {
                if let [a, b] = pair {
                    // Delivered in the other order, each at the other's arrival time.
                    let (ta, tb) = (out[*a].2, out[*b].2);
                    out.swap(*a, *b);
                    out[*a].2 = ta;
                    out[*b].2 = tb;
                }
            }
            out
        }),
        ("odometry stamps jittered", |m| {
            let mut out = m.to_vec();
            let mut k: i64 = 0;
            for x in out.iter_mut().filter(|x| x.0 == "/odom") {
                k += 1;
                // -40..40 ms
                shift_header_stamp(&mut x.3, ((k * 7919) % 81 - 40) * 1_000_000);
            }
            out
        }),
    ];
    for (name, deliver) in deliveries {
        let mut live = iasm_bag::live::Recorder::new(ReadOptions::default());
        let mut got = Vec::new();
        for (topic, ty, t, data) in deliver(&msgs) {
            live.push(&topic, &ty, t, &data).unwrap();
            if live.run().is_ok() {
                got.extend(live.finished_stops(&StopOptions::default(), false).unwrap());
            }
        }
        got.extend(live.finished_stops(&StopOptions::default(), true).unwrap());
        assert_eq!(got.len(), want.len(), "{name}");
        for (g, w) in got.iter().zip(&want) {
            // The same pose (a mean over the stop's poses: to rounding when one came twice).
            assert_abs_diff_eq!(g.stop.pose.x, w.pose.x, epsilon = 1e-9);
            assert_abs_diff_eq!(g.stop.pose.y, w.pose.y, epsilon = 1e-9);
            assert_abs_diff_eq!(g.stop.pose.theta, w.pose.theta, epsilon = 1e-9);
            assert_abs_diff_eq!(g.stop.listen_s.0, w.listen_s.0, epsilon = 0.05);
            // Jittered poses move a window by a few milliseconds; the others leave it.
            if !name.contains("jittered") {
                assert!(
                    g.audio == clean.stop_audio(w),
                    "{name}: the audio of the stop at {:?}",
                    w.listen_s
                );
            }
        }
    }
}
