//! `iasm regress`: the synthetic-room regression suite. Every scene in a folder is
//! simulated, localised with every SSL method and mapped with I-ASM; its DoA score and map
//! OSPA are checked against the thresholds in the scene's `[expect]` table.

use std::path::Path;

use anyhow::{Context, Result};
use asm::map::OccupancyMap;
use asm::ospa::{Ospa, ospa};
use asm::{IasmConfig, MapResult, Mapper, Pose};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rayon::prelude::*;
use serde::Serialize;
use ssl::{Audio, Localizer, Method, MicArray, SslConfig};

use crate::Outcome;
use crate::dataset::list_files;
use crate::score::{DoaScore, score_doas};
use crate::simulate::{load_scene, scene_map};
use sim::scene::PreparedScene;

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

/// A scene rendered at every stop, with what the pipeline needs to run on it.
pub struct Simulated {
    /// The scene's name (or its file's stem).
    pub name: String,
    /// The checked scene.
    pub scene: PreparedScene,
    /// What the array heard at each stop.
    pub audio: Vec<Audio>,
    /// The scene's array.
    pub array: MicArray,
    /// True source positions (m).
    pub truth: Vec<[f64; 2]>,
    /// DoAs per stop, N.
    pub n: usize,
    /// Robot poses (rad).
    pub poses: Vec<Pose>,
    /// The scene's occupancy map.
    pub map: OccupancyMap,
}

/// One method's run on a [`Simulated`] scene.
pub struct MethodRun {
    /// DoAs per stop (degrees, array frame).
    pub doas_deg: Vec<Vec<f64>>,
    /// Their score.
    pub score: DoaScore,
    /// The I-ASM map (seeded by the scene's seed).
    pub map: MapResult,
    /// Its OSPA (p = 1, c = 1 m).
    pub ospa: Ospa,
}

impl Simulated {
    /// Reads, checks and renders the scene in `path`.
    ///
    /// # Errors
    /// A scene that cannot be read or simulated, named.
    pub fn from_file(path: &Path) -> Result<Self> {
        let scene = load_scene(path)?;
        let stem = path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        Self::render(scene, stem)
    }

    /// Renders a checked scene (`fallback_name` when it has none).
    ///
    /// # Errors
    /// If the array or the map cannot be built.
    pub fn render(scene: PreparedScene, fallback_name: String) -> Result<Self> {
        let name = if scene.scene.name.is_empty() {
            fallback_name
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
        let poses = scene
            .stops
            .iter()
            .map(|s| Pose {
                x: s[0],
                y: s[1],
                theta: s[2],
            })
            .collect();
        let map = scene_map(&scene);
        Ok(Self {
            name,
            scene,
            audio,
            array,
            truth,
            n,
            poses,
            map,
        })
    }

    /// Localises every stop with `method`, scores the DoAs and maps them.
    ///
    /// # Errors
    /// Settings refused, or tables that do not fit (bugs here).
    pub fn run(&self, method: Method) -> Result<MethodRun> {
        let fs = self.scene.scene.fs;
        let loc = Localizer::new(
            &self.array,
            fs,
            &SslConfig {
                method,
                num_peaks: self.n,
                ..SslConfig::default()
            },
        )?;
        let doas_deg: Vec<Vec<f64>> = self
            .audio
            .par_iter()
            .map(|a| {
                loc.locate(a)
                    .map(|d| d.iter().map(|x| x.azimuth_deg).collect())
            })
            .collect::<Result<_, _>>()
            .with_context(|| format!("localising scene {}", self.name))?;
        let table: crate::dataset::Table = doas_deg
            .iter()
            .map(|r| r.iter().map(|&a| Some(a)).collect())
            .collect();
        let score_poses: Vec<crate::dataset::Pose> = self
            .poses
            .iter()
            .map(|p| crate::dataset::Pose {
                x: p.x,
                y: p.y,
                theta_deg: p.theta.to_degrees(),
            })
            .collect();
        let score = score_doas(&table, &score_poses, &self.truth, self.n, 5.0)?;
        let rad: Vec<Vec<f64>> = doas_deg
            .iter()
            .map(|r| r.iter().map(|a| a.to_radians()).collect())
            .collect();
        let mapper = Mapper::new(
            &self.map,
            &IasmConfig {
                num_doas: self.n,
                ..IasmConfig::default()
            },
        )?;
        let map = mapper.run(
            &self.poses,
            &rad,
            &mut StdRng::seed_from_u64(self.scene.scene.seed),
        )?;
        let ospa = ospa(&map.positions(), &self.truth, 1.0, 1.0);
        Ok(MethodRun {
            doas_deg,
            score,
            map,
            ospa,
        })
    }
}

/// Simulates one scene and runs the pipeline on it with every method.
///
/// # Errors
/// A scene that cannot be read or simulated, named.
pub fn run_scene(path: &Path) -> Result<Vec<SceneResult>> {
    let sim = Simulated::from_file(path)?;
    let e = &sim.scene.scene.expect;
    Method::ALL
        .iter()
        .map(|&method| {
            let r = sim.run(method)?;
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
                stops: sim.poses.len(),
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
