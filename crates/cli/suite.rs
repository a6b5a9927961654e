//! The synthetic-room regression suite: every scene in a folder is simulated, localised
//! with every SSL method and mapped with I-ASM; its DoA score and map OSPA are checked
//! against the thresholds in the scene's `[expect]` table. `iasm regress` and the
//! integration test run the same [`run_suite`].

use std::path::Path;

use anyhow::Result;
use serde::Serialize;
use ssl::Method;

use crate::dataset::list_files;
use crate::pipeline::{Simulated, scene_settings};
use crate::scenes::load_scene;

/// One scene run with one method.
#[derive(Clone, Debug, Serialize)]
pub struct SceneResult {
    /// The scene's name (or file stem).
    pub scene: String,
    /// The SSL method.
    pub method: &'static str,
    /// Stops.
    pub stops: usize,
    /// True sources.
    pub sources: usize,
    /// DoA score (hit within 5 degrees of a true bearing).
    pub doa_score: f64,
    /// Sources the map found.
    pub found: usize,
    /// OSPA of the map (m, p = 1, c = 1).
    pub ospa: f64,
    /// Thresholds missed, in words (empty when all hold).
    pub breaches: Vec<String>,
}

/// The whole suite.
#[derive(Clone, Debug, Serialize)]
pub struct SuiteReport {
    /// Version of this JSON.
    pub schema_version: u32,
    /// One row per scene and method.
    pub rows: Vec<SceneResult>,
    /// Wall time (s).
    pub seconds: f64,
}

impl SuiteReport {
    /// Every breach, labelled `scene/method`.
    pub fn breaches(&self) -> Vec<String> {
        self.rows
            .iter()
            .flat_map(|r| {
                r.breaches
                    .iter()
                    .map(move |b| format!("{}/{}: {b}", r.scene, r.method))
            })
            .collect()
    }

    /// The report as a table.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<22} {:<9} {:>5} {:>7} {:>9} {:>6} {:>8}  {}\n",
            "scene", "method", "stops", "sources", "DoA score", "found", "OSPA (m)", "status"
        );
        for r in &self.rows {
            let status = if r.breaches.is_empty() {
                "ok".to_owned()
            } else {
                r.breaches.join("; ")
            };
            s.push_str(&format!(
                "{:<22} {:<9} {:>5} {:>7} {:>9.3} {:>6} {:>8.3}  {}\n",
                r.scene, r.method, r.stops, r.sources, r.doa_score, r.found, r.ospa, status
            ));
        }
        s
    }
}

/// Simulates one scene and runs the pipeline on it with every method.
///
/// # Errors
/// A scene that cannot be read or simulated, named.
pub fn run_scene(path: &Path) -> Result<Vec<SceneResult>> {
    let (scene, e) = load_scene(path)?;
    let stem = path
        .file_stem()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned();
    let sim = Simulated::render(scene, stem)?;
    let n = e.num.unwrap_or(sim.truth.len().min(4));
    Method::ALL
        .iter()
        .map(|&method| {
            let r = sim.run(&scene_settings(method, n), sim.scene.scene.seed)?;
            let mut breaches = Vec::new();
            if let Some(min) = e.doa_score_min
                && r.score.score < min
            {
                breaches.push(format!("DoA score {:.3} < {min}", r.score.score));
            }
            if let Some(max) = e.ospa_max
                && r.ospa.total > max
            {
                breaches.push(format!("OSPA {:.3} > {max}", r.ospa.total));
            }
            Ok(SceneResult {
                scene: sim.name.clone(),
                method: method.name(),
                stops: sim.poses().len(),
                sources: sim.truth.len(),
                doa_score: r.score.score,
                found: r.map.sources.len(),
                ospa: r.ospa.total,
                breaches,
            })
        })
        .collect()
}

/// Runs every `*.toml` scene in `dir`, in natural name order.
///
/// # Errors
/// A folder that cannot be read or a scene that cannot be simulated.
pub fn run_suite(dir: &Path) -> Result<SuiteReport> {
    let t0 = std::time::Instant::now();
    let scenes = list_files(dir, "toml")?;
    anyhow::ensure!(!scenes.is_empty(), "no scene (*.toml) in {}", dir.display());
    let bar = crate::progress(scenes.len() as u64, "scenes");
    let mut rows = Vec::new();
    for s in &scenes {
        rows.extend(run_scene(s)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(SuiteReport {
        schema_version: 1,
        rows,
        seconds: t0.elapsed().as_secs_f64(),
    })
}
