//! `iasm map`: I-ASM from DoA tables or raw audio to a map of sources, as a table, JSON,
//! CSV and a picture.

use std::path::Path;

use anyhow::Result;
use asm::ospa::Ospa;
use asm::{IasmConfig, MapResult};
use serde::Serialize;
use ssl::SslConfig;
use ssl::signature::Signature;

use crate::Outcome;
use crate::args::MapArgs;
use crate::dataset::file_name;
use crate::explain::{Explanation, explain};
use crate::figure::MapFigure;
use crate::pipeline::{RunSpan, Survey};
use crate::settings::DEFAULT_ARRAY;

/// Version of the JSON `iasm map` writes.
pub const SCHEMA_VERSION: u32 = 1;

/// One run's report.
#[derive(Serialize)]
struct MapReport<'a> {
    schema_version: u32,
    /// The frame the sources' and poses' coordinates are in (ROS's name for it).
    frame_id: &'static str,
    doas: &'a str,
    seed: u64,
    params: &'a IasmConfig,
    /// The SSL settings and array, when the DoAs came from the recordings.
    #[serde(skip_serializing_if = "Option::is_none")]
    ssl: Option<&'a SslConfig>,
    #[serde(skip_serializing_if = "Option::is_none")]
    array: Option<&'a str>,
    /// The recording of the robot alone whose noise the SSL subtracted (`ssl::noise`).
    #[serde(skip_serializing_if = "Option::is_none")]
    noise: Option<&'a Path>,
    rounds: usize,
    particles: usize,
    unexplained_doas: usize,
    /// Sources found and removed as impossible (see `asm::MapResult::removed`).
    removed_sources: usize,
    /// What was found and refused, and why (see `asm::MapResult::refused`).
    refused: &'a [asm::Refused],
    sources: Vec<SourceRow<'a>>,
    ospa: Option<OspaReport>,
    /// The map against the truth after the best similarity transform (a diagnostic of the
    /// data's frames; see `asm::align`).
    #[serde(skip_serializing_if = "Option::is_none")]
    alignment: Option<asm::align::Alignment>,
    /// Without an occupancy map: how far from the stops the sources were searched for (m).
    #[serde(skip_serializing_if = "Option::is_none")]
    open_margin_m: Option<f64>,
    /// With `--explain`: where every DoA went (see `iasm::explain`).
    #[serde(skip_serializing_if = "Option::is_none")]
    explain: Option<Explanation>,
    /// With several `--dataset`: each run's stops in the union (its first stop, counted
    /// from 1, and how many), in the order of the stops `explain` counts.
    #[serde(skip_serializing_if = "Option::is_none")]
    runs: Option<&'a [RunSpan]>,
}

/// A source with what it sounds like, when asked (`--signatures`).
#[derive(Serialize)]
struct SourceRow<'a> {
    #[serde(flatten)]
    source: &'a asm::Source,
    #[serde(skip_serializing_if = "Option::is_none")]
    signature: Option<&'a Signature>,
}

#[derive(Clone, Copy, Serialize)]
struct OspaReport {
    p: f64,
    c: f64,
    #[serde(flatten)]
    value: Ospa,
}

/// Runs `iasm map`: the survey and settings, the map, its report written and printed.
///
/// # Errors
/// Bad survey or settings, or files that cannot be written.
pub fn run(a: &MapArgs) -> Result<Outcome> {
    if let Some(png) = &a.png {
        crate::figure::Format::of(png)?;
    }
    let (settings, survey, runs) = gather(a)?;
    let localised = a.input.doas.is_none();
    let config = &survey.mapper_config(&settings.iasm);
    let t0 = std::time::Instant::now();
    let result = survey.map(config, a.seed)?;
    let dt = t0.elapsed().as_secs_f64();
    for w in crate::pipeline::map_warnings(&survey.map, &survey.poses, config, &result) {
        eprintln!("warning: {w}");
    }
    let signatures = if a.signatures {
        signatures(a, &survey, &result)?
    } else {
        Vec::new()
    };
    let mut report = report(
        a,
        &survey,
        &settings,
        config,
        &result,
        localised,
        &signatures,
    );
    if runs.len() > 1 {
        report.runs = Some(&runs);
    }
    write_files(a, &survey, &report, &result, &signatures)?;
    if a.report.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_map(a, &survey, &report, &result, dt);
        print_signatures(&signatures);
    }
    Ok(Outcome::Success)
}

