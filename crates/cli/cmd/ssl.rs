//! `iasm ssl`: ranked DoAs per recording, a DoA table for a data set, and its score.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::Serialize;
use ssl::{MicArray, SslConfig};

use crate::Outcome;
use crate::args::SslArgs;
use crate::dataset::{Dataset, Table, read_poses, read_sources, read_table};
use crate::pipeline::{FileDoas, doa_table, localise_files};
use crate::rules::{Recordings, RuleCensus, Truth, run_census};
use crate::score::{Diagnostics, DoaScore, diagnose, score_doas};

/// Version of the JSON this command prints.
pub const SCHEMA_VERSION: u32 = 1;

/// Writes a DoA table as CSV, empty cells where a DoA is missing.
///
/// # Errors
/// If the file cannot be written.
pub fn write_doa_csv(path: &Path, table: &Table, header: bool) -> Result<()> {
    let mut s = String::new();
    let n = table.iter().map(Vec::len).max().unwrap_or(0);
    if header {
        let cols: Vec<String> = (1..=n).map(|i| format!("az{i}_deg")).collect();
        s.push_str(&cols.join(","));
        s.push('\n');
    }
    for row in table {
        let cells: Vec<String> = row
            .iter()
            .map(|c| c.map(|v| format!("{v:.3}")).unwrap_or_default())
            .collect();
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    crate::output::write_atomic(path, s.as_bytes())
}

/// What every part of the command needs: the settings, the array and its SSL settings,
/// the robot's noise.
struct Setup {
    settings: crate::settings::Settings,
    array: MicArray,
    config: SslConfig,
    noise: Option<crate::pipeline::RobotNoise>,
}

impl Setup {
    /// The recordings `files`, localised with this setup.
    fn localise(&self, files: &[std::path::PathBuf]) -> Result<Vec<FileDoas>> {
        localise_files(
            files,
            &self.array,
            self.settings.channels.as_deref(),
            &self.config,
            self.noise.as_ref(),
        )
    }
}

/// Runs `iasm ssl`: DoAs of the files given, or a data set's DoA table, and with
/// `--score` its score against the truth, printed and checked against the thresholds.
///
/// # Errors
/// Bad settings, unreadable or mismatched files.
pub fn run(args: &SslArgs) -> Result<Outcome> {
    let settings = args
        .settings
        .settings()?
        .with_dataset_array(args.dataset.as_deref())
        .with_dataset_noise(args.dataset.as_deref())?;
    let setup = Setup {
        array: settings.mic_array()?,
        config: settings.ssl.clone(),
        noise: crate::pipeline::RobotNoise::of(&settings)?,
        settings,
    };
    if let Some(note) = crate::pipeline::linear_array_note(&setup.array) {
        eprintln!("{note}");
    }
    let Some(dir) = &args.dataset else {
        let rows = setup.localise(&args.files)?;
        crate::pipeline::warn_recordings(&rows);
        print_rows(&rows, &setup.config, &setup.array, args.json)?;
        return Ok(Outcome::Success);
    };
    let ds = Dataset::open(dir)?;
    let (rows, elapsed) = localise_dataset(&setup, &ds, dir)?;
    let table = doa_table(rows.iter().map(|r| &r.doas[..]), setup.config.num_peaks);
    // Without a recording of the robot alone: does the robot's own noise show?
    if setup.settings.noise.is_none()
        && let Some(p) = &ds.poses
        && let Ok(poses) = read_poses(p, false)
        && let Some(note) = crate::robot_noise::note(&poses, &table)
    {
        eprintln!("{note}");
    }
    if let Some(out) = &args.out {
        write_doa_csv(out, &table, args.header)?;
        eprintln!("wrote {}", out.display());
    } else if !args.score {
        print_rows(&rows, &setup.config, &setup.array, args.json)?;
    }
    if !args.score {
        return Ok(Outcome::Success);
    }
    let report = score(args, &setup, &ds, &rows, &table, elapsed)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_score(&report, &setup.config, args.tol_deg);
    }
    check(args, &report, &setup.config, dir)
}

