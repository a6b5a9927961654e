//! One settings file for every command (issue 8): `[ssl]` and `[iasm]` tables reach the
//! pipeline whole, and flags override only what they name.

use crate::util::*;

/// Every `[ssl]` and `[iasm]` field away from its default (but still a sensible setting).
const EVERY_FIELD: &str = r#"
[ssl]
method = "gcc-phat"
frame_len = 2048
hop = 512
fmin_hz = 300.0
fmax_hz = 7000.0
az_step_deg = 2.0
elevation = { min_deg = -30.0, max_deg = 30.0, step_deg = 15.0 }
block_frames = 3
pooling = "mean"
pool_top = 2
placement_share = 0.5
deflate = true
deflate_max_residual = 0.5
num_peaks = 2
min_sep_deg = 15.0
min_relative = 0.2
dominance_blocks = 3
subband_votes = 5
min_prominence = 0.1
sidelobe_ratio = 2.0
min_significance = 6.0
incoherent_relative = 0.2
max_incoherence = 0.5
decay_gate_db = 12.0
decay_window_s = 0.4
speed_of_sound = 340.0
mvdr_loading = 0.2
mvdr_freq_smoothing = 1
music_sources = 3
music_freq_smoothing = 1
music_coarse = true
screen_channels = false

[iasm]
density_d = 8.0
sigma_p_m = 0.02
sigma_deg = 4.0
beta_m = 3.0
lambda_thresh_m2 = 0.05
dbscan_eps_m = 0.12
min_pts_frac = 0.12
resample_frac = 0.2
gamma_sigmas = 2.5
passes = 3
merge_dist_m = 0.4
max_rounds = 30
retries = 1
variant = "wdp"
refine = false
trim_mads = 2.5
trim_floor_deg = 1.5
min_observations = 4
vote_min_stops = 6
vote_min_thresholded_stops = 4
absence_ratio = 2.0
min_range_m = 0.25
beyond_map_m = 0.7
wall_clearance_m = 0.2
room_margin_m = 0.25
reflections = false
share_gate_sigmas = 0.4
reassociate = false
rank_gain = 0.8
"#;

// See: issue 8
#[test]
fn r8_map_honours_every_field_of_the_settings_file() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let cfg = path(&dir, "c.toml");
    std::fs::write(&cfg, EVERY_FIELD).unwrap();
    let v = json(&iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--method",
        "mvdr",
        "--config",
        arg(&cfg),
        "--json",
    ]));
    // What the file says, as the pipeline received it; `--method` overrides the file.
    let mut want: toml::Table = toml::from_str(EVERY_FIELD).unwrap();
    want["ssl"]["method"] = toml::Value::String("mvdr".into());
    // N is one number: the file's num_peaks is the mapper's num_doas too.
    want["iasm"]
        .as_table_mut()
        .unwrap()
        .insert("num_doas".into(), toml::Value::Integer(2));
    let want = serde_json::to_value(&want).unwrap();
    assert_eq!(v["ssl"], want["ssl"], "{v}");
    assert_eq!(v["params"], want["iasm"], "{v}");
    assert_eq!(v["array"], "iasm6");
    // Sources the path and absence checks removed are reported, not hidden.
    assert!(v["removed_sources"].is_u64(), "{v}");
    // The settings were used, not only echoed: no source was refined, each explains at
    // least 4 stops, and the two sources were found from DoAs localised with them.
    let sources = v["sources"].as_array().unwrap();
    assert_eq!(sources.len(), 2, "{v}");
    assert!(sources.iter().all(|s| s["refined"] == false), "{v}");
    assert!(
        sources
            .iter()
            .all(|s| s["observations"].as_u64().unwrap() >= 4),
        "{v}"
    );
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.2, "{v}");
}

