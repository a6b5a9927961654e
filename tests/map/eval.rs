//! `iasm eval`: every variant reported, and a missed source's refusal said.

use super::*;
use crate::util::*;

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
