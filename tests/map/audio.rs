//! `iasm map` from raw audio: the sources found, faulty microphones and recordings named,
//! channels picked, a continuous recording cut at the poses, and a drive through silence.

use super::*;
use crate::util::*;

#[test]
fn map_from_raw_audio_finds_the_sources() {
    // Each stop hears the two sources as plane waves from their bearings.
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let v = json(&mvdr_n2(&root, "map"));
    assert_eq!(v["doas"], "ssl:mvdr");
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.2, "{v}");
}

/// A microphone whose connector works loose for the first five stops (its channel all
/// zeros there): those recordings are localised without it, the run says so on stderr
/// (the channel, how many recordings, which), the DoA JSON marks their rows, and the map
/// still finds both sources.
#[test]
fn a_dead_microphone_is_named_and_left_out() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    for k in 1..=5 {
        zero_channel(&root.join(format!("audio/sub{k}.wav")), 3);
    }
    let out = mvdr_n2(&root, "map");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "warning: channel 4 in 5 of 20 recordings (sub1.wav, sub2.wav, sub3.wav and 2 \
             more): silent (no signal at all); localised without it"
        ),
        "{}",
        show(&out)
    );
    let v = json(&out);
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.2, "{v}");
    // The table marks the rows localised without it.
    let table = iasm(&["ssl", "--dataset", arg(&root), "--num", "2"]);
    let table = String::from_utf8_lossy(&table.stdout);
    let marked: Vec<&str> = table
        .lines()
        .filter(|l| l.ends_with("(channel 4 left out)"))
        .collect();
    assert_eq!(marked.len(), 5, "{table}");
    assert!(marked[0].contains("sub1.wav"), "{table}");
    let rows = json(&mvdr_n2(&root, "ssl"));
    let files = rows["files"].as_array().unwrap();
    for (k, f) in files.iter().enumerate() {
        let faulty = &f["faulty_channels"];
        if k < 5 {
            assert_eq!(
                faulty,
                &serde_json::json!([{"channel": 4, "left_out": true, "fault": "silent", "below_db": 300.0}]),
                "{f}"
            );
        } else {
            assert!(faulty.is_null(), "{f}");
        }
    }
}

/// A stop whose recorder wrote no sound (every sample zero) and one recorded at another
/// rate (32 kHz, its file saying so, the sources' bearings rendered at that rate): the run
/// names both on stderr, localises the second at its own rate, and the map still finds
/// both sources.
#[test]
fn a_silent_recording_and_one_at_another_rate_are_named() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    rewrite_wav(&root.join("audio/sub7.wav"), |c| {
        c.iter_mut().flatten().for_each(|v| *v = 0.0);
    });
    // Stop 9 (from 1) at 32 kHz: the same bearings as audio_dataset renders.
    let (x, y, th) = drive()[8];
    let waves: Vec<sim::farfield::PlaneWave> = AUDIO_TRUTH
        .iter()
        .map(|s| sim::farfield::PlaneWave {
            azimuth_deg: ssl::wrap_deg((s[1] - y).atan2(s[0] - x).to_degrees() - th),
            elevation_deg: 0.0,
            signal: sim::signal::Signal::Noise,
        })
        .collect();
    let mut a = sim::farfield::render(&iasm6(), &waves, 32_000, 16_000, 343.0, Some(30.0), 9);
    a.iter_mut().flatten().for_each(|v| *v *= 0.1);
    write_wav(&root.join("audio/sub9.wav"), &a, 32_000);
    let out = mvdr_n2(&root, "map");
    let err = String::from_utf8_lossy(&out.stderr);
    for needle in [
        "warning: no sound at all in 1 of 20 recordings, every sample zero (sub7.wav)",
        "warning: the recordings are sampled at 2 rates: 19 at 48000 Hz (sub1.wav, sub2.wav, \
         sub3.wav and 16 more); 1 at 32000 Hz (sub9.wav)",
    ] {
        assert!(err.contains(needle), "{needle}: {}", show(&out));
    }
    let v = json(&out);
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.2, "{v}");
    // Stop 9's DoAs are the bearings at 32 kHz too; stop 7 has none.
    let rows = json(&mvdr_n2(&root, "ssl"));
    let files = rows["files"].as_array().unwrap();
    assert_eq!(files[6]["silent"], true, "{}", files[6]);
    assert!(files[6]["doas"].as_array().unwrap().is_empty());
    assert!(files[8]["silent"].is_null(), "{}", files[8]);
    for s in AUDIO_TRUTH {
        let want = ssl::wrap_deg((s[1] - y).atan2(s[0] - x).to_degrees() - th);
        let near = files[8]["doas"]
            .as_array()
            .unwrap()
            .iter()
            .any(|d| ssl::wrap_deg(d["azimuth_deg"].as_f64().unwrap() - want).abs() < 2.0);
        assert!(near, "{want}: {}", files[8]);
    }
}

