//! `iasm map` and `iasm eval` through the binary: maps from DoA tables and from raw audio,
//! the picture and tables they write, and bad input.

use std::path::Path;

use crate::util::*;

const TRUTH: [[f64; 2]; 3] = [[1.5, 1.5], [4.0, -1.2], [5.5, 2.0]];

fn dataset(dir: &tempfile::TempDir) -> std::path::PathBuf {
    let root = path(dir, "ds");
    mapping_dataset(&root, &TRUTH, &drive());
    root
}

#[test]
fn map_from_a_doa_table_finds_every_source() {
    let dir = tempdir();
    let root = dataset(&dir);
    let (png, csv, out) = (
        path(&dir, "m.png"),
        path(&dir, "m.csv"),
        path(&dir, "m.json"),
    );
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
        "--seed",
        "4",
        "--png",
        arg(&png),
        "--csv",
        arg(&csv),
        "--out",
        arg(&out),
        "--json",
    ]);
    let v = json(&o);
    assert_eq!(v["schema_version"], 1);
    assert_eq!(v["seed"], 4);
    assert_eq!(v["sources"].as_array().unwrap().len(), 3, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.15, "{v}");
    assert_eq!(v["params"]["sigma_deg"], 5.0);
    // The files.
    assert_eq!(&std::fs::read(&png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 4);
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(saved, v);
}

#[test]
fn explain_names_each_sources_doas_and_where_a_missed_sources_doas_went() {
    // The three sources' exact DoAs, and a fourth true source that no stop heard of its
    // own.
    let dir = tempdir();
    let root = dataset(&dir);
    std::fs::write(
        root.join("src_gt.txt"),
        "s1 [1.5, 1.5, 0]\ns2 [4.0, -1.2, 0]\ns3 [5.5, 2.0, 0]\ns4 [2.0, -2.5, 0]\n",
    )
    .unwrap();
    let table = root.join("doas.csv");
    let base = [
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&table),
        "--num",
        "3",
        "--seed",
        "4",
        "--explain",
    ];
    let v = json(&iasm(&[&base[..], &["--json"]].concat()));
    let e = &v["explain"];
    let sources = e["sources"].as_array().unwrap();
    assert_eq!(sources.len(), 3, "{v}");
    for s in sources {
        // One DoA of each of the twenty stops, each through the source.
        let rays = s["rays"].as_array().unwrap();
        let stops: Vec<u64> = rays.iter().map(|r| r["stop"].as_u64().unwrap()).collect();
        assert_eq!(stops, (0..20).collect::<Vec<u64>>(), "{s}");
        assert!(
            rays.iter().all(|r| r["miss_deg"].as_f64().unwrap() < 0.5),
            "{s}"
        );
    }
    assert_eq!(e["unexplained"].as_array().unwrap().len(), 0, "{e}");
    let missed = e["missed"].as_array().unwrap();
    assert_eq!(missed.len(), 1, "{e}");
    assert_eq!(missed[0]["truth"], 4);
    // Where a heard source's bearing passes within 5 degrees of the unheard one's, its
    // DoA is listed, taken by the mapped source standing at that heard source.
    let hidden = [2.0f64, -2.5];
    let bearing = |(x, y, _): (f64, f64, f64), q: [f64; 2]| (q[1] - y).atan2(q[0] - x);
    let mut want = Vec::new();
    for (k, &pose) in drive().iter().enumerate() {
        let to = bearing(pose, hidden);
        let nearest = TRUTH
            .iter()
            .map(|&q| (q, ssl::wrap_deg((bearing(pose, q) - to).to_degrees()).abs()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        if nearest.1 <= 5.0 {
            let q = nearest.0;
            let at = sources
                .iter()
                .position(|s| {
                    (s["x"].as_f64().unwrap() - q[0]).hypot(s["y"].as_f64().unwrap() - q[1]) < 0.05
                })
                .unwrap();
            want.push((k as u64, at as u64 + 1));
        }
    }
    assert!(
        !want.is_empty(),
        "the layout hides the unheard source behind a heard one"
    );
    let heard: Vec<(u64, u64)> = missed[0]["heard"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| (h["stop"].as_u64().unwrap(), h["taken_by"].as_u64().unwrap()))
        .collect();
    assert_eq!(heard, want, "{e}");
    // The same on the terminal.
    let o = iasm(&base);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("every DoA is explained by a source"),
        "{text}"
    );
    let line = format!(
        "true source 4 (2.00, -2.50), no mapped source within 1 m: DoAs within 5° at {}: ",
        want[0].0
    );
    assert!(text.contains(&line), "{text}");
}