/// The data set's recordings localised, and the time it took (s), said on stderr.
fn localise_dataset(setup: &Setup, ds: &Dataset, dir: &Path) -> Result<(Vec<FileDoas>, f64)> {
    anyhow::ensure!(
        !ds.audio.is_empty(),
        "{}: no WAV file in {}",
        dir.display(),
        dir.join("audio").display()
    );
    let t0 = Instant::now();
    let rows = setup.localise(&ds.audio)?;
    let elapsed = t0.elapsed().as_secs_f64();
    crate::pipeline::warn_recordings(&rows);
    eprintln!(
        "{}: {} recordings localised with {} in {:.2} s ({:.1} ms per recording){}{}",
        dir.display(),
        rows.len(),
        setup.config.method,
        elapsed,
        1e3 * elapsed / rows.len() as f64,
        pooling_note(&rows, &setup.config),
        match &setup.settings.noise {
            Some(p) => format!("; the robot's own noise in {} subtracted", p.display()),
            None => String::new(),
        }
    );
    Ok((rows, elapsed))
}

/// The score of our DoA `table` and of the data set's published tables against its truth,
/// with `--by-distance` and `--rules` diagnostics.
fn score(
    args: &SslArgs,
    setup: &Setup,
    ds: &Dataset,
    rows: &[FileDoas],
    table: &Table,
    elapsed: f64,
) -> Result<ScoreReport> {
    let (poses_path, poses, sources) = truth_of(args, ds)?;
    let (n, mirror, config) = (
        setup.config.num_peaks,
        setup.array.mirror_axis_deg(),
        &setup.config,
    );
    let ours = score_doas(table, &poses, &sources, n, args.tol_deg, mirror)
        .with_context(|| format!("scoring against {}", poses_path.display()))?;
    let diag = |t: &Table| -> Result<Option<Diagnostics>> {
        args.by_distance
            .then(|| diagnose(t, &poses, &sources, n, MATCH_DEG, args.tol_deg, mirror))
            .transpose()
    };
    let mut diagnostics: Vec<NamedDiagnostics> = Vec::new();
    if let Some(d) = diag(table)? {
        diagnostics.push(NamedDiagnostics {
            table: format!("iasm {}", config.method),
            diagnostics: d,
        });
    }
    let mut published: Vec<PublishedScore> = Vec::new();
    for t in &ds.doa_tables {
        let name = t
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let scored = read_table(t).and_then(|tab| {
            Ok((
                score_doas(&tab, &poses, &sources, n, args.tol_deg, mirror)?,
                diag(&tab)?,
            ))
        });
        match scored {
            Ok((score, d)) => {
                if let Some(d) = d {
                    diagnostics.push(NamedDiagnostics {
                        table: name.clone(),
                        diagnostics: d,
                    });
                }
                published.push(PublishedScore { table: name, score });
            }
            Err(e) => eprintln!("warning: cannot score {}: {e:#}", t.display()),
        }
    }
    let truth = Truth {
        poses: &poses,
        sources: &sources,
        tol_deg: args.tol_deg,
        mirror_axis_deg: mirror,
    };
    let rules = args
        .rules
        .then(|| census(setup, ds, rows, &truth))
        .transpose()?;
    Ok(ScoreReport {
        schema_version: SCHEMA_VERSION,
        method: config.method.name(),
        num: n,
        tol_deg: args.tol_deg,
        recordings: rows.len(),
        ms_per_recording: 1e3 * elapsed / rows.len() as f64,
        ours,
        diagnostics,
        published,
        rules,
    })
}

/// The pose table's path, the poses and the true sources `--score` judges against: the
/// data set's, or `--truth`.
fn truth_of(args: &SslArgs, ds: &Dataset) -> Result<(PathBuf, Vec<asm::Pose>, Vec<[f64; 2]>)> {
    let dir = &ds.root;
    let poses_path = ds
        .poses
        .clone()
        .with_context(|| format!("--score: {} has no pose table in pose/", dir.display()))?;
    let sources_path = match &args.truth {
        Some(t) => t,
        None => ds
            .sources
            .as_ref()
            .with_context(|| format!("--score: {} has no src_gt* ground truth", dir.display()))?,
    };
    let poses = read_poses(&poses_path, false)?;
    let sources = read_sources(sources_path)?;
    Ok((poses_path, poses, sources))
}

/// The `--rules` census: which SSL rule left out each source no DoA found, and let in
/// each DoA that found none.
fn census(setup: &Setup, ds: &Dataset, rows: &[FileDoas], truth: &Truth) -> Result<RuleCensus> {
    let rec = Recordings {
        files: &ds.audio,
        array: &setup.array,
        channels: setup.settings.channels.as_deref(),
        noise: setup.noise.as_ref(),
    };
    run_census(&rec, &setup.config, rows, truth)
}