/// Recordings that hold another channel before the microphones' (a ReSpeaker's firmware
/// records its processed beam first): without `--channels` the run stops with a hint
/// that names the option; with `--channels 2-7` (or `channels` in the settings file) the
/// map finds both sources, `iasm watch` too; a channel the files do not have, or one
/// listed twice, is a clear error.
#[test]
fn channels_pick_the_microphones_out_of_a_wider_file() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    for k in 1..=20 {
        rewrite_wav(&root.join(format!("audio/sub{k}.wav")), |c| {
            // The "beam": the sum of the microphones, as a processed channel would be.
            let beam: Vec<f64> = (0..c[0].len())
                .map(|t| c.iter().map(|ch| ch[t]).sum::<f64>() / 6.0)
                .collect();
            c.insert(0, beam);
        });
    }
    let base = [
        "map",
        "--dataset",
        arg(&root),
        "--method",
        "mvdr",
        "--num",
        "2",
    ];
    let o = iasm(&base);
    // The recordings are read in parallel: the first that fails is named, whichever.
    assert_clear_error(
        &o,
        &["audio/sub", "7 channels", "6 microphones", "--channels"],
    );
    let v = json(&iasm(
        &[&base[..], &["--channels", "2-7", "--json"]].concat(),
    ));
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.2, "{v}");
    let cfg = path(&dir, "c.toml");
    std::fs::write(&cfg, "channels = [2, 3, 4, 5, 6, 7]\n").unwrap();
    let w = json(&iasm(
        &[&base[..], &["--config", arg(&cfg), "--json"]].concat(),
    ));
    assert_eq!(w["sources"], v["sources"]);
    // `iasm watch` picks them too.
    let watch = ["watch", arg(&root), "--replay", "--num", "2"];
    assert_clear_error(&iasm(&watch), &["sub1.wav", "7 channels", "--channels"]);
    let o = iasm(&[&watch[..], &["--channels", "2-7"]].concat());
    assert!(o.status.success(), "{}", show(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let last = out.lines().rfind(|l| l.starts_with("stop ")).unwrap();
    assert!(last.contains(" 2 sources"), "{out}");
    let o = iasm(&[&base[..], &["--channels", "2-6,9"]].concat());
    assert_clear_error(&o, &["audio/sub", "channel 9", "7 channels"]);
    std::fs::write(&cfg, "channels = [2, 3, 3, 5, 6, 7]\n").unwrap();
    let o = iasm(&[&base[..], &["--config", arg(&cfg)]].concat());
    assert_clear_error(&o, &["channel 3 twice"]);
}

#[test]
fn a_continuous_recording_cut_at_the_pose_times_maps_like_one_file_per_stop() {
    // The stops' recordings end to end with 0.25 s of silence between them, one pose per
    // stop with its start time: the windows are the stops' own samples, so the map is
    // the per-stop data set's.
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let long = path(&dir, "long.wav");
    let mut spec = None;
    let mut samples: Vec<i16> = Vec::new();
    let mut times = String::from("t,x,y,theta_deg\n");
    let poses = std::fs::read_to_string(root.join("pose/poses.csv")).unwrap();
    for (k, pose) in poses.lines().enumerate() {
        let mut r = hound::WavReader::open(root.join(format!("audio/sub{}.wav", k + 1))).unwrap();
        let s = r.spec();
        let frames = r.len() as usize / usize::from(s.channels);
        let start = samples.len() / usize::from(s.channels);
        times.push_str(&format!(
            "{},{pose}\n",
            start as f64 / f64::from(s.sample_rate)
        ));
        samples.extend(r.samples::<i16>().map(Result::unwrap));
        samples.extend(std::iter::repeat_n(
            0,
            usize::from(s.channels) * (s.sample_rate as usize / 4),
        ));
        spec = Some((s, frames));
    }
    let (spec, frames) = spec.unwrap();
    let mut w = hound::WavWriter::create(&long, spec).unwrap();
    samples.iter().for_each(|&v| w.write_sample(v).unwrap());
    w.finalize().unwrap();
    let timed = path(&dir, "timed.csv");
    std::fs::write(&timed, times).unwrap();
    let window = format!("{}", frames as f64 / f64::from(spec.sample_rate));
    let per_stop = json(&iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--num",
        "2",
        "--json",
    ]));
    let room = root.join("map/room.yaml");
    let from_recording = [
        "map",
        "--map",
        arg(&room),
        "--poses",
        arg(&timed),
        "--recording",
        arg(&long),
    ];
    let truth = root.join("src_gt.txt");
    let o = iasm(
        &[
            &from_recording[..],
            &[
                "--truth",
                arg(&truth),
                "--window",
                &window,
                "--num",
                "2",
                "--json",
            ],
        ]
        .concat(),
    );
    let continuous = json(&o);
    assert_eq!(
        continuous["sources"].as_array().unwrap().len(),
        2,
        "{continuous}"
    );
    assert_eq!(continuous["sources"], per_stop["sources"]);
    // Six channels for a four-microphone array: refused with the hint to pick them.
    let o = iasm(&[&from_recording[..], &["--array", "respeaker4"]].concat());
    assert_clear_error(
        &o,
        &["long.wav", "6 channels", "4 microphones", "--channels"],
    );
    // A pose whose time lies past the recording's end is named.
    let late = std::fs::read_to_string(&timed).unwrap() + "999,1,0,0\n";
    std::fs::write(&timed, late).unwrap();
    let o = iasm(&[&from_recording[..], &["--num", "2"]].concat());
    assert_clear_error(&o, &["long.wav", "pose 21", "999 s"]);
}