/// Each source's signature (`--signatures`), from every run's recordings, one per stop.
fn signatures(a: &MapArgs, survey: &Survey, result: &MapResult) -> Result<Vec<Option<Signature>>> {
    let runs = a.input.runs()?;
    let mut files = Vec::new();
    let array = runs[0].2.mic_array()?;
    let channels = runs[0].2.channels.clone();
    for (name, inputs, settings) in &runs {
        anyhow::ensure!(
            inputs.recording.is_none(),
            "--signatures needs one recording per stop, not one continuous --recording"
        );
        anyhow::ensure!(
            settings.mic_array()?.positions() == array.positions(),
            "--signatures: run {name} was heard by another array than the first run"
        );
        let run_files = match (&inputs.audio, &inputs.dataset) {
            (Some(dir), _) => crate::dataset::list_files(dir, "wav")?,
            (None, Some(d)) => crate::dataset::Dataset::open(d)?.audio,
            (None, None) => {
                anyhow::bail!("--signatures needs the recordings: --dataset or --audio")
            }
        };
        files.extend(run_files);
    }
    anyhow::ensure!(
        files.len() == survey.poses.len(),
        "--signatures: {} recordings for {} stops; they must match one to one",
        files.len(),
        survey.poses.len()
    );
    crate::pipeline::signatures(result, &survey.poses, &array, &|k| {
        crate::dataset::read_recording(&files[k], channels.as_deref())
    })
}

/// What each source sounds like, a line each.
fn print_signatures(signatures: &[Option<Signature>]) {
    if signatures.is_empty() {
        return;
    }
    println!(
        "What each source sounds like (the array steered at it from the stops that heard it):"
    );
    for (k, s) in signatures.iter().enumerate() {
        match s {
            Some(s) => println!(
                "  s{:<3} {:<9} {:>6.1} dB  band {:.0}-{:.0} Hz  modulation {:.2}  tonality {:.2}  across stops ±{:.1} dB  ({} stops)",
                k + 1,
                s.kind.name(),
                s.level_db,
                s.band_hz[0],
                s.band_hz[1],
                s.modulation,
                s.tonality,
                s.level_spread_db,
                s.stops
            ),
            None => println!("  s{:<3} no recording to steer at", k + 1),
        }
    }
}

/// The settings (the first run's, with `--variant`), the survey (of every run, one after
/// the other) and where each run's stops lie, the notes a user should see said.
fn gather(a: &MapArgs) -> Result<(crate::settings::Settings, Survey, Vec<RunSpan>)> {
    let runs = a.input.runs()?;
    let mut settings = runs[0].2.clone();
    if let Some(v) = a.variant {
        settings.iasm.variant = v;
    }
    let (survey, spans) = crate::pipeline::load_runs(&runs)?;
    if let Some(note) = survey.map_note() {
        eprintln!("{note}");
    }
    crate::robot_noise::tell(
        &settings,
        &survey.doa_source,
        &survey.poses,
        &survey.doas_deg,
    );
    if a.input.doas.is_none()
        && let Some(note) = crate::pipeline::linear_array_note(&settings.mic_array()?)
    {
        eprintln!("{note}");
    }
    Ok((settings, survey, spans))
}