// See: issue 8
#[test]
fn r8_the_settings_files_band_reaches_the_localizer() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let cfg = path(&dir, "c.toml");
    // 48 kHz recordings: a band starting at 30 kHz lies above Nyquist.
    std::fs::write(&cfg, "[ssl]\nfmin_hz = 30000.0\nfmax_hz = 40000.0\n").unwrap();
    let o = iasm(&["map", "--dataset", arg(&root), "--config", arg(&cfg)]);
    assert_clear_error(&o, &["30000"]);
    // `--fmin`/`--fmax` override the file.
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--config",
        arg(&cfg),
        "--fmin",
        "200",
        "--fmax",
        "8000",
        "--num",
        "2",
        "--json",
    ]);
    let v = json(&o);
    assert_eq!(v["ssl"]["fmin_hz"], 200.0);
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
}

// See: issue 8
#[test]
fn r8_a_settings_files_n_stands_unless_num_is_given() {
    // Three sources, a table of three DoAs per stop; the file says N = 2.
    let dir = tempdir();
    let root = path(&dir, "ds");
    mapping_dataset(&root, &[[1.5, 1.5], [4.0, -1.2], [5.5, 2.0]], &drive());
    let cfg = path(&dir, "c.toml");
    std::fs::write(&cfg, "[iasm]\nnum_doas = 2\n").unwrap();
    let doas = root.join("doas.csv");
    let base = [
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&doas),
        "--config",
        arg(&cfg),
    ];
    // N = 2 stood: of a table of three columns, the first two are mapped.
    let o = iasm(&base);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("mapping the first 2"),
        "{}",
        show(&o)
    );
    let mut json_args = base.to_vec();
    json_args.push("--json");
    let v = json(&iasm(&json_args));
    assert_eq!(v["params"]["num_doas"], 2);
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
    // --num overrides it.
    let mut args = base.to_vec();
    args.extend(["--num", "3", "--json"]);
    let v = json(&iasm(&args));
    assert_eq!(v["params"]["num_doas"], 3);
    assert_eq!(v["sources"].as_array().unwrap().len(), 3, "{v}");
}

/// A value the settings file's checks refuse names the file; one that only the recording's
/// sample rate makes wrong (a hop longer than the frame at that rate) names the recording.
#[test]
fn a_refused_setting_names_the_file_it_came_from() {
    let dir = tempdir();
    let cfg = path(&dir, "c.toml");
    let wav = path(&dir, "a.wav");
    write_wav(&wav, &plane_wave_recording(&iasm6(), &[30.0], SEED), FS);
    std::fs::write(&cfg, "[ssl]\naz_step_deg = 0.0\n").unwrap();
    let o = iasm(&["ssl", arg(&wav), "--config", arg(&cfg)]);
    assert_clear_error(
        &o,
        &["c.toml", "[ssl]", "az_step_deg = 0.0 is out of range"],
    );
    std::fs::write(&cfg, "[ssl]\nhop = 5000\n").unwrap();
    let o = iasm(&["ssl", arg(&wav), "--config", arg(&cfg)]);
    assert_clear_error(&o, &["a.wav", "[ssl]", "hop = 5000"]);
}

// See: issue 8
#[test]
fn r8_two_different_ns_in_one_file_are_a_clear_error() {
    let dir = tempdir();
    let cfg = path(&dir, "c.toml");
    std::fs::write(&cfg, "[ssl]\nnum_peaks = 3\n[iasm]\nnum_doas = 4\n").unwrap();
    let wav = path(&dir, "a.wav");
    write_wav(&wav, &plane_wave_recording(&iasm6(), &[30.0], SEED), FS);
    let o = iasm(&["ssl", arg(&wav), "--config", arg(&cfg)]);
    assert_clear_error(&o, &["c.toml", "num_peaks = 3", "num_doas = 4"]);
}

