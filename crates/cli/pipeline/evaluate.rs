//! The paper's Monte Carlo evaluation: every variant over many seeds, and each one's
//! statistics.

use super::*;

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
    /// The share of runs that found exactly as many sources as the truth holds.
    pub right_count: f64,
    /// The worst run's OSPA (m).
    pub worst: f64,
    /// The seed of the worst run.
    pub worst_seed: u64,
    /// Every run's OSPA (m), by seed.
    pub runs: Vec<f64>,
    /// Every run's number of sources, by seed.
    pub sources: Vec<usize>,
    /// The mean distance of matched sources from the truth, before and after each run's
    /// best similarity transform of the map onto the truth, and the transforms' mean scale
    /// and rotation (degrees): a diagnostic of the data's frames (`asm::align`). `None`
    /// when no run matched three sources.
    pub aligned: Option<AlignedStats>,
    /// True sources missed per run, and of those how many the mapper made and refused, by
    /// rule (the mean of each run's [`MissedTally`]): a source lost to the mapper's rules
    /// rather than to the DoAs.
    pub missed: MissedTally,
}

/// The runs' [`asm::align::Alignment`]s, averaged.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct AlignedStats {
    /// Runs with a transform (three matched sources or more).
    pub runs: usize,
    /// Mean distance of matched sources from the truth (m).
    pub mean_before_m: f64,
    /// The same after each run's transform (m).
    pub mean_after_m: f64,
    /// Mean scale of the transforms.
    pub scale: f64,
    /// Mean rotation of the transforms (degrees).
    pub rotation_deg: f64,
}

/// The paper's Monte Carlo evaluation: `runs` seeded maps (seeds `seed0..seed0 + runs`) of
/// each variant, in parallel, scored with OSPA (cutoff `c` m, order `p`).
///
/// # Errors
/// A survey without truth, or as [`Mapper::new`] and [`Mapper::run`].
pub fn evaluate(
    survey: &Survey,
    base: &IasmConfig,
    variants: &[Variant],
    runs: usize,
    seed0: u64,
    c: f64,
    p: f64,
) -> Result<Vec<VariantStats>> {
    let truth = survey
        .truth
        .as_ref()
        .context("the evaluation needs ground truth (src_gt* or --truth)")?;
    let doas_rad = survey.doas_rad();
    let bar = crate::progress((variants.len() * runs) as u64, "mapping");
    let out = variants
        .iter()
        .map(|&v| {
            let config = IasmConfig {
                variant: v,
                ..survey.mapper_config(base)
            };
            let mapper = Mapper::new(&survey.map, &config)?;
            let res: Vec<Run> = (0..runs as u64)
                .into_par_iter()
                .map(|s| {
                    let r = mapper.run_seeded(
                        &survey.poses,
                        &doas_rad,
                        survey.cut.as_deref(),
                        seed0 + s,
                    )?;
                    bar.inc(1);
                    let found = r.positions();
                    Ok((
                        ospa(&found, truth, c, p),
                        r.sources.len(),
                        asm::align::align(&found, truth, c),
                        MissedTally::of(&r, truth, c),
                    ))
                })
                .collect::<Result<_>>()?;
            Ok(summarise(v, &res, truth.len(), seed0))
        })
        .collect::<Result<Vec<_>>>();
    bar.finish_and_clear();
    out
}

/// One run's OSPA, source count, alignment, and how its missed sources were lost.
type Run = (Ospa, usize, Option<asm::align::Alignment>, MissedTally);

fn summarise(variant: Variant, res: &[Run], truth: usize, seed0: u64) -> VariantStats {
    let n = res.len() as f64;
    let fits: Vec<_> = res.iter().filter_map(|r| r.2).collect();
    let k = fits.len() as f64;
    let aligned = (!fits.is_empty()).then(|| AlignedStats {
        runs: fits.len(),
        mean_before_m: fits.iter().map(|f| f.mean_before_m).sum::<f64>() / k,
        mean_after_m: fits.iter().map(|f| f.mean_after_m).sum::<f64>() / k,
        scale: fits.iter().map(|f| f.scale).sum::<f64>() / k,
        rotation_deg: fits
            .iter()
            .map(|f| f.rotation_rad.to_degrees())
            .sum::<f64>()
            / k,
    });
    let runs: Vec<f64> = res.iter().map(|r| r.0.total).collect();
    let mut sorted = runs.clone();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    let median = if sorted.len() % 2 == 1 {
        sorted[mid]
    } else {
        0.5 * (sorted[mid - 1] + sorted[mid])
    };
    VariantStats {
        variant,
        mean: sorted.iter().sum::<f64>() / n,
        median,
        mean_localization: res.iter().map(|r| r.0.localization).sum::<f64>() / n,
        mean_cardinality: res.iter().map(|r| r.0.cardinality).sum::<f64>() / n,
        mean_sources: res.iter().map(|r| r.1 as f64).sum::<f64>() / n,
        right_count: res.iter().filter(|r| r.1 == truth).count() as f64 / n,
        worst: sorted.last().copied().unwrap_or(f64::NAN),
        worst_seed: seed0
            + runs
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(i, _)| i as u64),
        runs,
        sources: res.iter().map(|r| r.1).collect(),
        aligned,
        missed: MissedTally::mean(res.iter().map(|r| r.3)),
    }
}
