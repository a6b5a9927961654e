//! `iasm map` and `iasm eval`: I-ASM from DoA tables (or raw audio) to a map of sources,
//! once or as the paper's Monte Carlo evaluation.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail, ensure};
use asm::map::OccupancyMap;
use asm::ospa::{Ospa, ospa};
use asm::{IasmConfig, MapResult, Mapper, Pose, Variant};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rayon::prelude::*;
use serde::Serialize;
use ssl::{MicArray, SslConfig};

use crate::Outcome;
use crate::args::{EvalArgs, InputArgs, MapArgs};
use crate::dataset::{Dataset, list_files, read_poses, read_sources, read_table};
use crate::ssl_cmd::{doa_table, localise_files};

/// Version of the JSON `iasm map` writes.
pub const SCHEMA_VERSION: u32 = 1;

/// Everything a mapping run needs, read and checked.
#[derive(Clone, Debug)]
pub struct MapInputs {
    /// The occupancy map.
    pub map: OccupancyMap,
    /// Robot poses (theta in radians).
    pub poses: Vec<Pose>,
    /// Array-frame DoAs (rad) per stop.
    pub doas: Vec<Vec<f64>>,
    /// Ground-truth sources, when known.
    pub truth: Option<Vec<[f64; 2]>>,
    /// Where the DoAs came from (a table's path, or `ssl:<method>`).
    pub doa_source: String,
}

/// Reads a ROS map; when the image the YAML names is missing and the YAML's folder holds
/// exactly one PGM, reads that one instead and says so on stderr.
///
/// # Errors
/// If the map cannot be read.
pub fn load_map(yaml: &Path) -> Result<OccupancyMap> {
    let named =
        OccupancyMap::image_path(yaml).map_err(|m| anyhow::anyhow!("{}: {m}", yaml.display()))?;
    let image = if named.exists() {
        None
    } else {
        let dir = yaml.parent().unwrap_or(Path::new("."));
        let pgms = list_files(dir, "pgm")?;
        match pgms.as_slice() {
            [only] => {
                eprintln!(
                    "warning: {} names the image {}, which does not exist; using {}, the only PGM beside it",
                    yaml.display(),
                    named.display(),
                    only.display()
                );
                Some(only.clone())
            }
            _ => None,
        }
    };
    Ok(OccupancyMap::load_with_image(yaml, image.as_deref())?)
}

/// Reads a DoA table (degrees) into per-stop azimuths in radians, dropping empty cells.
///
/// # Errors
/// If the table cannot be read.
pub fn read_doas(path: &Path) -> Result<Vec<Vec<f64>>> {
    Ok(read_table(path)?
        .into_iter()
        .map(|row| row.into_iter().flatten().map(f64::to_radians).collect())
        .collect())
}

fn to_rad(poses: Vec<crate::dataset::Pose>) -> Vec<Pose> {
    poses
        .into_iter()
        .map(|p| Pose {
            x: p.x,
            y: p.y,
            theta: p.theta_deg.to_radians(),
        })
        .collect()
}

fn first_with_ext(dir: &Path, ext: &str) -> Result<PathBuf> {
    list_files(dir, ext)?
        .into_iter()
        .next()
        .with_context(|| format!("no .{ext} file in {}", dir.display()))
}

