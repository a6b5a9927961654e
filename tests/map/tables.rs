//! `iasm map` from DoA tables: the sources found, what `--explain` says of them, a survey
//! without a map, a truth in another frame, and the figure.

use std::path::Path;

use super::*;
use crate::util::*;

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
