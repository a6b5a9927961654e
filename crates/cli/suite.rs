//! The synthetic-room regression suite: every scene in a folder is simulated, localised
//! with every SSL method and mapped with I-ASM, on several seeds; its DoA score and map
//! OSPA are checked against the thresholds in the scene's `[expect]` table. `iasm regress`
//! and the integration test run the same [`run_suite`].
//!
//! One seed per scene makes every figure chaotic (a particle filter's draw, or a 1e-6
//! change of the audio, can move a source count), so each scene runs with
//! [`Expect::seeds`] seeds (`seed`, `seed + 1`, ...): each renders the scene anew (signals
//! and sensor noise) and maps with that seed. A scene is judged on the mean over its seeds
//! and on its worst seed. N is set as a user who does not know the room would set it
//! ([`user_n`]), not to the true number of sources.

use std::path::Path;

use anyhow::Result;
use serde::Serialize;
use ssl::Method;

use crate::dataset::list_files;
use crate::pipeline::{Simulated, scene_settings};
use crate::scenes::{Expect, load_scene, prepare};
use crate::settings::Settings;

/// One scene run with one method, over its seeds.
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
    /// DoAs per stop, N.
    pub n: usize,
    /// The seeds run.
    pub seeds: Vec<u64>,
    /// Mean DoA score (first N DoAs, hit within 5 degrees of a true bearing).
    pub doa_score: f64,
    /// Sources the map found, per seed.
    pub found: Vec<usize>,
    /// Mean OSPA of the maps (m, p = 1, c = 1).
    pub ospa: f64,
    /// The worst seed's OSPA (m).
    pub ospa_worst: f64,
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
            "{:<22} {:<9} {:>5} {:>7} {:>2} {:>9} {:>12} {:>9} {:>9}  {}\n",
            "scene",
            "method",
            "stops",
            "sources",
            "N",
            "DoA score",
            "found",
            "OSPA mean",
            "worst",
            "status"
        );
        for r in &self.rows {
            let status = if r.breaches.is_empty() {
                "ok".to_owned()
            } else {
                r.breaches.join("; ")
            };
            let found: Vec<String> = r.found.iter().map(usize::to_string).collect();
            s.push_str(&format!(
                "{:<22} {:<9} {:>5} {:>7} {:>2} {:>9.3} {:>12} {:>9.3} {:>9.3}  {}\n",
                r.scene,
                r.method,
                r.stops,
                r.sources,
                r.n,
                r.doa_score,
                found.join(","),
                r.ospa,
                r.ospa_worst,
                status
            ));
        }
        s
    }
}

/// N as a user sets it without knowing the room: 3 for a room of up to three talkers, 4
/// beyond. It is an upper bound on what one stop hears, not the number of sources.
pub fn user_n(sources: usize) -> usize {
    if sources <= 3 { 3 } else { 4 }
}

/// The thresholds of `e` that `r` misses, in words.
fn breaches(e: &Expect, r: &SceneResult) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(min) = e.doa_score_min
        && r.doa_score < min
    {
        out.push(format!("mean DoA score {:.3} < {min}", r.doa_score));
    }
    if let Some(max) = e.ospa_max
        && r.ospa > max
    {
        out.push(format!("mean OSPA {:.3} > {max}", r.ospa));
    }
    if let Some(max) = e.ospa_worst_max
        && r.ospa_worst > max
    {
        out.push(format!("worst OSPA {:.3} > {max}", r.ospa_worst));
    }
    let (lo, hi) = (
        r.found.iter().copied().min().unwrap_or(0),
        r.found.iter().copied().max().unwrap_or(0),
    );
    if let Some(min) = e.found_min
        && lo < min
    {
        out.push(format!("found {lo} < {min}"));
    }
    if let Some(max) = e.found_max
        && hi > max
    {
        out.push(format!("found {hi} > {max}"));
    }
    out
}