/// Resolves the map, poses, DoAs and truth from the command line.
///
/// # Errors
/// Missing or unreadable inputs, named.
pub fn load_inputs(a: &InputArgs) -> Result<MapInputs> {
    let ds = a.dataset.as_deref().map(Dataset::open).transpose()?;
    let map_path = match (&a.map, &ds) {
        (Some(p), _) => p.clone(),
        (None, Some(d)) => first_with_ext(&d.root.join("map"), "yaml")?,
        (None, None) => bail!("give --dataset DIR or --map map.yaml"),
    };
    let map = load_map(&map_path)?;
    let pose_path = match (&a.poses, &ds) {
        (Some(p), _) => p.clone(),
        (None, Some(d)) => d
            .poses
            .clone()
            .with_context(|| format!("{}: no pose table in pose/", d.root.display()))?,
        (None, None) => bail!("give --dataset DIR or --poses FILE"),
    };
    let theta_rad = match a.theta_unit.as_str() {
        "deg" | "degrees" => false,
        "rad" | "radians" => true,
        other => bail!("--theta-unit {other:?}: expected deg or rad"),
    };
    let poses = to_rad(read_poses(&pose_path, theta_rad)?);
    let truth_path = a
        .truth
        .clone()
        .or_else(|| ds.as_ref().and_then(|d| d.sources.clone()));
    let truth = truth_path.as_deref().map(read_sources).transpose()?;
    let (doas, doa_source) = if let Some(t) = &a.doas {
        (read_doas(t)?, t.display().to_string())
    } else {
        let files = match (&a.audio, &ds) {
            (Some(dir), _) => list_files(dir, "wav")?,
            (None, Some(d)) => d.audio.clone(),
            (None, None) => bail!("give --doas TABLE, --audio DIR or --dataset DIR"),
        };
        ensure!(!files.is_empty(), "no WAV file to localise");
        ensure!(
            files.len() == poses.len(),
            "{} recordings but {} poses in {}: they must match one to one",
            files.len(),
            poses.len(),
            pose_path.display()
        );
        let config = SslConfig {
            method: a.method.parse()?,
            num_peaks: a.num,
            ..SslConfig::default()
        };
        let array = MicArray::from_spec(&a.array)?;
        let rows = localise_files(&files, &array, &config)?;
        let table = doa_table(&rows, a.num);
        (
            table
                .into_iter()
                .map(|r| r.into_iter().flatten().map(f64::to_radians).collect())
                .collect(),
            format!("ssl:{}", config.method),
        )
    };
    ensure!(
        doas.len() == poses.len(),
        "{} rows of DoAs ({doa_source}) but {} poses ({}): they must match one to one",
        doas.len(),
        poses.len(),
        pose_path.display()
    );
    Ok(MapInputs {
        map,
        poses,
        doas,
        truth,
        doa_source,
    })
}

/// I-ASM settings from an optional TOML file and the flags.
///
/// # Errors
/// If the file cannot be read or a value is refused.
pub fn iasm_config(a: &InputArgs, variant: Option<&str>) -> Result<IasmConfig> {
    let mut c = match &a.iasm_config {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("reading I-ASM settings {}", p.display()))?;
            toml::from_str::<IasmConfig>(&text)
                .map_err(|e| anyhow::anyhow!("{}: {}", p.display(), e.message()))?
        }
        None => IasmConfig::default(),
    };
    c.num_doas = a.num;
    c.refine |= a.refine;
    if let Some(v) = variant {
        c.variant = v.parse::<Variant>().map_err(anyhow::Error::msg)?;
    }
    c.validate()?;
    Ok(c)
}

/// One run's report.
#[derive(Serialize)]
struct MapReport<'a> {
    schema_version: u32,
    doas: &'a str,
    seed: u64,
    params: &'a IasmConfig,
    rounds: usize,
    particles: usize,
    unexplained_doas: usize,
    sources: &'a [asm::Source],
    ospa: Option<OspaReport>,
}

#[derive(Clone, Copy, Serialize)]
struct OspaReport {
    p: f64,
    c: f64,
    #[serde(flatten)]
    value: Ospa,
}

