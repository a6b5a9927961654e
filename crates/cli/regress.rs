//! `iasm regress`: the synthetic-room regression suite. Every scene in a folder is
//! simulated, localised with every SSL method and mapped with I-ASM; its DoA score and map
//! OSPA are checked against the thresholds in the scene's `[expect]` table.

use std::path::Path;

use anyhow::{Context, Result};
use asm::ospa::ospa;
use asm::{IasmConfig, Mapper, Pose};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rayon::prelude::*;
use serde::Serialize;
use ssl::{Audio, Localizer, Method, MicArray, SslConfig};

use crate::Outcome;
use crate::dataset::list_files;
use crate::score::score_doas;
use crate::simulate::{load_scene, scene_map};

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
    let scene = load_scene(path)?;
    let name = if scene.scene.name.is_empty() {
        path.file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned()
    } else {
        scene.scene.name.clone()
    };
    let fs = scene.scene.fs;
    let audio: Vec<Audio> = (0..scene.stops.len())
        .into_par_iter()
        .map(|k| {
            let ch = scene
                .render_stop(k)
                .into_iter()
                .map(|c| c.into_iter().map(|v| v as f32).collect())
                .collect();
            Audio::new(fs, ch).map_err(anyhow::Error::from)
        })
        .collect::<Result<_>>()?;
    let array = MicArray::new(name.clone(), scene.mics.clone())?;
    let truth: Vec<[f64; 2]> = scene
        .scene
        .sources
        .iter()
        .map(|s| [s.pos[0], s.pos[1]])
        .collect();
    let n = scene.scene.expect.num.unwrap_or(truth.len().min(4));
    let poses: Vec<Pose> = scene
        .stops
        .iter()
        .map(|s| Pose {
            x: s[0],
            y: s[1],
            theta: s[2],
        })
        .collect();
    let score_poses: Vec<crate::dataset::Pose> = scene
        .stops
        .iter()
        .map(|s| crate::dataset::Pose {
            x: s[0],
            y: s[1],
            theta_deg: s[2].to_degrees(),
        })
        .collect();
    let map = scene_map(&scene);
    let mapper = Mapper::new(
        &map,
        &IasmConfig {
            num_doas: n,
            ..IasmConfig::default()
        },
    )?;
    Method::ALL
        .iter()
        .map(|&method| {
            let loc = Localizer::new(
                &array,
                fs,
                &SslConfig {
                    method,
                    num_peaks: n,
                    ..SslConfig::default()
                },
            )?;
            let doas: Vec<Vec<f64>> = audio
                .par_iter()
                .map(|a| {
                    loc.locate(a)
                        .map(|d| d.iter().map(|x| x.azimuth_deg).collect())
                })
                .collect::<Result<_, _>>()
                .with_context(|| format!("localising scene {name}"))?;
            let table: crate::dataset::Table = doas
                .iter()
                .map(|r| r.iter().map(|&a| Some(a)).collect())
                .collect();
            let score = score_doas(&table, &score_poses, &truth, n, 5.0)?;
            let rad: Vec<Vec<f64>> = doas
                .iter()
                .map(|r| r.iter().map(|a| a.to_radians()).collect())
                .collect();
            let result = mapper.run(&poses, &rad, &mut StdRng::seed_from_u64(scene.scene.seed))?;
            let o = ospa(&result.positions(), &truth, 1.0, 1.0).total;
            let e = &scene.scene.expect;
            let mut breaches = Vec::new();
            if let Some(min) = e.doa_score_min
                && score.score < min
            {
                breaches.push(format!("DoA score {:.3} < {min}", score.score));
            }
            if let Some(max) = e.ospa_max
                && o > max
            {
                breaches.push(format!("OSPA {o:.3} > {max}"));
            }
            Ok(SceneResult {
                scene: name.clone(),
                method: method.name(),
                stops: poses.len(),
                sources: truth.len(),
                doa_score: score.score,
                found: result.sources.len(),
                ospa: o,
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

/// Runs `iasm regress`.
///
/// # Errors
/// As [`run_suite`].
pub fn run(dir: &Path, json: bool) -> Result<Outcome> {
    let report = run_suite(dir)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table());
        println!(
            "{} scenes x {} methods in {:.1} s",
            report.rows.len() / Method::ALL.len(),
            Method::ALL.len(),
            report.seconds
        );
    }
    Ok(if report.breaches().is_empty() {
        Outcome::Success
    } else {
        Outcome::ThresholdFailed
    })
}
