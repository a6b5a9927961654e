//! `iasm regress`: the synthetic-room regression suite ([`crate::suite`]) as a table or
//! JSON, exit status 1 on a breached threshold.

use std::path::Path;

use anyhow::Result;
use ssl::Method;

use crate::Outcome;
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