/// Simulates one scene on each of its seeds and runs the pipeline on it with every method.
///
/// # Errors
/// A scene that cannot be read or simulated, named.
pub fn run_scene(path: &Path, base: &Settings) -> Result<Vec<SceneResult>> {
    let (scene, e) = load_scene(path)?;
    let stem = path
        .file_stem()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned();
    let base = &scene_base(base, &e)?;
    let seed0 = scene.scene.seed;
    let count = e.seeds.unwrap_or(DEFAULT_SEEDS);
    anyhow::ensure!(
        count >= 1,
        "scene {}: expect.seeds must be at least 1",
        path.display()
    );
    let seeds: Vec<u64> = (0..count as u64).map(|i| seed0 + i).collect();
    let sources = scene.scene.sources.len();
    let stops = scene.stops.len();
    let n = e.num.unwrap_or(user_n(sources));
    let template = scene.scene.clone();
    // The first seed is the scene as loaded; the others are prepared anew from it.
    let mut loaded = Some(scene);
    let mut name = None;
    let mut runs = Vec::new(); // per seed, per method: (score, found, ospa)
    for &seed in &seeds {
        let prepared = match loaded.take() {
            Some(p) => p,
            None => {
                let mut s = template.clone();
                s.seed = seed;
                prepare(s)?
            }
        };
        let sim = Simulated::render(prepared, stem.clone())?;
        name.get_or_insert_with(|| sim.name.clone());
        let per_method: Vec<(f64, usize, f64)> = Method::PAPER
            .iter()
            .map(|&method| {
                let r = sim.run(&scene_settings(base, method, n), seed)?;
                Ok((r.score.score, r.map.sources.len(), r.ospa.total))
            })
            .collect::<Result<_>>()?;
        runs.push(per_method);
    }
    let name = name.expect("at least one seed");
    let k = seeds.len() as f64;
    Ok(Method::PAPER
        .iter()
        .enumerate()
        .map(|(m, &method)| {
            let col: Vec<(f64, usize, f64)> = runs.iter().map(|r| r[m]).collect();
            let mut r = SceneResult {
                scene: name.clone(),
                method: method.name(),
                stops,
                sources,
                n,
                seeds: seeds.clone(),
                doa_score: col.iter().map(|c| c.0).sum::<f64>() / k,
                found: col.iter().map(|c| c.1).collect(),
                ospa: col.iter().map(|c| c.2).sum::<f64>() / k,
                ospa_worst: col.iter().map(|c| c.2).fold(0.0, f64::max),
                breaches: Vec::new(),
            };
            r.breaches = breaches(&e, &r);
            r
        })
        .collect())
}

/// `base` with the scene's `[expect.settings]` laid over it, key by key.
fn scene_base(base: &Settings, e: &Expect) -> Result<Settings> {
    let Some(over) = &e.settings else {
        return Ok(base.clone());
    };
    fn merge(into: &mut toml::Table, from: &toml::Table) {
        for (k, v) in from {
            match (into.get_mut(k), v) {
                (Some(toml::Value::Table(a)), toml::Value::Table(b)) => merge(a, b),
                _ => {
                    into.insert(k.clone(), v.clone());
                }
            }
        }
    }
    let mut t = toml::Table::try_from(base)?;
    merge(&mut t, over);
    let s = Settings::from_toml(&toml::to_string(&t)?)
        .map_err(|e| anyhow::anyhow!("expect.settings: {e:#}"))?;
    s.validate()?;
    Ok(s)
}

/// Seeds per scene when its `[expect]` does not say.
pub const DEFAULT_SEEDS: usize = 3;

/// Runs every `*.toml` scene in `dir`, in natural name order, with `base` settings (each
/// method in turn, and each scene's N).
///
/// # Errors
/// A folder that cannot be read or a scene that cannot be simulated.
pub fn run_suite(dir: &Path, base: &Settings) -> Result<SuiteReport> {
    let t0 = std::time::Instant::now();
    let scenes = list_files(dir, "toml")?;
    anyhow::ensure!(!scenes.is_empty(), "no scene (*.toml) in {}", dir.display());
    let bar = crate::progress(scenes.len() as u64, "scenes");
    let mut rows = Vec::new();
    for s in &scenes {
        rows.extend(run_scene(s, base)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(SuiteReport {
        schema_version: 2,
        rows,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_with_no_seeds_is_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.toml");
        std::fs::write(
            &p,
            "fs = 8000\nclip_s = 0.1\n[room]\ndims = [5.0, 4.0, 3.0]\n\
             absorption = [0.6, 0.6, 0.6, 0.6, 0.6, 0.6]\n[array]\npreset = \"iasm6\"\n\
             height = 0.8\n[[sources]]\npos = [1.0, 3.0, 1.0]\n[trajectory]\n\
             poses = [[1.0, 1.0, 0.0]]\n[expect]\nseeds = 0\n",
        )
        .unwrap();
        let e = format!("{:#}", run_scene(&p, &Settings::default()).unwrap_err());
        assert!(e.contains("s.toml") && e.contains("expect.seeds"), "{e}");
    }
}