#[test]
fn without_an_occupancy_map_the_sources_are_searched_around_the_stops() {
    // The same survey with its map/ folder removed: the same three sources, a note on
    // stderr saying where they were searched, and the margin in the JSON.
    let dir = tempdir();
    let root = dataset(&dir);
    let doas = root.join("doas.csv");
    let run = |extra: &[&str]| {
        let mut args = vec!["map", "--dataset", arg(&root), "--doas", arg(&doas)];
        args.extend_from_slice(&["--num", "3", "--seed", "4", "--json"]);
        args.extend_from_slice(extra);
        iasm(&args)
    };
    let with_map = json(&run(&[]));
    assert!(with_map.get("open_margin_m").is_none(), "{with_map}");
    std::fs::remove_dir_all(root.join("map")).unwrap();
    let o = run(&[]);
    let v = json(&o);
    let note = String::from_utf8_lossy(&o.stderr);
    assert!(
        note.contains("no occupancy map") && note.contains("3 m"),
        "{note}"
    );
    assert_eq!(v["open_margin_m"], 3.0);
    let found = v["sources"].as_array().unwrap();
    assert_eq!(found.len(), 3, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.15, "{v}");
    // Every source is found within 0.1 m of where the surveyed map put it.
    for s in with_map["sources"].as_array().unwrap() {
        let (x, y) = (s["x"].as_f64().unwrap(), s["y"].as_f64().unwrap());
        assert!(
            found
                .iter()
                .any(|f| (f["x"].as_f64().unwrap() - x).hypot(f["y"].as_f64().unwrap() - y) < 0.1),
            "{s} not in {v}"
        );
    }
    // A margin that leaves a source out loses it (TRUTH[0] is 1.5 m from the path);
    // a bad margin is a clear error.
    let near = json(&run(&["--open-margin", "1.0"]));
    assert!(near["sources"].as_array().unwrap().len() < 3, "{near}");
    assert_clear_error(&run(&["--open-margin=0"]), &["margin", "poses.csv"]);
}