/// The run's report: the map, and against the truth when there is one.
fn report<'a>(
    a: &MapArgs,
    survey: &'a Survey,
    settings: &'a crate::settings::Settings,
    config: &'a IasmConfig,
    result: &'a MapResult,
    localised: bool,
    signatures: &'a [Option<Signature>],
) -> MapReport<'a> {
    let ospa = survey
        .ospa(result, a.report.ospa_c, a.report.ospa_p)
        .map(|value| OspaReport {
            p: a.report.ospa_p,
            c: a.report.ospa_c,
            value,
        });
    let alignment = survey
        .truth
        .as_deref()
        .and_then(|t| asm::align::align(&result.positions(), t, a.report.ospa_c));
    let explain = a.explain.then(|| {
        explain(
            result,
            &survey.poses,
            &survey.doas_deg,
            survey.cut.as_deref(),
            survey.truth.as_deref(),
            a.report.ospa_c,
            crate::compare::HIT_DEG,
        )
    });
    MapReport {
        schema_version: SCHEMA_VERSION,
        frame_id: crate::rosmap::FRAME,
        doas: &survey.doa_source,
        seed: a.seed,
        params: config,
        ssl: localised.then_some(&settings.ssl),
        array: localised.then(|| settings.array.as_deref().unwrap_or(DEFAULT_ARRAY)),
        noise: settings.noise.as_deref().filter(|_| localised),
        rounds: result.rounds,
        particles: result.particles,
        unexplained_doas: result.unexplained,
        removed_sources: result.removed,
        refused: &result.refused,
        sources: result
            .sources
            .iter()
            .enumerate()
            .map(|(k, source)| SourceRow {
                source,
                signature: signatures.get(k).and_then(Option::as_ref),
            })
            .collect(),
        ospa,
        alignment,
        open_margin_m: survey.open_margin_m,
        explain,
        runs: None,
    }
}

/// The files asked for: the JSON, the CSV, the truth in the map's frame, the picture, the
/// MCAP.
fn write_files(
    a: &MapArgs,
    survey: &Survey,
    report: &MapReport<'_>,
    result: &MapResult,
    signatures: &[Option<Signature>],
) -> Result<()> {
    if let Some(out) = &a.out {
        crate::output::write_atomic(out, serde_json::to_string_pretty(report)?.as_bytes())?;
    }
    if let Some(csv) = &a.csv {
        write_sources_csv(csv, result)?;
    }
    if let Some(path) = &a.write_aligned_truth {
        let (Some(truth), Some(fit)) = (survey.truth.as_deref(), report.alignment) else {
            anyhow::bail!(
                "--write-aligned-truth {}: the map needs the truth and three sources matched to it within c = {} m",
                path.display(),
                a.report.ospa_c
            );
        };
        let text: String = truth
            .iter()
            .enumerate()
            .map(|(i, &q)| {
                let [x, y] = fit.invert(q);
                format!("s{} [{x:.4}, {y:.4}, 0]\n", i + 1)
            })
            .collect();
        crate::output::write_atomic(path, text.as_bytes())?;
    }
    if let Some(png) = &a.png {
        write_figure(a, png, survey, report, result, signatures)?;
    }
    if let Some(path) = &a.mcap {
        let mut messages = crate::rosmap::of_survey(survey, result);
        crate::rosmap::label_kinds(&mut messages, signatures);
        crate::rosmap::write_mcap(path, &messages, messages.path.header.stamp.ns())?;
    }
    Ok(())
}

/// The map's picture, titled with the data, the DoAs' origin, the variant and the score.
fn write_figure(
    a: &MapArgs,
    png: &Path,
    survey: &Survey,
    report: &MapReport<'_>,
    result: &MapResult,
    signatures: &[Option<Signature>],
) -> Result<()> {
    let data = match (&a.input.dataset[..], &a.input.poses) {
        ([], Some(p)) => file_name(p),
        ([], None) => "survey".to_owned(),
        (d, _) => d
            .iter()
            .map(|p| file_name(p))
            .collect::<Vec<_>>()
            .join(" + "),
    };
    let doas = survey
        .doa_source
        .strip_prefix("ssl:")
        .map_or_else(|| file_name(Path::new(&survey.doa_source)), str::to_owned);
    let ospa = report
        .ospa
        .map_or(String::new(), |o| format!(", OSPA {:.3} m", o.value.total));
    let title = format!(
        "{data}: {doas}, {}, {} sources found{ospa}",
        report.params.variant.name(),
        result.sources.len()
    );
    crate::figure::map(
        png,
        &MapFigure {
            title,
            map: &survey.map,
            poses: &survey.poses,
            result,
            truth: survey.truth.as_deref(),
            full_map: a.figure.full_map,
            width: a.figure.figure_width,
            kinds: signatures
                .iter()
                .map(|s| {
                    s.as_ref()
                        .map(|s| format!("{}, {:.0} dB", s.kind.name(), s.level_db))
                })
                .collect(),
        },
    )
}

