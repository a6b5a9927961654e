//! `iasm ssl` through the binary: DoAs of files and data sets, scores, and bad input.

use crate::util::*;

#[test]
fn ssl_finds_a_source_in_a_wav_file() {
    let dir = tempdir();
    let wav = path(&dir, "one.wav");
    write_wav(&wav, &plane_wave_recording(&iasm6(), &[-72.0], SEED), FS);
    for method in ["gcc-phat", "mvdr"] {
        let o = iasm(&["ssl", arg(&wav), "--method", method, "--num", "2", "--json"]);
        let v = json(&o);
        assert_eq!(v["schema_version"], 1);
        assert_eq!(v["method"], method);
        let doas = v["files"][0]["doas"].as_array().unwrap();
        assert!(!doas.is_empty() && doas.len() <= 2);
        let az = doas[0]["azimuth_deg"].as_f64().unwrap();
        assert!((az + 72.0).abs() < 2.0, "{method}: {az}");
    }
}

/// A data set in the published layout: a robot at three poses hearing one far source;
/// the recordings are named so that only a number-aware order matches the poses.
fn synthetic_dataset(dir: &tempfile::TempDir) -> std::path::PathBuf {
    let root = path(dir, "ds");
    std::fs::create_dir_all(root.join("audio")).unwrap();
    std::fs::create_dir_all(root.join("pose")).unwrap();
    let source = [40.0, 25.0];
    let poses = [(0.0, 0.0, 0.0), (1.0, 0.0, 90.0), (2.0, 1.0, -45.0)];
    let names = ["sub9.wav", "sub10.wav", "sub11.wav"];
    let mut csv = String::from("x,y,theta\n");
    for (k, ((x, y, th), name)) in poses.iter().zip(names).enumerate() {
        let bearing = f64::atan2(source[1] - y, source[0] - x).to_degrees();
        let az = ssl::wrap_deg(bearing - th);
        write_wav(
            &root.join("audio").join(name),
            &plane_wave_recording(&iasm6(), &[az], SEED + k as u64),
            FS,
        );
        csv.push_str(&format!("{x},{y},{th}\n"));
    }
    std::fs::write(root.join("pose/poses.csv"), csv).unwrap();
    std::fs::write(root.join("src_gt.txt"), "s1 [40.0, 25.0, 0]\n").unwrap();
    root
}

#[test]
fn ssl_dataset_writes_a_table_in_natural_order_and_scores_it() {
    let dir = tempdir();
    let root = synthetic_dataset(&dir);
    let out = path(&dir, "doas.csv");
    let o = iasm(&[
        "ssl",
        "--dataset",
        arg(&root),
        "--num",
        "1",
        "--out",
        arg(&out),
        "--header",
        "--score",
        "--json",
    ]);
    let v = json(&o);
    // Every DoA points at the source only if rows follow sub9, sub10, sub11.
    assert_eq!(v["ours"]["hits"], 3, "{v}");
    assert_eq!(v["ours"]["score"], 1.0);
    let table = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines[0], "az1_deg");
    assert_eq!(lines.len(), 4);
}

#[test]
fn ssl_scores_against_another_truth_when_given_one() {
    // The same recordings scored against a truth on the far side of the robot: no hit.
    let dir = tempdir();
    let root = synthetic_dataset(&dir);
    let elsewhere = path(&dir, "elsewhere.txt");
    std::fs::write(&elsewhere, "s1 [-40.0, -25.0, 0]\n").unwrap();
    let score = |extra: &[&str]| {
        let mut args = vec![
            "ssl",
            "--dataset",
            arg(&root),
            "--num",
            "1",
            "--score",
            "--json",
        ];
        args.extend_from_slice(extra);
        json(&iasm(&args))["ours"]["hits"].as_u64().unwrap()
    };
    assert_eq!(score(&[]), 3);
    assert_eq!(score(&["--truth", arg(&elsewhere)]), 0);
}