/// The score on the terminal: a row per table, the diagnostics by distance, the census.
fn print_score(report: &ScoreReport, config: &SslConfig, tol_deg: f64) {
    println!(
        "DoA score (first {} DoAs, hit within {tol_deg} deg of a true bearing)",
        report.num
    );
    println!(
        "{:<28} {:>6} {:>6} {:>7} {:>10}",
        "table", "hits", "total", "score", "mean err"
    );
    // An angle, or "-" where there was nothing to average (no hit, an empty band).
    let deg = |v: f64| {
        if v.is_finite() {
            format!("{v:.2}°")
        } else {
            "-".to_owned()
        }
    };
    let line = |name: &str, s: &DoaScore| {
        println!(
            "{:<28} {:>6} {:>6} {:>7.3} {:>10}",
            name,
            s.hits,
            s.total,
            s.score,
            deg(s.mean_hit_error_deg)
        )
    };
    line(&format!("iasm {}", config.method), &report.ours);
    for p in &report.published {
        line(&p.table, &p.score);
    }
    for nd in &report.diagnostics {
        let (name, d) = (&nd.table, &nd.diagnostics);
        println!(
            "\n{name}: DoAs within {} deg of a source, by its distance; recall of sources within 3 m {:.3} ({} pairs)",
            d.match_deg, d.recall_3m, d.near_pairs
        );
        println!(
            "  {:<10} {:>5} {:>10} {:>12} {:>11}",
            "distance", "DoAs", "mean |err|", "median |err|", "axis bias"
        );
        for b in &d.bands {
            println!(
                "  {:<10} {:>5} {:>10} {:>12} {:>11}",
                b.band,
                b.doas,
                deg(b.mean_abs_err_deg),
                deg(b.median_abs_err_deg),
                deg(b.axis_bias_deg)
            );
        }
    }
    if let Some(c) = &report.rules {
        print_census(&format!("iasm {}", config.method), c, tol_deg);
    }
}

/// `--min-score` and `--beat-published`.
fn check(args: &SslArgs, report: &ScoreReport, config: &SslConfig, dir: &Path) -> Result<Outcome> {
    let ours = &report.ours;
    let mut failed = false;
    if let Some(min) = args.min_score
        && ours.score < min
    {
        eprintln!("FAIL: score {:.3} is below --min-score {min}", ours.score);
        failed = true;
    }
    if args.beat_published {
        let key = config.method.name().replace('-', "").to_ascii_lowercase();
        let same = report
            .published
            .iter()
            .find(|p| p.table.replace('-', "").to_ascii_lowercase().contains(&key));
        match same {
            Some(p) if ours.score < p.score.score => {
                eprintln!(
                    "FAIL: score {:.3} is below the published {} ({:.3})",
                    ours.score, p.table, p.score.score
                );
                failed = true;
            }
            Some(_) => {}
            None => bail!(
                "--beat-published: no published table for {} in {}",
                config.method,
                dir.join("azimuth").display()
            ),
        }
    }
    Ok(if failed {
        Outcome::ThresholdFailed
    } else {
        Outcome::Success
    })
}

#[derive(Serialize)]
struct PublishedScore {
    table: String,
    #[serde(flatten)]
    score: DoaScore,
}

#[derive(Serialize)]
struct NamedDiagnostics {
    table: String,
    #[serde(flatten)]
    diagnostics: Diagnostics,
}

/// With --by-distance, a DoA is attributed to the source of nearest bearing within this.
const MATCH_DEG: f64 = 10.0;

#[derive(Serialize)]
struct ScoreReport {
    schema_version: u32,
    method: &'static str,
    num: usize,
    tol_deg: f64,
    recordings: usize,
    ms_per_recording: f64,
    ours: DoaScore,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    diagnostics: Vec<NamedDiagnostics>,
    published: Vec<PublishedScore>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rules: Option<RuleCensus>,
}