/// The map on the terminal: a line on the run, a row per source, the score, where the
/// DoAs went (`--explain`) and the frames' agreement.
fn print_map(a: &MapArgs, survey: &Survey, report: &MapReport<'_>, result: &MapResult, dt: f64) {
    if let Some(runs) = report.runs {
        let each: Vec<String> = runs
            .iter()
            .map(|r| {
                format!(
                    "{} (stops {}-{})",
                    r.name,
                    r.first_stop,
                    r.first_stop + r.stops - 1
                )
            })
            .collect();
        println!("{} runs mapped as one: {}", runs.len(), each.join(", "));
    }
    println!(
        "I-ASM ({}) on {} stops, DoAs from {}: {} sources in {} rounds of {} particles ({:.0} ms, seed {})",
        report.params.variant.name(),
        survey.poses.len(),
        survey.doa_source,
        result.sources.len(),
        result.rounds,
        result.particles,
        1e3 * dt,
        a.seed
    );
    if result.removed > 0 {
        println!(
            "  {} more found and removed: on the robot's path, beyond the map, outside the room or behind a wall or another's reflections, contradicted by stops that heard nothing there, or left with too few DoAs by sources that fit them better (--explain says which; see asm::IasmConfig::min_range_m, room_margin_m, wall_clearance_m, reflections, absence_ratio, reassociate)",
            result.removed
        );
    }
    println!(
        "{:>3} {:>8} {:>8} {:>6} {:>9} {:>9} {:>6}  heard at stops",
        "#", "x (m)", "y (m)", "DoAs", "particles", "2σ (m)", "round"
    );
    for (i, s) in result.sources.iter().enumerate() {
        let two_sigma = 2.0 * asm::pf::max_eigenvalue(s.covariance).sqrt();
        println!(
            "{:>3} {:>8.3} {:>8.3} {:>6} {:>9} {:>9.3} {:>6}  {}",
            i + 1,
            s.x,
            s.y,
            s.observations,
            s.particles,
            two_sigma,
            s.round,
            heard(&s.history)
        );
        if let Some([x, y]) = s.mirror {
            println!(
                "    or at ({x:.3}, {y:.3}): its DoAs' mirror images in the linear array's line meet there as well (the robot did not turn enough to tell)"
            );
        }
    }
    if let Some(o) = report.ospa {
        println!(
            "OSPA (p = {}, c = {} m): {:.3} m (localisation {:.3}, cardinality {:.3})",
            o.p, o.c, o.value.total, o.value.localization, o.value.cardinality
        );
    }
    if let Some(e) = &report.explain {
        print_explanation(e, a.report.ospa_c);
    }
    if let Some(f) = report.alignment {
        println!(
            "Matched sources {:.3} m from the truth; {:.3} m after the best similarity transform of the map (scale {:.3}, rotation {:+.2}°, shift ({:+.3}, {:+.3}) m; {} pairs): much less means the poses' and the truth's frames disagree",
            f.mean_before_m,
            f.mean_after_m,
            f.scale,
            f.rotation_rad.to_degrees(),
            f.shift[0],
            f.shift[1],
            f.pairs
        );
    }
}

/// `--explain` on the terminal: one line per source, per stop with DoAs left, per missed
/// true source.
fn print_explanation(e: &Explanation, c: f64) {
    println!("Where the DoAs went (stop: azimuth in the array frame, miss or error in degrees):");
    for s in &e.sources {
        let rays: Vec<String> = s
            .rays
            .iter()
            .map(|r| {
                let blend = if r.blend {
                    ", a blend with its image"
                } else if r.image {
                    ", its image in a wall"
                } else {
                    ""
                };
                format!(
                    "{}: {:.1} ({:.1}{blend})",
                    r.stop, r.azimuth_deg, r.miss_deg
                )
            })
            .collect();
        println!("  source {} explains {}", s.source, rays.join(", "));
    }
    if e.unexplained.is_empty() {
        println!("  every DoA is explained by a source");
    }
    for s in &e.unexplained {
        let az: Vec<String> = s.azimuths_deg.iter().map(|a| format!("{a:.1}")).collect();
        let cut = match s.cut {
            Some(true) => " (the SSL found more peaks than N there)",
            _ => "",
        };
        println!("  stop {} unexplained: {}{cut}", s.stop, az.join(", "));
    }
    for r in &e.refused {
        println!(
            "  refused ({:.2}, {:.2}), heard from stops {}: {}",
            r.x,
            r.y,
            list(&r.stops),
            refusal(&r.rule)
        );
    }
    for m in &e.missed {
        let heard: Vec<String> = m
            .heard
            .iter()
            .map(|h| {
                let by = h
                    .taken_by
                    .map_or_else(|| "unexplained".to_owned(), |k| format!("source {k}"));
                format!("{}: {:+.1} ({by})", h.stop, h.error_deg)
            })
            .collect();
        let heard = if heard.is_empty() {
            "no stop".to_owned()
        } else {
            heard.join(", ")
        };
        let refused = m.refused.as_ref().map_or_else(String::new, |r| {
            format!("; found at ({:.2}, {:.2}) and refused (above)", r.x, r.y)
        });
        println!(
            "  true source {} ({:.2}, {:.2}), no mapped source within {c} m: DoAs within {}° at {heard}{refused}",
            m.truth, m.x, m.y, e.tol_deg
        );
    }
}

