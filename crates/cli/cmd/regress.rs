//! `iasm regress`: the synthetic-room regression suite ([`crate::suite`]) as a table or
//! JSON, exit status 1 on a breached threshold.

use std::path::Path;

use anyhow::Result;
use ssl::Method;

use crate::Outcome;
use crate::args::GeneratedArgs;
use crate::generated::{DrawThresholds, run_draw};
use crate::settings::Settings;
use crate::suite::run_suite;

/// Runs `iasm regress`.
///
/// # Errors
/// As [`run_suite`].
pub fn run(dir: &Path, settings: &Settings, num: Option<usize>, json: bool) -> Result<Outcome> {
    let report = run_suite(dir, settings, num)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table());
        println!(
            "{} scenes x {} methods in {:.1} s",
            report.rows.len() / Method::PAPER.len(),
            Method::PAPER.len(),
            report.seconds
        );
    }
    Ok(if report.breaches().is_empty() {
        Outcome::Success
    } else {
        Outcome::ThresholdFailed
    })
}

/// Runs `iasm regress --generated`.
///
/// # Errors
/// As [`run_draw`].
pub fn run_generated(a: &GeneratedArgs, settings: &Settings, json: bool) -> Result<Outcome> {
    let opts = crate::draw_options(&a.draw, a.renderings, a.map_seeds, a.floor_only)?;
    let report = run_draw(&opts, settings)?;
    let breaches = report.breaches(&DrawThresholds {
        max_mean: a.max_mean_ospa,
        max_p90: a.max_p90_ospa,
        min_right_count: a.min_right_count,
        max_outside: a.max_outside,
    });
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        if a.scenes {
            print!("{}", report.scenes_table());
            println!();
        }
        print!("{}", report.table());
        let mapped = if a.floor_only {
            "true bearings only".to_owned()
        } else {
            format!("{} methods and true bearings", Method::PAPER.len())
        };
        let talkers = if report.talkers.is_empty() {
            "speech-shaped noise".to_owned()
        } else {
            report.talkers.join(", ")
        };
        println!(
            "{} scenes (seeds {}..{}) x {} renderings x {} maps, {mapped}, talkers {talkers}, in {:.1} s",
            report.seeds[1] - report.seeds[0],
            report.seeds[0],
            report.seeds[1],
            report.renderings,
            report.map_seeds,
            report.seconds
        );
        for b in &breaches {
            println!("breach: {b}");
        }
    }
    Ok(if breaches.is_empty() {
        Outcome::Success
    } else {
        Outcome::ThresholdFailed
    })
}
