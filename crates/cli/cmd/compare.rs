//! `iasm compare`: every SSL method side by side on one data set.

use anyhow::Result;

use crate::Outcome;
use crate::args::CompareArgs;
use crate::compare::{CompareOptions, Report, compare, parse_methods, to_csv};

/// Runs `iasm compare`.
///
/// # Errors
/// Bad arguments, a data set without truth, or a failure of the pipeline.
pub fn run(a: &CompareArgs) -> Result<Outcome> {
    let settings = a
        .settings
        .settings()?
        .with_dataset_array(Some(&a.dataset))
        .with_dataset_noise(Some(&a.dataset))?;
    let opts = CompareOptions {
        methods: parse_methods(&a.methods)?,
        runs: a.runs,
        seed0: a.seed,
        ospa_c: a.report.ospa_c,
        ospa_p: a.report.ospa_p,
        open_margin_m: a.open_margin,
        rules: a.rules,
        tables: a.tables.clone(),
    };
    let t0 = std::time::Instant::now();
    // One line per stage; the stages' own progress bars (localising, mapping) show the rest.
    let report = compare(&a.dataset, &settings, &opts, &|stage, stages, what| {
        eprintln!("[{stage}/{stages}] {what}");
    })?;
    let secs = t0.elapsed().as_secs_f64();
    if a.report.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report, secs);
    }
    if let Some(dir) = &a.out {
        // Built beside the folder and swapped in whole: a run that fails part-way leaves the
        // last report as it was, never a folder of two runs' files. A folder of nothing but
        // an earlier report's files (written before the swap was) is replaced too.
        let json = serde_json::to_string_pretty(&report)?;
        crate::output::replace_dir(dir, only_report_files(dir), |d| {
            crate::output::write_atomic(&d.join("report.json"), json.as_bytes())?;
            crate::output::write_atomic(&d.join("report.csv"), to_csv(&report).as_bytes())?;
            crate::figure::comparison(&report, d)
        })?;
        if !a.report.json {
            println!(
                "report: {} (report.json, report.csv, ospa.svg, error_by_distance.svg, maps.svg)",
                dir.display()
            );
        }
    }
    Ok(Outcome::Success)
}

/// Whether `dir` holds nothing but the files `iasm compare --out` writes.
fn only_report_files(dir: &std::path::Path) -> bool {
    const OURS: [&str; 5] = [
        "report.json",
        "report.csv",
        "ospa.svg",
        "error_by_distance.svg",
        "maps.svg",
    ];
    std::fs::read_dir(dir).is_ok_and(|entries| {
        entries
            .flatten()
            .all(|e| OURS.contains(&e.file_name().to_string_lossy().as_ref()))
    })
}

fn print_table(r: &Report, secs: f64) {
    println!(
        "{}: {} recordings, N = {}, {} maps per row (seeds {}..{}), {:.1} s",
        r.dataset,
        r.recordings,
        r.num_doas,
        r.runs,
        r.seed0,
        r.seed0 + r.runs as u64,
        secs
    );
    println!(
        "{:<24} {:>6} {:>7} {:>9} {:>9} {:>8} {:>8} {:>8} {:>7} {:>7} {:>7} {:>9}",
        "DoA source",
        "score",
        "recall",
        "err<1.5m",
        "OSPA mean",
        "median",
        "worst",
        "aligned",
        "loc.",
        "card.",
        "right",
        "ms/rec."
    );
    for row in &r.rows {
        let near = {
            // DoAs on sources nearer than 1.5 m: the first two bands, weighted by count.
            let b = &row.diagnostics.bands;
            let (n, s) = b.iter().take(2).fold((0usize, 0.0), |(n, s), x| {
                if x.doas > 0 {
                    (n + x.doas, s + x.mean_abs_err_deg * x.doas as f64)
                } else {
                    (n, s)
                }
            });
            if n > 0 { s / n as f64 } else { f64::NAN }
        };
        let o = &row.ospa;
        println!(
            "{:<24} {:>6.3} {:>7.3} {:>9} {:>9.3} {:>8.3} {:>8.3} {:>8} {:>7.3} {:>7.3} {:>6.0}% {:>9}",
            row.name,
            row.doa.score,
            row.diagnostics.recall_3m,
            if near.is_finite() {
                format!("{near:.1}°")
            } else {
                "-".to_owned()
            },
            o.mean,
            o.median,
            o.worst,
            o.aligned
                .map_or_else(|| "-".to_owned(), |a| format!("{:.3}", a.mean_after_m)),
            o.mean_localization,
            o.mean_cardinality,
            100.0 * o.right_count,
            row.ms_per_recording
                .map_or_else(|| "-".to_owned(), |v| format!("{v:.1}"))
        );
    }
    println!(
        "aligned: the matched sources' mean distance from the truth after each map's best similarity transform onto it (asm::align), free of any disagreement between the poses' and the truth's frames"
    );
    if r.rows.iter().any(|row| row.rules.is_some()) {
        println!(
            "\nwhy sources within 3 m were missed (iasm ssl --score --rules); N raised to 4N would add"
        );
        println!(
            "{:<24} {:>7} {:>8} {:>9} {:>11} {:>18}",
            "method", "missed", "no peak", "cut at N", "thresholds", "added (on source)"
        );
        for row in &r.rows {
            let Some(c) = &row.rules else { continue };
            println!(
                "{:<24} {:>7} {:>8} {:>9} {:>11} {:>18}",
                row.name,
                format!("{}/{}", c.pairs - c.found, c.pairs),
                c.no_peak,
                c.cut_at_n,
                c.by_thresholds(),
                format!("{} ({})", c.beyond_n, c.beyond_n_on_source)
            );
        }
    }
}