/// `--deflate` and `--no-deflate` set `ssl.deflate` for the command (by default it is
/// left to the array: `null`, deflated only for a compact one), and the map says so; the
/// two at once are refused.
#[test]
fn the_deflate_flags_reach_the_localizer() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let run = |extra: &[&str]| {
        let mut args = vec!["map", "--dataset", arg(&root), "--num", "2", "--json"];
        args.extend_from_slice(extra);
        json(&iasm(&args))
    };
    assert_eq!(run(&[])["ssl"]["deflate"], serde_json::Value::Null);
    let v = run(&["--deflate"]);
    assert_eq!(v["ssl"]["deflate"], true, "{v}");
    assert_eq!(v["sources"].as_array().unwrap().len(), 2, "{v}");
    assert_eq!(run(&["--no-deflate"])["ssl"]["deflate"], false);
    let o = iasm(&["map", "--dataset", arg(&root), "--deflate", "--no-deflate"]);
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--no-deflate"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Every numeric setting of the file, set to what a hand or a typo writes (zero, negative,
/// NaN, infinite, huge, tiny, and the values of an earlier sweep that crashed it,
/// aborted it on a 2-TB allocation or kept it busy for minutes), is either refused when the
/// file is read, with an error that names the file, the key and the range accepted, or runs
/// to a map (exit 0). None panics, aborts or runs on unbounded.
// See: issue 49
#[test]
fn r49_every_numeric_setting_is_refused_at_reading_or_maps() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let base: toml::Table = toml::from_str(EVERY_FIELD).unwrap();
    let bad: [toml::Value; 11] = [
        toml::Value::Integer(0),
        toml::Value::Integer(-1),
        toml::Value::Float(f64::NAN),
        toml::Value::Float(f64::INFINITY),
        toml::Value::Float(1e300),
        toml::Value::Float(1e-300),
        toml::Value::Float(5e-324),
        toml::Value::Float(1e-9),
        toml::Value::Integer(i64::MAX),
        toml::Value::Integer(1_000_000_000),
        toml::Value::Integer(1),
    ];
    let mut keys: Vec<(String, Option<String>)> = Vec::new();
    for table in ["ssl", "iasm"] {
        for (k, v) in base[table].as_table().unwrap() {
            match v {
                toml::Value::Integer(_) | toml::Value::Float(_) => {
                    keys.push((table.into(), Some(k.clone())))
                }
                _ => {}
            }
        }
    }
    // The elevation's step, inside its inline table.
    keys.push(("ssl".into(), None));
    let mut refused = 0;
    let mut ran = 0;
    for (table, key) in &keys {
        for value in &bad {
            let mut t = base.clone();
            let shown = match key {
                Some(k) => {
                    t[table.as_str()]
                        .as_table_mut()
                        .unwrap()
                        .insert(k.clone(), value.clone());
                    k.clone()
                }
                None => {
                    t["ssl"]["elevation"]
                        .as_table_mut()
                        .unwrap()
                        .insert("step_deg".into(), value.clone());
                    "step_deg".into()
                }
            };
            let cfg = path(&dir, "bad.toml");
            std::fs::write(&cfg, toml::to_string(&t).unwrap()).unwrap();
            let o = iasm(&[
                "map",
                "--dataset",
                arg(&root),
                "--method",
                "mvdr",
                "--config",
                arg(&cfg),
            ]);
            let err = String::from_utf8_lossy(&o.stderr);
            let what = format!("[{table}] {shown} = {value}: {}", show(&o));
            assert!(
                !err.contains("panicked") && o.status.code().is_some(),
                "{what}"
            );
            // Not a number, infinite, or beyond any room or array: never a setting.
            let absurd = match value {
                toml::Value::Float(f) => !f.is_finite() || f.abs() > 1e100,
                // A block or a pool of more blocks than a recording has is the whole
                // recording: any count is one.
                toml::Value::Integer(i) => {
                    *i == i64::MAX && !matches!(shown.as_str(), "block_frames" | "pool_top")
                }
                _ => false,
            };
            assert!(!absurd || o.status.code() == Some(2), "accepted: {what}");
            match o.status.code() {
                Some(0) => ran += 1,
                Some(2) => {
                    refused += 1;
                    assert!(err.contains("bad.toml"), "the error names the file: {what}");
                    assert!(err.contains(&shown), "the error names the key: {what}");
                }
                _ => panic!("neither a map nor a clean error: {what}"),
            }
        }
    }
    // Those accepted (a zero where zero turns a rule off, a one where one is a count, a
    // tiny fraction where any fraction is one) made a map.
    assert_eq!(refused + ran, keys.len() * bad.len());
    assert!(refused > 0 && ran > 0);
}