/// Runs `iasm map`.
///
/// # Errors
/// Bad inputs or settings, or files that cannot be written.
pub fn run_map(a: &MapArgs) -> Result<Outcome> {
    let inputs = load_inputs(&a.input)?;
    let config = iasm_config(&a.input, Some(&a.variant))?;
    let mapper = Mapper::new(&inputs.map, &config)?;
    let t0 = std::time::Instant::now();
    let result = mapper.run(
        &inputs.poses,
        &inputs.doas,
        &mut StdRng::seed_from_u64(a.seed),
    )?;
    let dt = t0.elapsed().as_secs_f64();
    let o = inputs.truth.as_ref().map(|t| OspaReport {
        p: a.report.ospa_p,
        c: a.report.ospa_c,
        value: ospa(&result.positions(), t, a.report.ospa_c, a.report.ospa_p),
    });
    let report = MapReport {
        schema_version: SCHEMA_VERSION,
        doas: &inputs.doa_source,
        seed: a.seed,
        params: &config,
        rounds: result.rounds,
        particles: result.particles,
        unexplained_doas: result.unexplained,
        sources: &result.sources,
        ospa: o,
    };
    if let Some(out) = &a.out {
        std::fs::write(out, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", out.display()))?;
    }
    if let Some(csv) = &a.csv {
        write_sources_csv(csv, &result)?;
    }
    if let Some(png) = &a.png {
        crate::render::write_png(
            png,
            &inputs.map,
            &inputs.poses,
            &result,
            inputs.truth.as_deref(),
        )?;
    }
    if a.report.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(Outcome::Success);
    }
    println!(
        "I-ASM ({}) on {} stops, DoAs from {}: {} sources in {} rounds of {} particles ({:.0} ms, seed {})",
        config.variant.name(),
        inputs.poses.len(),
        inputs.doa_source,
        result.sources.len(),
        result.rounds,
        result.particles,
        1e3 * dt,
        a.seed
    );
    println!(
        "{:>3} {:>8} {:>8} {:>6} {:>9} {:>9} {:>6}",
        "#", "x (m)", "y (m)", "DoAs", "particles", "2σ (m)", "round"
    );
    for (i, s) in result.sources.iter().enumerate() {
        let two_sigma = 2.0 * asm::pf::max_eigenvalue(s.covariance).sqrt();
        println!(
            "{:>3} {:>8.3} {:>8.3} {:>6} {:>9} {:>9.3} {:>6}",
            i + 1,
            s.x,
            s.y,
            s.observations,
            s.particles,
            two_sigma,
            s.round
        );
    }
    if let Some(o) = o {
        println!(
            "OSPA (p = {}, c = {} m): {:.3} m (localisation {:.3}, cardinality {:.3})",
            o.p, o.c, o.value.total, o.value.localization, o.value.cardinality
        );
    }
    Ok(Outcome::Success)
}

fn write_sources_csv(path: &Path, r: &MapResult) -> Result<()> {
    let mut s = String::from("x_m,y_m,observations,particles,cov_xx,cov_xy,cov_yy,round\n");
    for src in &r.sources {
        s.push_str(&format!(
            "{:.4},{:.4},{},{},{:.6},{:.6},{:.6},{}\n",
            src.x,
            src.y,
            src.observations,
            src.particles,
            src.covariance[0][0],
            src.covariance[0][1],
            src.covariance[1][1],
            src.round
        ));
    }
    std::fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}

/// One variant's Monte Carlo summary.
#[derive(Clone, Debug, Serialize)]
pub struct VariantStats {
    /// The variant.
    pub variant: Variant,
    /// Mean OSPA (m).
    pub mean: f64,
    /// Median OSPA (m).
    pub median: f64,
    /// Mean localisation part (m).
    pub mean_localization: f64,
    /// Mean cardinality part (m).
    pub mean_cardinality: f64,
    /// Mean number of sources found.
    pub mean_sources: f64,
    /// Every run's OSPA (m), by seed.
    pub runs: Vec<f64>,
}