/// Where nothing sounds, the map is empty. Every recording of a drive holds independent
/// noise on each channel (sensor noise, a silent room): the SSL reports no DoA (each
/// spectrum's peaks lie below `ssl::SslConfig::min_significance`), and the map has no
/// source, with both of the paper's methods. (Before the significance floor, such a data
/// set gave N random DoAs per stop and maps of 5-8 sources.)
#[test]
fn a_drive_through_silence_maps_nothing() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    let poses = drive();
    mapping_dataset(&root, &AUDIO_TRUTH, &poses);
    std::fs::create_dir_all(root.join("audio")).unwrap();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut gauss = move || {
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (u, v) = (uniform(), uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    for k in 0..poses.len() {
        let channels: Vec<Vec<f64>> = (0..6)
            .map(|_| (0..FS as usize / 2).map(|_| 0.01 * gauss()).collect())
            .collect();
        write_wav(&root.join(format!("audio/sub{}.wav", k + 1)), &channels, FS);
    }
    for method in ["gcc-phat", "mvdr"] {
        let ssl = json(&iasm(&[
            "ssl",
            "--dataset",
            arg(&root),
            "--method",
            method,
            "--json",
        ]));
        let files = ssl["files"].as_array().unwrap();
        assert_eq!(files.len(), poses.len());
        for f in files {
            assert_eq!(f["doas"].as_array().unwrap().len(), 0, "{method}: {f}");
        }
        let map = json(&iasm(&[
            "map",
            "--dataset",
            arg(&root),
            "--method",
            method,
            "--json",
        ]));
        assert_eq!(
            map["sources"].as_array().unwrap().len(),
            0,
            "{method}: {map}"
        );
    }
}
