//! The SSL method comparison: every method side by side on one data set, from its DoAs to
//! its maps.
//!
//! For each method the recordings are localised once (timed on the worker thread, file
//! read included), and its DoA table is scored ([`crate::score`]: the DoA score, errors by
//! distance band, recall of sources within 3 m) and mapped over `runs` seeds with the full
//! I-ASM (CA) variant and the settings' profile ([`crate::pipeline::evaluate`]). The
//! published tables in `azimuth/`, when present, are scored and mapped the same way as
//! extra rows, so that a method is always seen beside the authors' own DoAs.

use std::path::Path;

use anyhow::{Context, Result, ensure};
use asm::Variant;
use serde::Serialize;
use ssl::Method;

use crate::dataset::{Dataset, Table, read_table};
use crate::pipeline::{
    Survey, SurveyInputs, VariantStats, evaluate, first_columns, localise_files, mapped_table,
};
use crate::rules::{Recordings, RuleCensus, Truth, run_census};
use crate::score::{Diagnostics, DoaScore, diagnose, score_doas};
use crate::settings::Settings;

/// Version of the report's JSON layout.
pub const SCHEMA_VERSION: u32 = 1;

/// A DoA within this many degrees of a source's bearing is a hit (the DoA score's rule).
pub const HIT_DEG: f64 = 5.0;
/// A DoA is attributed to the nearest source's bearing within this for the error bands.
pub const MATCH_DEG: f64 = 10.0;

/// What to compare and how.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// The methods, in report order.
    pub methods: Vec<Method>,
    /// Maps per method (seeds `seed0..seed0 + runs`).
    pub runs: usize,
    /// The first seed.
    pub seed0: u64,
    /// OSPA cutoff (m) and order.
    pub ospa_c: f64,
    /// OSPA order.
    pub ospa_p: f64,
    /// Without an occupancy map: the search margin around the stops (m; default
    /// [`crate::pipeline::OPEN_MARGIN_M`]).
    pub open_margin_m: Option<f64>,
    /// Also take each method's census of missed near sources ([`crate::rules`]).
    pub rules: bool,
    /// DoA tables of other tools, each a row (`--table`).
    pub tables: Vec<std::path::PathBuf>,
}

/// One row of the comparison: a method of ours, or a published table.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// The method's name, or the published table's file name.
    pub name: String,
    /// `"ssl"` for a method run here, `"published"` for a table in `azimuth/`, `"given"`
    /// for a table given with `--table` (another tool's DoAs).
    pub kind: &'static str,
    /// The DoA score (first N DoAs, hit within [`HIT_DEG`]).
    pub doa: DoaScore,
    /// Errors by distance band and the recall of sources within 3 m.
    pub diagnostics: Diagnostics,
    /// The CA maps' OSPA over the runs.
    pub ospa: VariantStats,
    /// Milliseconds per recording on one thread, file read included (methods only).
    pub ms_per_recording: Option<f64>,
    /// The sources of the first seed's map (m), for the figure.
    pub map_seed0: Vec<[f64; 2]>,
    /// Why the near sources no DoA found were missed (methods only, with
    /// [`CompareOptions::rules`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rules: Option<RuleCensus>,
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The data set folder.
    pub dataset: String,
    /// Recordings (stops).
    pub recordings: usize,
    /// N: DoAs per stop.
    pub num_doas: usize,
    /// Maps per row, and the first seed.
    pub runs: usize,
    /// The first seed.
    pub seed0: u64,
    /// The true sources (m).
    pub truth: Vec<[f64; 2]>,
    /// The robot's stops (x, y in m).
    pub path: Vec<[f64; 2]>,
    /// One row per method, then one per published table.
    pub rows: Vec<Row>,
}

/// Parses `all` or a comma-separated list of method names.
///
/// # Errors
/// An unknown name, or an empty list.
pub fn parse_methods(s: &str) -> Result<Vec<Method>> {
    if s.trim().eq_ignore_ascii_case("all") {
        return Ok(Method::ALL.to_vec());
    }
    let mut out = Vec::new();
    for name in s.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let m: Method = name.parse().map_err(|_| {
            anyhow::anyhow!(
                "--methods: unknown method {name:?} (known: all, {})",
                Method::ALL.map(Method::name).join(", ")
            )
        })?;
        if !out.contains(&m) {
            out.push(m);
        }
    }
    ensure!(!out.is_empty(), "--methods names no method");
    Ok(out)
}

