//! `iasm diff` through the binary: two runs through one room rendered apart (other noise,
//! another late tail), mapped, and compared; the sources kept, moved, removed and added
//! are the scene files' (`fixtures/diff`), and bad maps are clear errors.

use std::path::{Path, PathBuf};

use crate::util::*;

/// A scene of `fixtures/diff` rendered into `dir` and mapped with `method`: the map JSON.
fn mapped(dir: &tempfile::TempDir, scene: &str, method: &str) -> PathBuf {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("fixtures/diff/{scene}.toml"));
    let data = path(dir, scene);
    if !data.exists() {
        let o = iasm(&["simulate", arg(&file), "--out", arg(&data)]);
        assert!(o.status.success(), "{}", show(&o));
    }
    let out = path(dir, &format!("{scene}.{method}.json"));
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&data),
        "--method",
        method,
        "--num",
        "4",
        "--seed",
        "1",
        "--out",
        arg(&out),
    ]);
    assert!(o.status.success(), "{}", show(&o));
    out
}

fn at(v: &serde_json::Value) -> [f64; 2] {
    [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()]
}

fn near(p: [f64; 2], q: [f64; 2], tol: f64) -> bool {
    (p[0] - q[0]).hypot(p[1] - q[1]) <= tol
}

#[test]
fn two_runs_through_one_room_show_what_was_kept_moved_removed_and_added() {
    // The scene files' truth: talker A stays at (1.5, 5.3); talker B walks from (6.8, 5.2)
    // to (4.3, 5.3), 2.50 m; the hum at (0.6, 0.8) is gone; a hum at (4.8, 0.6) is new.
    let dir = tempdir();
    for method in ["gcc-phat", "mvdr"] {
        let (before, after) = (
            mapped(&dir, "before", method),
            mapped(&dir, "after", method),
        );
        let out = path(&dir, &format!("diff.{method}.json"));
        let fig = path(&dir, &format!("diff.{method}.svg"));
        let v = json(&iasm(&[
            "diff",
            arg(&before),
            arg(&after),
            "--json",
            "--out",
            arg(&out),
            "--png",
            arg(&fig),
        ]));
        assert_eq!(json_file(&out), v, "--out and --json differ");
        let counts: Vec<u64> = ["kept", "moved", "removed", "added"]
            .iter()
            .map(|k| v[k].as_u64().unwrap())
            .collect();
        assert_eq!(counts, [1, 1, 1, 1], "{method}: {v:#}");
        let change = |kind: &str| {
            v["changes"]
                .as_array()
                .unwrap()
                .iter()
                .find(|c| c["kind"] == kind)
                .unwrap()
                .clone()
        };
        let (kept, moved) = (change("kept"), change("moved"));
        let (removed, added) = (change("removed"), change("added"));
        assert!(near(at(&kept["from"]), [1.5, 5.3], 0.3), "{method}: {kept}");
        assert!(near(at(&kept["to"]), [1.5, 5.3], 0.3), "{method}: {kept}");
        assert!(
            near(at(&moved["from"]), [6.8, 5.2], 0.3),
            "{method}: {moved}"
        );
        assert!(near(at(&moved["to"]), [4.3, 5.3], 0.3), "{method}: {moved}");
        let d = moved["distance_m"].as_f64().unwrap();
        assert!((d - 2.50).abs() < 0.3, "{method}: moved {d} m");
        assert!(
            near(at(&removed["from"]), [0.6, 0.8], 0.3),
            "{method}: {removed}"
        );
        assert!(near(at(&added["to"]), [4.8, 0.6], 0.3), "{method}: {added}");
        // 2.5 m against errors of a few decimetres: the covariances leave no doubt that
        // the talker moved, nor that the hums are not each other seen a little off.
        for c in [&moved, &removed, &added] {
            assert!(c["confidence"].as_f64().unwrap() > 0.99, "{method}: {c}");
        }
        assert!(kept["p_same"].as_f64().unwrap() > 0.01, "{method}: {kept}");
        let texts = svg_texts(&fig);
        assert!(
            texts
                .iter()
                .any(|t| t.contains("1 kept, 1 moved, 1 removed, 1 added")),
            "{texts:?}"
        );
        assert!(texts.iter().any(|t| t == "moved (to the dot)"), "{texts:?}");
    }
}

#[test]
fn a_map_compared_with_itself_is_all_kept() {
    let dir = tempdir();
    let a = path(&dir, "a.json");
    std::fs::write(
        &a,
        r#"{"frame_id": "map", "sources": [
            {"x": 1.0, "y": 2.0, "covariance": [[0.01, 0.0], [0.0, 0.01]]},
            {"x": 4.0, "y": 2.0, "covariance": [[0.01, 0.0], [0.0, 0.01]], "state": "silent", "since": 5}]}"#,
    )
    .unwrap();
    let v = json(&iasm(&["diff", arg(&a), arg(&a), "--json"]));
    assert_eq!(v["kept"], 2, "{v}");
    assert_eq!(
        v["moved"].as_u64().unwrap() + v["removed"].as_u64().unwrap(),
        0
    );
    for c in v["changes"].as_array().unwrap() {
        assert_eq!(c["p_same"], 1.0);
        assert_eq!(c["distance_m"], 0.0);
    }
    assert_eq!(v["changes"][1]["silent_since"], 5);
    // The table says the state too.
    let o = iasm(&["diff", arg(&a), arg(&a)]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("silent since stop 5"));
}

#[test]
fn bad_maps_and_options_are_clear_errors() {
    let dir = tempdir();
    let good = path(&dir, "good.json");
    std::fs::write(
        &good,
        r#"{"frame_id": "map", "sources": [{"x": 1, "y": 2}]}"#,
    )
    .unwrap();
    let other = path(&dir, "odom.json");
    std::fs::write(&other, r#"{"frame_id": "odom", "sources": []}"#).unwrap();
    let broken = path(&dir, "broken.json");
    std::fs::write(&broken, "{\"sources\": [").unwrap();
    let no_y = path(&dir, "no_y.json");
    std::fs::write(&no_y, r#"{"sources": [{"x": 1, "y": 2}, {"x": 3}]}"#).unwrap();
    let missing = path(&dir, "missing.json");
    assert_clear_error(
        &iasm(&["diff", arg(&good), arg(&missing)]),
        &["missing.json"],
    );
    assert_clear_error(
        &iasm(&["diff", arg(&broken), arg(&good)]),
        &["broken.json", "not JSON"],
    );
    assert_clear_error(
        &iasm(&["diff", arg(&good), arg(&no_y)]),
        &["no_y.json", "source 1 (s2)", "\"y\""],
    );
    assert_clear_error(
        &iasm(&["diff", arg(&good), arg(&other)]),
        &["good.json", "odom.json", "one frame"],
    );
    assert_clear_error(
        &iasm(&["diff", arg(&good), arg(&good), "--floor-m=-1"]),
        &["--floor-m", "must be >= 0 m"],
    );
    assert_clear_error(
        &iasm(&["diff", arg(&good), arg(&good), "--same-p", "1"]),
        &["--same-p", "must lie in (0, 1)"],
    );
    assert_clear_error(
        &iasm(&[
            "diff",
            arg(&good),
            arg(&good),
            "--png",
            arg(&path(&dir, "fig.gif")),
        ]),
        &["fig.gif", ".png or .svg"],
    );
}