#[test]
fn a_missed_threshold_exits_with_status_1() {
    let dir = tempdir();
    let root = synthetic_dataset(&dir);
    // Two DoAs per recording but one source: at most half can hit.
    let o = iasm(&[
        "ssl",
        "--dataset",
        arg(&root),
        "--num",
        "2",
        "--score",
        "--min-score",
        "0.9",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", show(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("below --min-score"));
}

#[test]
fn a_scoring_option_without_score_is_refused_not_ignored() {
    // A gate that could never fail: --min-score without --score would score nothing and
    // exit 0. So would --score on single files, which have no poses or truth.
    let dir = tempdir();
    let root = synthetic_dataset(&dir);
    for flag in [
        &["--min-score", "0.9"][..],
        &["--by-distance"],
        &["--rules"],
    ] {
        let mut a = vec!["ssl", "--dataset", arg(&root)];
        a.extend_from_slice(flag);
        let o = iasm(&a);
        assert_eq!(o.status.code(), Some(2), "{flag:?}: {}", show(&o));
        assert_clear_error(&o, &[flag[0], "--score"]);
    }
    let wav = root.join("audio/sub9.wav");
    assert_clear_error(&iasm(&["ssl", arg(&wav), "--score"]), &["--score"]);
}

#[test]
fn wrong_channel_count_is_a_clear_error() {
    let dir = tempdir();
    let wav = path(&dir, "four.wav");
    let mics4 = ssl::MicArray::preset("respeaker4")
        .unwrap()
        .positions()
        .to_vec();
    write_wav(&wav, &plane_wave_recording(&mics4, &[10.0], SEED), FS);
    let o = iasm(&["ssl", arg(&wav)]);
    assert_clear_error(&o, &["four.wav", "4 channels", "6 microphones"]);
}

#[test]
fn a_file_that_is_not_a_wav_is_a_clear_error() {
    let dir = tempdir();
    let wav = path(&dir, "text.wav");
    std::fs::write(&wav, "this is a text file and not RIFF audio at all").unwrap();
    assert_clear_error(&iasm(&["ssl", arg(&wav)]), &["text.wav", "not a"]);
}

#[test]
fn an_empty_file_is_a_clear_error() {
    let dir = tempdir();
    let wav = path(&dir, "empty.wav");
    std::fs::write(&wav, "").unwrap();
    assert_clear_error(&iasm(&["ssl", arg(&wav)]), &["empty.wav"]);
}

#[test]
fn a_truncated_wav_is_a_clear_error() {
    let dir = tempdir();
    let wav = path(&dir, "cut.wav");
    write_wav(&wav, &plane_wave_recording(&iasm6(), &[10.0], SEED), FS);
    let bytes = std::fs::read(&wav).unwrap();
    std::fs::write(&wav, &bytes[..bytes.len() / 2]).unwrap();
    assert_clear_error(&iasm(&["ssl", arg(&wav)]), &["cut.wav", "truncated"]);
}

#[test]
fn a_recording_shorter_than_a_frame_is_a_clear_error() {
    let dir = tempdir();
    let wav = path(&dir, "blip.wav");
    write_wav(&wav, &vec![vec![0.01; 100]; 6], FS);
    assert_clear_error(
        &iasm(&["ssl", arg(&wav)]),
        &["blip.wav", "shorter than one"],
    );
}

/// `iasm ssl` of a recording with the array file `name` holding `text` fails with a clear
/// error that names `needles`.
fn assert_array_file_refused(name: &str, text: &str, needles: &[&str]) {
    let dir = tempdir();
    let wav = path(&dir, "x.wav");
    write_wav(&wav, &plane_wave_recording(&iasm6(), &[10.0], SEED), FS);
    let arr = path(&dir, name);
    std::fs::write(&arr, text).unwrap();
    assert_clear_error(&iasm(&["ssl", arg(&wav), "--array", arg(&arr)]), needles);
}

#[test]
fn an_array_file_with_one_microphone_is_a_clear_error() {
    assert_array_file_refused(
        "mono.toml",
        "positions = [[0.0, 0.0, 0.0]]\n",
        &["mono.toml", "at least two microphones"],
    );
}

#[test]
fn an_array_file_with_duplicate_positions_is_a_clear_error() {
    assert_array_file_refused(
        "dup.json",
        r#"{"positions": [[0,0,0],[0.1,0,0],[0.1,0,0]]}"#,
        &["dup.json", "microphones 1 and 2"],
    );
}

/// The ReSpeaker 4-mic's positions written in millimetres: 64 m across, refused by name.
#[test]
fn an_array_file_in_millimetres_is_a_clear_error() {
    assert_array_file_refused(
        "mm.toml",
        "positions = [[-32.0, 0.0, 0.0], [0.0, -32.0, 0.0], [32.0, 0.0, 0.0], [0.0, 32.0, 0.0]]\n",
        &["mm.toml", "64.000 m", "millimetres"],
    );
}

#[test]
fn an_unknown_array_or_method_is_a_clear_error() {
    let dir = tempdir();
    let wav = path(&dir, "x.wav");
    write_wav(&wav, &plane_wave_recording(&iasm6(), &[10.0], SEED), FS);
    assert_clear_error(
        &iasm(&["ssl", arg(&wav), "--array", "nosuch"]),
        &["nosuch", "iasm6"],
    );
    assert_clear_error(
        &iasm(&["ssl", arg(&wav), "--method", "musik"]),
        &["musik", "normmusic"],
    );
}

#[test]
fn a_missing_file_is_a_clear_error() {
    assert_clear_error(&iasm(&["ssl", "no/such/file.wav"]), &["no/such/file.wav"]);
}

#[test]
fn demo_maps_the_built_in_scene() {
    // Ten talkers at (1.5..7.5, 1.9 | 4.1): all found, OSPA under 0.2 m.
    let dir = tempdir();
    let png = path(&dir, "demo.png");
    let o = iasm(&["demo", "--png", arg(&png)]);
    assert!(o.status.success(), "{}", show(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("10 of 10 sources found"), "{out}");
    let ospa: f64 = out
        .split("OSPA ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|v| v.parse().ok())
        .expect("an OSPA figure");
    assert!(ospa < 0.2, "{out}");
    assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
}

#[test]
fn the_shipped_array_file_is_the_iasm6_preset() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = ssl::MicArray::from_file(&root.join("fixtures/arrays/iasm6.toml")).unwrap();
    assert_eq!(file, ssl::MicArray::preset("iasm6").unwrap());
    let s =
        iasm::settings::Settings::load(Some(&root.join("fixtures/ssl-mbss-like.toml"))).unwrap();
    assert_eq!((s.ssl.frame_len, s.ssl.block_frames), (Some(4096), 1));
    assert_eq!((s.ssl.num_peaks, s.iasm.num_doas), (4, 4));
    let s = iasm::settings::Settings::load(Some(&root.join("fixtures/ssl-pra-like.toml"))).unwrap();
    assert_eq!((s.ssl.az_step_deg, s.ssl.block_frames), (1.0, 1_000_000));
    assert_eq!(s.ssl.elevation, Some(ssl::ElevationRange::PLANE));
}

/// A data set of four stops, each hearing a loud noise source and one `quiet_db` below it,
/// both as plane waves, both within 3 m of every stop (the truth places them there).
fn loud_and_quiet_dataset(dir: &tempfile::TempDir, quiet_db: f64) -> std::path::PathBuf {
    use sim::farfield::{PlaneWave, render};
    use sim::signal::Signal;
    let root = path(dir, "lq");
    std::fs::create_dir_all(root.join("audio")).unwrap();
    std::fs::create_dir_all(root.join("pose")).unwrap();
    let (loud, quiet) = ([1.5, 1.0], [0.5, -1.5]);
    let mut csv = String::from("x,y,theta\n");
    for k in 0..4 {
        let (x, y, th) = (0.2 * k as f64, 0.0, 30.0 * k as f64);
        let az = |s: [f64; 2]| ssl::wrap_deg((s[1] - y).atan2(s[0] - x).to_degrees() - th);
        let wave = |azimuth_deg| PlaneWave {
            azimuth_deg,
            elevation_deg: 0.0,
            signal: Signal::Noise,
        };
        let n = FS as usize / 2;
        let a = render(
            &iasm6(),
            &[wave(az(loud))],
            FS,
            n,
            343.0,
            Some(30.0),
            SEED + k,
        );
        let b = render(
            &iasm6(),
            &[wave(az(quiet))],
            FS,
            n,
            343.0,
            None,
            SEED + 100 + k,
        );
        let g = 10f64.powf(quiet_db / 20.0);
        let mixed: Vec<Vec<f64>> = a
            .iter()
            .zip(&b)
            .map(|(a, b)| a.iter().zip(b).map(|(u, v)| 0.1 * (u + g * v)).collect())
            .collect();
        write_wav(&root.join(format!("audio/sub{}.wav", k + 1)), &mixed, FS);
        csv.push_str(&format!("{x},{y},{th}\n"));
    }
    std::fs::write(root.join("pose/poses.csv"), csv).unwrap();
    std::fs::write(
        root.join("src_gt.txt"),
        format!(
            "s1 [{}, {}, 0]\ns2 [{}, {}, 0]\n",
            loud[0], loud[1], quiet[0], quiet[1]
        ),
    )
    .unwrap();
    root
}

#[test]
fn rules_names_the_threshold_that_left_a_quiet_source_out() {
    // Four stops, each hearing two noise sources 3 dB apart, both within 3 m. With N = 1
    // only one of the two can be reported: the quiet one is cut at N at every stop. With
    // N = 4 but a height threshold of 0.95 (its exceptions off), the quiet one's peak,
    // lower than the loud one's, is too low at every stop. The census must say so, and
    // account for every miss once.
    let dir = tempdir();
    let root = loud_and_quiet_dataset(&dir, -3.0);
    let strict = path(&dir, "strict.toml");
    std::fs::write(
        &strict,
        "[ssl]\nmin_relative = 0.95\nincoherent_relative = 0.0\ndominance_blocks = 0\n",
    )
    .unwrap();
    // (cut at N, too low) and every missed (stop, source, reason), for `extra` flags.
    let census = |extra: &[&str]| {
        let mut a = vec![
            "ssl",
            "--dataset",
            arg(&root),
            "--method",
            "gcc-phat",
            "--score",
            "--rules",
            "--json",
        ];
        a.extend_from_slice(extra);
        let v = json(&iasm(&a));
        let r = &v["rules"];
        assert_every_miss_filed_once(r);
        let get = |k: &str| census_count(r, k);
        assert_eq!((get("pairs"), get("found")), (8, 4), "{r}");
        let missed: Vec<(u64, u64, String)> = r["missed"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| {
                (
                    m["stop"].as_u64().unwrap(),
                    m["source"].as_u64().unwrap(),
                    m["reason"].as_str().unwrap().to_owned(),
                )
            })
            .collect();
        ((get("cut_at_n"), get("low")), missed)
    };
    // Each miss is listed: the quiet source (the truth's second, index 1) at every stop.
    let every_stop = |reason: &str| {
        (0..4)
            .map(|k| (k, 1, reason.to_owned()))
            .collect::<Vec<_>>()
    };
    assert_eq!(census(&["--num", "1"]), ((4, 0), every_stop("cut_at_n")));
    assert_eq!(
        census(&["--num", "4", "--config", arg(&strict)]),
        ((0, 4), every_stop("low"))
    );
    // The table on the terminal names the rules.
    let o = iasm(&[
        "ssl",
        "--dataset",
        arg(&root),
        "--method",
        "gcc-phat",
        "--num",
        "1",
        "--score",
        "--rules",
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", show(&o));
    assert!(
        text.contains("why sources within 3 m were missed (4 of 8 pairs")
            && text.contains("cut at N by stronger DoAs"),
        "{text}"
    );
}