/// Stop numbers, comma-separated.
fn list(stops: &[usize]) -> String {
    stops
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The rule that refused a source, and the setting that states it.
fn refusal(rule: &asm::Refusal) -> String {
    match rule {
        asm::Refusal::Misplaced => {
            "on the robot's path, beyond the map or behind a wall (min_range_m, beyond_map_m, wall_clearance_m)"
                .to_owned()
        }
        asm::Refusal::ThinlyHeard => {
            "too few stops once the rows the SSL cut at N count 3/5 each (vote_min_thresholded_stops)"
                .to_owned()
        }
        asm::Refusal::SpokenAgainst { against } => format!(
            "stops {} heard other sources and nothing there, as near to it as the stops that heard it (absence_ratio; the first is forgiven)",
            list(against)
        ),
        asm::Refusal::Reassigned => {
            "its other DoAs fit mapped sources better and went to them, leaving fewer than min_observations stops (reassociate)"
                .to_owned()
        }
        asm::Refusal::Reflection => {
            "heard only by reflection: its DoAs are another source's reflections in the map's walls, or that source and its reflection heard as one peak (reflections)"
                .to_owned()
        }
        asm::Refusal::OutsideRoom => {
            "outside the room: where the map holds a wall or unknown space, and its DoAs fit no free place near it (room_margin_m)"
                .to_owned()
        }
    }
}

/// When a source was heard, as the map's table says it: its first and last stop (from
/// 0), whether it appeared or fell silent, and where it moved.
fn heard(h: &asm::History) -> String {
    let mut out = format!("{}-{}", h.first_stop, h.last_stop);
    if let Some(k) = h.appeared_at {
        out += &format!(", appeared at {k}");
    }
    match h.silent_since() {
        Some(k) => out += &format!(", silent since {k}"),
        None => out += ", active",
    }
    if let Some(j) = h.moved_from {
        out += &format!(", moved here from #{}", j + 1);
    }
    if let Some(j) = h.moved_to {
        out += &format!(", moved to #{}", j + 1);
    }
    out
}

fn write_sources_csv(path: &Path, r: &MapResult) -> Result<()> {
    // The stops that heard each source and its state at the run's end (`asm::History`)
    // come after the columns of earlier versions, so that a reader by position still works.
    let mut s = String::from(
        "x_m,y_m,observations,particles,cov_xx,cov_xy,cov_yy,round,first_stop,last_stop,heard_stops,heard_share,state,silent_since\n",
    );
    for src in &r.sources {
        let h = &src.history;
        s.push_str(&format!(
            "{:.4},{:.4},{},{},{:.6},{:.6},{:.6},{},{},{},{},{:.3},{},{}\n",
            src.x,
            src.y,
            src.observations,
            src.particles,
            src.covariance[0][0],
            src.covariance[0][1],
            src.covariance[1][1],
            src.round,
            h.first_stop,
            h.last_stop,
            h.heard_stops,
            h.heard_share,
            if h.is_active() { "active" } else { "silent" },
            h.silent_since().map_or(String::new(), |k| k.to_string()),
        ));
    }
    crate::output::write_atomic(path, s.as_bytes())
}
