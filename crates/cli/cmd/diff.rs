//! `iasm diff`: two maps of one building compared (`asm::diff`), as a table, JSON and a
//! figure of both maps.

use anyhow::{Context, Result, bail};
use asm::diff::{Change, ChangeKind, DiffConfig, diff};
use serde::Serialize;

use crate::Outcome;
use crate::args::DiffArgs;
use crate::mapfile::MapFile;

/// Version of the JSON `iasm diff` writes.
pub const SCHEMA_VERSION: u32 = 1;

/// The comparison's report.
#[derive(Serialize)]
struct DiffReport<'a> {
    schema_version: u32,
    before: &'a std::path::Path,
    after: &'a std::path::Path,
    #[serde(skip_serializing_if = "Option::is_none")]
    frame_id: Option<&'a str>,
    config: DiffConfig,
    kept: usize,
    moved: usize,
    removed: usize,
    added: usize,
    changes: Vec<ChangeRow>,
}

/// A change with the positions it joins and the later map's state of its source.
#[derive(Serialize)]
struct ChangeRow {
    #[serde(flatten)]
    change: Change,
    /// Where it was in the earlier map.
    #[serde(skip_serializing_if = "Option::is_none")]
    from: Option<[f64; 2]>,
    /// Where it is in the later map.
    #[serde(skip_serializing_if = "Option::is_none")]
    to: Option<[f64; 2]>,
    /// In the later map, the stop from which it was silent at the end of that run.
    #[serde(skip_serializing_if = "Option::is_none")]
    silent_since: Option<usize>,
}

/// Runs `iasm diff`.
///
/// # Errors
/// Maps that cannot be read, maps in two frames, settings out of range, files that cannot
/// be written.
pub fn run(a: &DiffArgs) -> Result<Outcome> {
    if let Some(png) = &a.png {
        crate::figure::Format::of(png)?;
    }
    let config = DiffConfig {
        floor_m: a.floor_m,
        same_p: a.same_p,
        move_max_m: a.move_max_m,
    };
    // The flags' parsers check each value (`args::diff`); this holds for arguments built
    // without them.
    config.check().map_err(anyhow::Error::msg)?;
    let (before, after) = (MapFile::read(&a.before)?, MapFile::read(&a.after)?);
    if let (Some(fa), Some(fb)) = (&before.frame_id, &after.frame_id)
        && fa != fb
    {
        bail!(
            "{} is in frame {fa:?} and {} in {fb:?}: two maps are compared in one frame",
            a.before.display(),
            a.after.display()
        );
    }
    let changes = diff(&before.placed(), &after.placed(), &config);
    let report = report(&before, &after, config, &changes);
    if let Some(out) = &a.out {
        crate::output::write_atomic(out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    }
    if let Some(png) = &a.png {
        let map = a
            .map
            .as_deref()
            .map(asm::map::OccupancyMap::load)
            .transpose()
            .context("--map")?;
        crate::figure::diff(
            png,
            &crate::figure::DiffFigure {
                title: format!(
                    "{} -> {}: {} kept, {} moved, {} removed, {} added",
                    crate::dataset::file_name(&a.before),
                    crate::dataset::file_name(&a.after),
                    report.kept,
                    report.moved,
                    report.removed,
                    report.added
                ),
                map: map.as_ref(),
                before: &before.placed(),
                after: &after.placed(),
                changes: &changes,
                width: a.figure_width,
            },
        )?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report, &config);
    }
    Ok(Outcome::Success)
}

fn report<'a>(
    before: &'a MapFile,
    after: &'a MapFile,
    config: DiffConfig,
    changes: &[Change],
) -> DiffReport<'a> {
    let count = |k: ChangeKind| changes.iter().filter(|c| c.kind == k).count();
    let at =
        |m: &MapFile, i: Option<usize>| i.map(|i| [m.sources[i].placed.x, m.sources[i].placed.y]);
    DiffReport {
        schema_version: SCHEMA_VERSION,
        before: &before.path,
        after: &after.path,
        frame_id: before.frame_id.as_deref().or(after.frame_id.as_deref()),
        config,
        kept: count(ChangeKind::Kept),
        moved: count(ChangeKind::Moved),
        removed: count(ChangeKind::Removed),
        added: count(ChangeKind::Added),
        changes: changes
            .iter()
            .map(|&c| ChangeRow {
                change: c,
                from: at(before, c.before),
                to: at(after, c.after),
                silent_since: c.after.and_then(|j| after.sources[j].silent_since),
            })
            .collect(),
    }
}

fn print_table(r: &DiffReport<'_>, config: &DiffConfig) {
    println!(
        "{} ({} sources) -> {} ({} sources); floor {:.2} m, kept while p >= {:.2}, moves up to {:.1} m",
        r.before.display(),
        r.kept + r.moved + r.removed,
        r.after.display(),
        r.kept + r.moved + r.added,
        config.floor_m,
        1.0 - config.same_p,
        config.move_max_m
    );
    println!(
        "{:<8} {:<20} {:<20} {:>9} {:>8} {:>7} {:>10}  note",
        "change", "before", "after", "dist (m)", "m²", "p_same", "confidence"
    );
    let place = |i: Option<usize>, p: Option<[f64; 2]>| match (i, p) {
        (Some(i), Some([x, y])) => format!("s{} ({x:.2}, {y:.2})", i + 1),
        _ => "-".to_owned(),
    };
    for row in &r.changes {
        let c = &row.change;
        let mut note = match c.kind {
            ChangeKind::Removed | ChangeKind::Added => match c.nearest {
                Some(n) => format!("nearest in the other map: s{}", n + 1),
                None => "the other map is empty".to_owned(),
            },
            _ => String::new(),
        };
        if let Some(k) = row.silent_since {
            note = format!(
                "{note}{}silent since stop {k}",
                if note.is_empty() { "" } else { "; " }
            );
        }
        println!(
            "{:<8} {:<20} {:<20} {:>9} {:>8} {:>7.3} {:>10.3}  {note}",
            c.kind.name(),
            place(c.before, row.from),
            place(c.after, row.to),
            c.distance_m.map_or("-".to_owned(), |d| format!("{d:.3}")),
            c.mahalanobis2.map_or("-".to_owned(), |v| format!("{v:.1}")),
            c.p_same,
            c.confidence
        );
    }
    println!(
        "{} kept, {} moved, {} removed, {} added",
        r.kept, r.moved, r.removed, r.added
    );
}