/// Runs the comparison on the data set at `root` (published layout, with ground truth).
/// `progress(stage, stages, what)` is told each stage as it starts: localising and mapping
/// per method, mapping per published table.
///
/// # Errors
/// A data set without recordings, poses or truth, or any failure of the pipeline, named.
pub fn compare(
    root: &Path,
    settings: &Settings,
    opts: &CompareOptions,
    progress: &dyn Fn(usize, usize, &str),
) -> Result<Report> {
    ensure!(opts.runs > 0, "--runs must be at least 1");
    let ds = Dataset::open(root)?;
    ensure!(
        !ds.audio.is_empty(),
        "{}: no recordings in audio/",
        root.display()
    );
    // Checked before any method runs: without it every method would localise and map
    // before the first score failed.
    ensure!(
        ds.sources.is_some(),
        "{}: the comparison needs ground truth (src_gt* in the data set)",
        root.display()
    );
    let inputs = SurveyInputs {
        dataset: Some(root.to_owned()),
        open_margin_m: opts.open_margin_m,
        ..SurveyInputs::default()
    };
    let n = settings.ssl.num_peaks;
    let array = settings.mic_array()?;
    let stages = (2 + usize::from(opts.rules)) * opts.methods.len()
        + ds.doa_tables.len()
        + opts.tables.len();
    let mut stage = 0;
    let mut tell = |what: String| {
        stage += 1;
        progress(stage, stages, &what);
    };
    let mut surveys = Surveys { inputs, base: None };
    let noise = crate::pipeline::RobotNoise::of(settings)?;
    let mut rows = Vec::new();
    for &method in &opts.methods {
        let mut s = settings.clone();
        s.ssl.method = method;
        let rec = Recordings {
            files: &ds.audio,
            array: &array,
            channels: s.channels.as_deref(),
            noise: noise.as_ref(),
        };
        rows.push(method_row(&rec, &s, opts, &mut surveys, &mut tell)?);
    }
    let published = ds.doa_tables.iter().map(|t| (t, "published"));
    for (t, kind) in published.chain(opts.tables.iter().map(|t| (t, "given"))) {
        let name = crate::dataset::file_name(t);
        tell(format!("{name}: {} maps", opts.runs));
        let table = first_columns(read_table(t)?, n, t);
        ensure!(
            kind == "published" || table.len() == ds.audio.len(),
            "{}: {} rows for {} recordings (one row per recording, in the audio's order)",
            t.display(),
            table.len(),
            ds.audio.len()
        );
        let survey = surveys.with(table, t.display().to_string(), None, settings)?;
        rows.push(row(&survey, name, kind, None, settings, opts)?);
    }
    let base = surveys
        .base
        .context("nothing to compare: no method and no published table")?;
    Ok(Report {
        schema_version: SCHEMA_VERSION,
        dataset: root.display().to_string(),
        recordings: base.poses.len(),
        num_doas: n,
        runs: opts.runs,
        seed0: opts.seed0,
        truth: base.truth.unwrap_or_default(),
        path: base.poses.iter().map(|p| [p.x, p.y]).collect(),
        rows,
    })
}

/// The survey of a comparison: its map, poses and truth read once, with the first DoA
/// table; every other row swaps its DoAs in.
struct Surveys {
    inputs: SurveyInputs,
    base: Option<Survey>,
}

impl Surveys {
    /// The survey with `table`'s DoAs (from `source`; `cut`: which rows the SSL cut at N).
    fn with(
        &mut self,
        table: Table,
        source: String,
        cut: Option<Vec<bool>>,
        s: &Settings,
    ) -> Result<Survey> {
        let base = match &self.base {
            Some(b) => b.clone(),
            None => {
                let first =
                    Survey::load_with_doas(&self.inputs, s, Some((table.clone(), source.clone())))?;
                if let Some(note) = first.map_note() {
                    eprintln!("{note}");
                }
                self.base = Some(first.clone());
                first
            }
        };
        base.with_doas(table, source, cut)
    }
}

/// The row of the method `s.ssl.method`: the recordings localised, timed and mapped, and
/// with `opts.rules`, why the near sources it missed were missed. `tell` is told each
/// stage as it starts.
fn method_row(
    rec: &Recordings<'_>,
    s: &Settings,
    opts: &CompareOptions,
    surveys: &mut Surveys,
    tell: &mut dyn FnMut(String),
) -> Result<Row> {
    let method = s.ssl.method;
    tell(format!(
        "{method}: localising {} recordings",
        rec.files.len()
    ));
    let files = localise_files(rec.files, rec.array, rec.channels, &s.ssl, rec.noise)?;
    if Some(&method) == opts.methods.first() {
        crate::pipeline::warn_recordings(&files);
    }
    let ms = 1e3 * files.iter().map(|f| f.seconds).sum::<f64>() / files.len() as f64;
    let n = s.ssl.num_peaks;
    let table = mapped_table(files.iter().map(|f| (&f.doas[..], &f.extra[..])), n);
    let cut = Some(files.iter().map(|f| f.cut).collect());
    let survey = surveys.with(table, format!("ssl:{method}"), cut, s)?;
    tell(format!("{method}: {} maps", opts.runs));
    let mut r = row(&survey, method.name().to_owned(), "ssl", Some(ms), s, opts)?;
    if opts.rules {
        tell(format!("{method}: why near sources were missed"));
        let truth = Truth {
            poses: &survey.poses,
            sources: survey.truth.as_deref().unwrap_or_default(),
            tol_deg: HIT_DEG,
            mirror_axis_deg: survey.mirror_axis_deg,
        };
        r.rules = Some(run_census(rec, &s.ssl, &files, &truth)?);
    }
    Ok(r)
}