/// The census of `--rules` in words: where the missed near sources went, and what let the
/// false DoAs in.
fn print_census(name: &str, c: &RuleCensus, tol_deg: f64) {
    let missed = c.pairs - c.found;
    println!(
        "\n{name}: why sources within 3 m were missed ({} of {} pairs found within {tol_deg} deg; {missed} missed)",
        c.found, c.pairs
    );
    let no_peak = format!(
        " ({} with a peak within {} deg, {} with another source within min_sep_deg)",
        c.no_peak_displaced,
        2.0 * tol_deg,
        c.no_peak_beside
    );
    let cut = if c.cut_but_extra > 0 {
        format!(
            " ({} reported beyond N by the octave votes)",
            c.cut_but_extra
        )
    } else {
        String::new()
    };
    let rows = [
        ("no peak there in the spectrum", c.no_peak, no_peak),
        ("cut at N by stronger DoAs", c.cut_at_n, cut),
        ("too low (min_relative)", c.low, String::new()),
        (
            "low and coherent (max_incoherence)",
            c.coherent,
            String::new(),
        ),
        (
            "not prominent (min_prominence)",
            c.prominence,
            String::new(),
        ),
        ("a sidelobe (sidelobe_ratio)", c.sidelobe, String::new()),
        (
            "insignificant (min_significance)",
            c.insignificant,
            String::new(),
        ),
        ("two rules at once", c.jointly, String::new()),
    ];
    for (what, k, note) in rows {
        let note = if k > 0 { note.as_str() } else { "" };
        println!("  {what:<36} {k:>5}{note}");
    }
    println!(
        "{name}: DoAs with no source within {tol_deg} deg: {} of {}, let in by height {}, by block votes {}, as incoherent {}",
        c.false_doas, c.doas, c.by_height, c.by_dominance, c.by_incoherence
    );
    println!(
        "{name}: N raised to {} would add {} DoAs, {} of them within {tol_deg} deg of a source",
        c.wide_n, c.beyond_n, c.beyond_n_on_source
    );
}

#[derive(Serialize)]
struct SslReport<'a> {
    schema_version: u32,
    method: &'static str,
    array: &'a str,
    files: &'a [FileDoas],
}

fn print_rows(rows: &[FileDoas], config: &SslConfig, array: &MicArray, json: bool) -> Result<()> {
    let mut out = std::io::stdout().lock();
    if json {
        let r = SslReport {
            schema_version: SCHEMA_VERSION,
            method: config.method.name(),
            array: array.name(),
            files: rows,
        };
        writeln!(out, "{}", serde_json::to_string_pretty(&r)?)?;
        return Ok(());
    }
    // The extra DoAs of a cut row (`ssl::Located::extra`) follow its N, marked `+`; a row
    // localised without a faulty channel says so at its end.
    for r in rows {
        let cell = |mark: &str, d: &ssl::Doa| {
            let az = format!("{mark}{:.1}", d.azimuth_deg);
            format!("{az:>7}° ({:.3})", d.strength)
        };
        let cells: Vec<String> = (r.doas.iter().map(|d| cell("", d)))
            .chain(r.extra.iter().map(|d| cell("+", d)))
            .collect();
        let faulty: Vec<String> = r
            .faulty_channels
            .iter()
            .map(|f| {
                let how = if f.left_out { "left out" } else { "kept" };
                format!("channel {} {how}", f.channel)
            })
            .collect();
        let note = if faulty.is_empty() {
            String::new()
        } else {
            format!("  ({})", faulty.join(", "))
        };
        writeln!(out, "{}\t{}{note}", r.file.display(), cells.join("  "))?;
    }
    Ok(())
}

/// With the default pooling ([`ssl::Pooling::Auto`]), how many recordings were steady and
/// pooled by their mean (empty when the pooling was set; MUSIC always pools by the mean).
fn pooling_note(rows: &[crate::pipeline::FileDoas], config: &ssl::SslConfig) -> String {
    if config.pooling != ssl::Pooling::Auto {
        return String::new();
    }
    if config.method == ssl::Method::Music {
        return "; pooled by the blocks' mean, as MUSIC always is (ssl::Pooling::Auto)".into();
    }
    if ssl::Method::COHERENT.contains(&config.method) {
        return format!(
            "; one spectrum of each whole recording, as {} takes",
            config.method
        );
    }
    let mean = rows
        .iter()
        .filter(|r| r.pooling == ssl::Pooling::Mean)
        .count();
    let n = rows.len();
    match mean {
        0 => "; none steady, every one pooled by its blocks' max (ssl::Pooling::Auto)".into(),
        m if m == n => "; every one steady, pooled by its blocks' mean (ssl::Pooling::Auto)".into(),
        m => format!(
            "; {m} of {n} steady, pooled by their blocks' mean, the rest by the max (ssl::Pooling::Auto)"
        ),
    }
}