#[test]
fn a_truth_surveyed_in_another_frame_is_told_from_a_bad_map() {
    // The truth the map is scored against, surveyed in a frame 5 % larger, turned 3
    // degrees and shifted: the map is as good as before, and the report says so.
    let dir = tempdir();
    let root = dataset(&dir);
    let (k, r, t) = (1.05f64, 3f64.to_radians(), [0.1, -0.12]);
    let gt: String = TRUTH
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (s, c) = r.sin_cos();
            let (x, y) = (
                k * (c * p[0] - s * p[1]) + t[0],
                k * (s * p[0] + c * p[1]) + t[1],
            );
            format!("s{} [{x}, {y}, 0]\n", i + 1)
        })
        .collect();
    let moved = path(&dir, "moved_gt.txt");
    std::fs::write(&moved, gt).unwrap();
    let map = |truth: &Path| {
        json(&iasm(&[
            "map",
            "--dataset",
            arg(&root),
            "--doas",
            arg(&root.join("doas.csv")),
            "--num",
            "3",
            "--truth",
            arg(truth),
            "--json",
        ]))
    };
    let own = map(&root.join("src_gt.txt"));
    let v = map(&moved);
    let f = &v["alignment"];
    let num = |key: &str| f[key].as_f64().unwrap();
    assert_eq!(f["pairs"], 3, "{v}");
    assert!(num("mean_before_m") > 0.15, "{v}");
    assert!((num("scale") - k).abs() < 0.02, "{v}");
    assert!((num("rotation_rad").to_degrees() - 3.0).abs() < 0.5, "{v}");
    // After the transform, what is left is the map's own error, as against its own truth.
    let own_error = own["alignment"]["mean_before_m"].as_f64().unwrap();
    assert!(num("mean_after_m") < own_error + 0.02, "{v}\n{own}");
    // The truth moved back into the map's frame is where it was surveyed from.
    let back = path(&dir, "back.txt");
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
        "--truth",
        arg(&moved),
        "--write-aligned-truth",
        arg(&back),
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let text = std::fs::read_to_string(&back).unwrap();
    let got: Vec<Vec<f64>> = text
        .lines()
        .map(|l| {
            let inner = &l[l.find('[').unwrap() + 1..l.find(']').unwrap()];
            inner
                .split(',')
                .map(|v| v.trim().parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(got.len(), 3, "{text}");
    for (g, t) in got.iter().zip(&TRUTH) {
        assert!((g[0] - t[0]).hypot(g[1] - t[1]) < 0.05, "{text}");
    }
}

/// The numeric tick labels of an SVG figure.
fn ticks(texts: &[String]) -> Vec<f64> {
    texts.iter().filter_map(|t| t.parse().ok()).collect()
}

#[test]
fn the_svg_map_has_axes_in_metres_a_legend_and_a_title_and_is_cropped_to_the_scene() {
    let dir = tempdir();
    let root = dataset(&dir);
    let svg = path(&dir, "map.svg");
    let full = path(&dir, "full.SVG");
    let doas = root.join("doas.csv");
    let map = |out: &Path, extra: &[&str]| {
        let mut a = vec![
            "map",
            "--dataset",
            arg(&root),
            "--doas",
            arg(&doas),
            "--num",
            "3",
            "--png",
            arg(out),
        ];
        a.extend_from_slice(extra);
        let o = iasm(&a);
        assert!(o.status.success(), "{}", show(&o));
    };
    map(&svg, &[]);
    map(&full, &["--full-map"]);
    let texts = svg_texts(&svg);
    let has = |want: &str| texts.iter().any(|t| t.contains(want));
    for want in [
        "x (m)",
        "y (m)",
        "true source",
        "source found",
        "2-sigma ellipse",
        "trajectory",
        "stop (heading tick)",
        "particles",
    ] {
        assert!(has(want), "map.svg lacks {want:?}: {texts:?}");
    }
    // The title: data set, DoA source, variant, sources found, OSPA.
    let title = texts
        .iter()
        .find(|t| t.starts_with("ds: doas.csv, ca, 3 sources found, OSPA 0."))
        .unwrap_or_else(|| panic!("no title in {texts:?}"));
    assert!(title.ends_with(" m"), "{title}");
    // The scene spans x in [0, 5.7] and y in [-1.2, 2]; the occupancy map x in [-1, 7]
    // and y in [-3, 3]. Cropped, the axes stay within the scene and its 0.8 m margin;
    // with --full-map they reach the map's edges.
    let (crop, whole) = (ticks(&texts), ticks(&svg_texts(&full)));
    let span = |v: &[f64]| {
        (
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    };
    let ((c0, c1), (w0, w1)) = (span(&crop), span(&whole));
    assert!(
        c0 >= -2.0 - 1e-9 && c1 <= 6.5 + 1e-9,
        "cropped ticks {crop:?}"
    );
    assert!(w0 <= -2.5 && w1 >= 6.5, "full-map ticks {whole:?}");
}

#[test]
fn a_figure_of_an_unknown_format_is_refused_before_the_work() {
    let dir = tempdir();
    let root = dataset(&dir);
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
        "--png",
        arg(&path(&dir, "map.jpg")),
    ]);
    assert_clear_error(&o, &["map.jpg", ".png or .svg"]);
}

/// `iasm CMD --dataset ROOT --method mvdr --num 2 --json`.
fn mvdr_n2(root: &Path, cmd: &str) -> std::process::Output {
    iasm(&[
        cmd,
        "--dataset",
        arg(root),
        "--method",
        "mvdr",
        "--num",
        "2",
        "--json",
    ])
}

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
fn eval_reports_every_variant() {
    let dir = tempdir();
    let root = dataset(&dir);
    let v = json(&iasm(&[
        "eval",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
        "--runs",
        "4",
        "--json",
    ]));
    let names: Vec<&str> = v["variants"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["variant"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["ca", "ws", "wdp"]);
    let ca = &v["variants"][0];
    assert_eq!(ca["runs"].as_array().unwrap().len(), 4);
    assert!(ca["mean"].as_f64().unwrap() < 0.15, "{v}");
    // The spread over seeds: the worst run is one of the runs and no better than the
    // mean; the share of runs with the right count agrees with the per-run counts.
    let runs: Vec<f64> = ca["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_f64().unwrap())
        .collect();
    let worst = ca["worst"].as_f64().unwrap();
    assert!(
        runs.contains(&worst) && worst >= ca["mean"].as_f64().unwrap(),
        "{v}"
    );
    assert_eq!(
        runs[(ca["worst_seed"].as_u64().unwrap()) as usize],
        worst,
        "{v}"
    );
    let counts: Vec<u64> = ca["sources"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .collect();
    let right = counts.iter().filter(|&&c| c == 3).count() as f64 / 4.0;
    assert_eq!(ca["right_count"].as_f64().unwrap(), right, "{v}");
    // The frame fit: exact bearings in one frame leave the map where it was.
    let fit = &ca["aligned"];
    assert_eq!(fit["runs"], 4, "{v}");
    assert!(fit["mean_after_m"].as_f64().unwrap() <= fit["mean_before_m"].as_f64().unwrap() + 1e-9);
    assert!((fit["scale"].as_f64().unwrap() - 1.0).abs() < 0.02, "{v}");
    // An impossible bound fails with status 1.
    let o = iasm(&[
        "eval",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
        "--runs",
        "2",
        "--max-mean-ospa",
        "0.0",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", show(&o));
    let aligned = |bound: &str| {
        iasm(&[
            "eval",
            "--dataset",
            arg(&root),
            "--doas",
            arg(&root.join("doas.csv")),
            "--num",
            "3",
            "--runs",
            "2",
            "--max-aligned",
            bound,
        ])
    };
    assert!(aligned("0.5").status.success());
    let o = aligned("0.0");
    assert_eq!(o.status.code(), Some(1), "{}", show(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--max-aligned"));
}

#[test]
fn a_missing_map_image_falls_back_to_the_only_pgm_with_a_warning() {
    let dir = tempdir();
    let root = dataset(&dir);
    let yaml = root.join("map/room.yaml");
    let text = std::fs::read_to_string(&yaml)
        .unwrap()
        .replace("room.pgm", "0201.pgm");
    std::fs::write(&yaml, text).unwrap();
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning") && err.contains("0201.pgm") && err.contains("room.pgm"),
        "{err}"
    );
}

fn map_with(root: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["map", "--dataset", arg(root), "--num", "3"];
    args.extend_from_slice(extra);
    iasm(&args)
}

#[test]
fn poses_and_doas_of_different_lengths_are_a_clear_error() {
    let dir = tempdir();
    let root = dataset(&dir);
    let doas = std::fs::read_to_string(root.join("doas.csv")).unwrap();
    let short: String = doas.lines().take(5).map(|l| format!("{l}\n")).collect();
    std::fs::write(root.join("short.csv"), short).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("short.csv"))]);
    assert_clear_error(&o, &["5 rows of DoAs", "20 poses", "short.csv"]);
}

#[test]
fn a_nan_or_non_numeric_pose_is_a_clear_error() {
    let dir = tempdir();
    let root = dataset(&dir);
    let poses = root.join("pose/poses.csv");
    let good = std::fs::read_to_string(&poses).unwrap();
    std::fs::write(&poses, good.replacen("0.3,0,", "0.3,NaN,", 1)).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv"))]);
    assert_clear_error(&o, &["poses.csv", "row 2", "y"]);
    std::fs::write(&poses, good.replacen("0.3,0,", "0.3,north,", 1)).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv"))]);
    assert_clear_error(&o, &["poses.csv", "row 2, column 2", "north"]);
}

#[test]
fn a_map_with_no_known_cell_is_a_clear_error() {
    let dir = tempdir();
    let root = dataset(&dir);
    let mut pgm = b"P5\n160 120\n255\n".to_vec();
    pgm.extend(std::iter::repeat_n(205u8, 160 * 120));
    std::fs::write(root.join("map/room.pgm"), pgm).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv"))]);
    assert_clear_error(&o, &["room.yaml", "no known"]);
}

#[test]
fn malformed_yaml_and_pgm_are_clear_errors() {
    let dir = tempdir();
    let root = dataset(&dir);
    let yaml = root.join("map/room.yaml");
    let good = std::fs::read_to_string(&yaml).unwrap();
    std::fs::write(
        &yaml,
        good.replace("resolution: 0.05", "resolution: five cm"),
    )
    .unwrap();
    assert_clear_error(
        &map_with(&root, &["--doas", arg(&root.join("doas.csv"))]),
        &["room.yaml", "resolution"],
    );
    std::fs::write(
        &yaml,
        good.replace("origin: [-1.0, -3.0, 0.0]", "origin: [-1.0, -3.0, 0.5]"),
    )
    .unwrap();
    assert_clear_error(
        &map_with(&root, &["--doas", arg(&root.join("doas.csv"))]),
        &["room.yaml", "yaw"],
    );
    std::fs::write(&yaml, good).unwrap();
    std::fs::write(root.join("map/room.pgm"), b"P5\n160 120\n255\nshort").unwrap();
    assert_clear_error(
        &map_with(&root, &["--doas", arg(&root.join("doas.csv"))]),
        &["room.pgm", "bytes"],
    );
}

#[test]
fn a_doa_table_wider_than_n_maps_its_first_n_columns() {
    // See: issue 13. Three sources, three columns, N = 2: the first two columns (the
    // first two sources) are mapped, and stderr says so once.
    let dir = tempdir();
    let root = dataset(&dir);
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "2",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        err.matches("mapping the first 2").count(),
        1,
        "{}",
        show(&o)
    );
    let v = json(&o);
    let found = sources_of(&v);
    assert_eq!(found.len(), 2, "{v}");
    for t in &TRUTH[..2] {
        assert!(
            found.iter().any(|f| (f[0] - t[0]).hypot(f[1] - t[1]) < 0.2),
            "{v}"
        );
    }
}

// See: issue 13
#[test]
fn r13_an_absurd_map_resolution_is_a_clear_error_not_a_panic() {
    // resolution: 999999999990.05 once made the DBSCAN grid overflow its allocation.
    let dir = tempdir();
    let root = dataset(&dir);
    let yaml = root.join("map/room.yaml");
    let text = std::fs::read_to_string(&yaml)
        .unwrap()
        .replace("resolution: 0.05", "resolution: 999999999990.05");
    std::fs::write(&yaml, text).unwrap();
    let t0 = std::time::Instant::now();
    let o = iasm(&[
        "map",
        "--map",
        arg(&yaml),
        "--poses",
        arg(&root.join("pose/poses.csv")),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
    ]);
    assert_clear_error(&o, &["room.yaml", "resolution"]);
    assert!(t0.elapsed().as_secs_f64() < 5.0, "{:?}", t0.elapsed());
}

// See: issue 13
#[test]
fn r13_a_ros_exported_pose_csv_with_a_quaternion_maps_like_the_plain_table() {
    let dir = tempdir();
    let root = dataset(&dir);
    let mut ros = String::from(
        "stamp,frame_id,pose.position.x,pose.position.y,pose.position.z,\
         pose.orientation.x,pose.orientation.y,pose.orientation.z,pose.orientation.w\n",
    );
    for (k, &(x, y, th)) in drive().iter().enumerate() {
        let half = th.to_radians() / 2.0;
        ros.push_str(&format!(
            "{k}.0,map,{x},{y},0.0,0.0,0.0,{},{}\n",
            half.sin(),
            half.cos()
        ));
    }
    let ros_path = path(&dir, "ros_poses.csv");
    std::fs::write(&ros_path, ros).unwrap();
    let run = |poses: &Path| {
        json(&iasm(&[
            "map",
            "--dataset",
            arg(&root),
            "--poses",
            arg(poses),
            "--doas",
            arg(&root.join("doas.csv")),
            "--num",
            "3",
            "--json",
        ]))
    };
    let plain = run(&root.join("pose/poses.csv"));
    let v = run(&ros_path);
    assert_eq!(v["sources"].as_array().unwrap().len(), 3, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.15, "{v}");
    assert!(
        (v["ospa"]["total"].as_f64().unwrap() - plain["ospa"]["total"].as_f64().unwrap()).abs()
            < 1e-6,
        "{v}\n{plain}"
    );
}

// See: issue 13
#[test]
fn r13_a_map_yaml_with_a_quoted_hash_and_a_block_origin_is_read_as_yaml() {
    let dir = tempdir();
    let root = dataset(&dir);
    std::fs::rename(root.join("map/room.pgm"), root.join("map/room#1.pgm")).unwrap();
    std::fs::write(
        root.join("map/room.yaml"),
        "image: \"room#1.pgm\"   # quoted: the # is part of the name\nresolution: 0.05\n\
         origin:\n  - -1.0\n  - -3.0\n  - 0.0\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv")), "--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("warning"), "{}", show(&o)); // the named image was found
    let v = json(&o);
    assert_eq!(v["sources"].as_array().unwrap().len(), 3, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.15, "{v}");
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

#[test]
fn eval_and_explain_say_a_missed_source_was_refused_by_the_absence_rule() {
    // Talker A heard from all nine stops along y = -1; source B (1.5, -2.5) only from
    // stops 0, 5 and 6 (2.5-3.7 m away), while stops 1-4, 1.5-2.2 m from it, report A
    // alone (rows shorter than N: all they heard). The mapper makes B and refuses it in
    // every run: `iasm eval` counts one source missed per run, refused for the absences,
    // none never made; `iasm map --explain` names the stops that spoke against it.
    let dir = tempdir();
    let root = path(&dir, "ds");
    let (a, b) = ([3.5, 2.0], [1.5, -2.5]);
    let poses: Vec<(f64, f64, f64)> = (0..9).map(|k| (-0.5 + 0.9 * k as f64, -1.0, 0.0)).collect();
    mapping_dataset(&root, &[a, b], &poses);
    let bearing = |s: [f64; 2], p: (f64, f64, f64)| (s[1] - p.1).atan2(s[0] - p.0).to_degrees();
    let table: String = poses
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            if [0, 5, 6].contains(&k) {
                format!("{:.3},{:.3}\n", bearing(a, p), bearing(b, p))
            } else {
                format!("{:.3}\n", bearing(a, p))
            }
        })
        .collect();
    std::fs::write(root.join("doas.csv"), table).unwrap();
    let doas = root.join("doas.csv");
    let base = ["--dataset", arg(&root), "--doas", arg(&doas), "--num", "3"];
    let v = json(&iasm(
        &[&["eval"], &base[..], &["--runs", "4", "--json"]].concat(),
    ));
    let ca = &v["variants"][0];
    assert_eq!(ca["variant"], "ca");
    let missed = &ca["missed"];
    assert_eq!(missed["missed"], 1.0, "{v}");
    assert_eq!(missed["spoken_against"], 1.0, "{v}");
    assert_eq!(missed["thinly_heard"], 0.0, "{v}");
    assert_eq!(missed["misplaced"], 0.0, "{v}");
    let o = iasm(&[&["map"], &base[..], &["--seed", "2", "--explain"]].concat());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", show(&o));
    assert!(
        text.contains(
            "heard from stops 0, 5, 6: stops 1, 2, 3, 4 heard other sources and nothing there"
        ),
        "{text}"
    );
    assert!(
        text.contains("found at (1.50, -2.50) and refused (above)"),
        "{text}"
    );
    let o = iasm(&[&["eval"], &base[..], &["--runs", "2"]].concat());
    assert!(
        String::from_utf8_lossy(&o.stdout)
            .contains("1.00 for stops that heard nothing there (absence_ratio)"),
        "{}",
        show(&o)
    );
}