fn row(
    survey: &Survey,
    name: String,
    kind: &'static str,
    ms_per_recording: Option<f64>,
    settings: &Settings,
    opts: &CompareOptions,
) -> Result<Row> {
    let truth = survey
        .truth
        .as_ref()
        .context("the comparison needs ground truth (src_gt* in the data set)")?;
    let n = settings.ssl.num_peaks;
    let mirror = survey.mirror_axis_deg;
    let doa = score_doas(&survey.doas_deg, &survey.poses, truth, n, HIT_DEG, mirror)?;
    let diagnostics = diagnose(
        &survey.doas_deg,
        &survey.poses,
        truth,
        n,
        MATCH_DEG,
        HIT_DEG,
        mirror,
    )?;
    let ospa = evaluate(
        survey,
        &settings.iasm,
        &[Variant::Ca],
        opts.runs,
        opts.seed0,
        opts.ospa_c,
        opts.ospa_p,
    )?
    .pop()
    .expect("one variant asked, one returned");
    let map_seed0 = survey.map(&settings.iasm, opts.seed0)?.positions();
    Ok(Row {
        name,
        kind,
        doa,
        diagnostics,
        ospa,
        ms_per_recording,
        map_seed0,
        rules: None,
    })
}

/// The report as CSV: one line per row, the columns of the terminal table and the error
/// of each distance band.
pub fn to_csv(r: &Report) -> String {
    let bands: Vec<&str> = r
        .rows
        .first()
        .map(|row| {
            row.diagnostics
                .bands
                .iter()
                .map(|b| b.band.as_str())
                .collect()
        })
        .unwrap_or_default();
    let mut out = csv_header(&bands);
    for row in &r.rows {
        out.push_str(&csv_row(row));
    }
    out
}

/// The CSV's header line, with a column per distance band of `bands`.
fn csv_header(bands: &[&str]) -> String {
    let mut out = String::from(
        "name,kind,doa_score,doa_hits,doa_total,mean_hit_error_deg,recall_3m,ospa_mean,ospa_median,ospa_worst,ospa_localization,ospa_cardinality,right_count,mean_sources,ms_per_recording,aligned_mean_m",
    );
    for b in bands {
        out.push_str(&format!(",err_deg_{}", b.replace(' ', "")));
    }
    out.push_str(
        ",missed_per_run,refused_absence,refused_thin,refused_misplaced,refused_reassigned",
    );
    out.push_str(",near_missed,missed_no_peak,missed_cut_at_n,missed_by_thresholds,beyond_n,beyond_n_on_source");
    out.push('\n');
    out
}

/// A number in the CSV: four decimals, empty where it is not finite.
fn csv_num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.4}")
    } else {
        String::new()
    }
}

/// One row's CSV line: its scores, the error per distance band, why the maps missed
/// sources and, with `--rules`, the SSL's census.
fn csv_row(row: &Row) -> String {
    let num = csv_num;
    let o = &row.ospa;
    let mut cells: Vec<String> = vec![
        row.name.clone(),
        row.kind.to_string(),
        num(row.doa.score),
        row.doa.hits.to_string(),
        row.doa.total.to_string(),
        num(row.doa.mean_hit_error_deg),
        num(row.diagnostics.recall_3m),
        num(o.mean),
        num(o.median),
        num(o.worst),
        num(o.mean_localization),
        num(o.mean_cardinality),
        num(o.right_count),
        num(o.mean_sources),
        row.ms_per_recording.map(num).unwrap_or_default(),
        o.aligned.map(|a| num(a.mean_after_m)).unwrap_or_default(),
    ];
    cells.extend(
        row.diagnostics
            .bands
            .iter()
            .map(|b| num(b.mean_abs_err_deg)),
    );
    let m = &o.missed;
    cells.extend(
        [
            m.missed,
            m.spoken_against,
            m.thinly_heard,
            m.misplaced,
            m.reassigned,
        ]
        .map(num),
    );
    let census: [Option<usize>; 6] = match &row.rules {
        Some(c) => [
            Some(c.pairs - c.found),
            Some(c.no_peak),
            Some(c.cut_at_n),
            Some(c.by_thresholds()),
            Some(c.beyond_n),
            Some(c.beyond_n_on_source),
        ],
        None => [None; 6],
    };
    cells.extend(census.map(|v| v.map(|v| v.to_string()).unwrap_or_default()));
    cells.join(",") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn methods_are_parsed_from_all_or_a_list() {
        assert_eq!(parse_methods("all").unwrap(), Method::ALL.to_vec());
        assert_eq!(
            parse_methods("mvdr, normmusic,mvdr").unwrap(),
            vec![Method::Mvdr, Method::NormMusic]
        );
        let e = parse_methods("mvdr,beamformit").unwrap_err();
        assert!(format!("{e:#}").contains("beamformit"), "{e:#}");
        assert!(parse_methods(" , ").is_err());
    }
}