/// Runs `runs` seeded mappings (seeds `seed0..seed0 + runs`) of each variant in parallel.
///
/// # Errors
/// As [`Mapper::new`] and [`Mapper::run`].
pub fn evaluate(
    inputs: &MapInputs,
    base: &IasmConfig,
    variants: &[Variant],
    runs: usize,
    seed0: u64,
    c: f64,
    p: f64,
) -> Result<Vec<VariantStats>> {
    let truth = inputs
        .truth
        .as_ref()
        .context("the evaluation needs ground truth (src_gt* or --truth)")?;
    let bar = crate::progress((variants.len() * runs) as u64, "mapping");
    let out = variants
        .iter()
        .map(|&v| {
            let mapper = Mapper::new(
                &inputs.map,
                &IasmConfig {
                    variant: v,
                    ..base.clone()
                },
            )?;
            let res: Vec<(Ospa, usize)> = (0..runs as u64)
                .into_par_iter()
                .map(|s| {
                    let r = mapper.run(
                        &inputs.poses,
                        &inputs.doas,
                        &mut StdRng::seed_from_u64(seed0 + s),
                    )?;
                    bar.inc(1);
                    Ok((ospa(&r.positions(), truth, c, p), r.sources.len()))
                })
                .collect::<Result<_>>()?;
            let n = res.len() as f64;
            let mut totals: Vec<f64> = res.iter().map(|r| r.0.total).collect();
            let runs_by_seed = totals.clone();
            totals.sort_by(f64::total_cmp);
            let median = if totals.len() % 2 == 1 {
                totals[totals.len() / 2]
            } else {
                0.5 * (totals[totals.len() / 2 - 1] + totals[totals.len() / 2])
            };
            Ok(VariantStats {
                variant: v,
                mean: totals.iter().sum::<f64>() / n,
                median,
                mean_localization: res.iter().map(|r| r.0.localization).sum::<f64>() / n,
                mean_cardinality: res.iter().map(|r| r.0.cardinality).sum::<f64>() / n,
                mean_sources: res.iter().map(|r| r.1 as f64).sum::<f64>() / n,
                runs: runs_by_seed,
            })
        })
        .collect::<Result<Vec<_>>>();
    bar.finish_and_clear();
    out
}

#[derive(Serialize)]
struct EvalReport<'a> {
    schema_version: u32,
    doas: &'a str,
    runs: usize,
    seed0: u64,
    ospa_p: f64,
    ospa_c: f64,
    seconds: f64,
    variants: &'a [VariantStats],
}

/// Runs `iasm eval`.
///
/// # Errors
/// Bad inputs or settings.
pub fn run_eval(a: &EvalArgs) -> Result<Outcome> {
    ensure!(a.runs > 0, "--runs must be at least 1");
    let inputs = load_inputs(&a.input)?;
    let base = iasm_config(&a.input, None)?;
    let t0 = std::time::Instant::now();
    let stats = evaluate(
        &inputs,
        &base,
        &Variant::ALL,
        a.runs,
        a.seed,
        a.report.ospa_c,
        a.report.ospa_p,
    )?;
    let secs = t0.elapsed().as_secs_f64();
    if a.report.json {
        let r = EvalReport {
            schema_version: SCHEMA_VERSION,
            doas: &inputs.doa_source,
            runs: a.runs,
            seed0: a.seed,
            ospa_p: a.report.ospa_p,
            ospa_c: a.report.ospa_c,
            seconds: secs,
            variants: &stats,
        };
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        println!(
            "I-ASM Monte Carlo: {} runs per variant, DoAs from {}, OSPA p = {}, c = {} m ({:.1} s)",
            a.runs, inputs.doa_source, a.report.ospa_p, a.report.ospa_c, secs
        );
        println!(
            "{:<8} {:>10} {:>10} {:>10} {:>10} {:>9}",
            "variant", "mean (m)", "median (m)", "loc. (m)", "card. (m)", "sources"
        );
        for s in &stats {
            println!(
                "{:<8} {:>10.3} {:>10.3} {:>10.3} {:>10.3} {:>9.2}",
                s.variant.name().to_uppercase(),
                s.mean,
                s.median,
                s.mean_localization,
                s.mean_cardinality,
                s.mean_sources
            );
        }
    }
    let ca = stats
        .iter()
        .find(|s| s.variant == Variant::Ca)
        .expect("CA is always evaluated");
    let mut failed = false;
    if let Some(max) = a.max_mean_ospa
        && ca.mean > max
    {
        eprintln!(
            "FAIL: CA mean OSPA {:.3} m is above --max-mean-ospa {max}",
            ca.mean
        );
        failed = true;
    }
    if a.expect_ablation {
        for s in stats.iter().filter(|s| s.variant != Variant::Ca) {
            if s.mean <= ca.mean {
                eprintln!(
                    "FAIL: {} mean OSPA {:.3} m is not worse than CA's {:.3} m",
                    s.variant.name().to_uppercase(),
                    s.mean,
                    ca.mean
                );
                failed = true;
            }
        }
    }
    Ok(if failed {
        Outcome::ThresholdFailed
    } else {
        Outcome::Success
    })
}
