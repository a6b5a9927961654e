//! The generated benchmark: scenes drawn at random ([`sim::draw`]), each rendered several
//! times, localised with every method of the paper, mapped, and reported as a
//! distribution, beside the maps that **true bearings** through the same stops give.
//!
//! Why true bearings beside every scene: they are what the mapper could reach with a
//! perfect front end (every source heard at every stop, at its exact bearing), so each
//! scene's loss splits between the front end (the method's map against the floor) and the
//! mapper (the floor against zero). And why, beside each method, the bearings it heard
//! ([`heard_bearings`]: the exact bearing of each source one of its DoAs found, nothing
//! else): the front end's share splits again, into the sources it never heard (the floor
//! against these maps) and what its DoAs' errors and clutter cost the mapper (these maps
//! against the method's own).
//!
//! Why each scene is rendered more than once: the sensor noise and the late tail are drawn
//! anew each time, and a result that holds on one rendering only shows as spread
//! ([`Distribution::spread`]) instead of as accuracy.
//!
//! Why the seeds are split ([`sim::draw::TUNING_SEEDS`], [`sim::draw::JUDGING_SEEDS`]): a
//! default chosen on the scenes it is reported on is fitted to them. Choose on the tuning
//! seeds, report on the judging seeds once per change.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;
use sim::draw::{DrawConfig, Drawn, Family, draw};
use ssl::Method;

use crate::pipeline::{Simulated, Survey, scene_settings};
use crate::scenes::prepare;
use crate::settings::Settings;
use sim::scene::PreparedScene;

/// The method label of the maps made from true bearings.
pub const TRUE_BEARINGS: &str = "true-bearings";

/// What follows a method's label in the label of its maps from the bearings it heard
/// ([`heard_bearings`]).
pub const HEARD: &str = ":heard";

/// A DoA within this many degrees of a source's bearing heard that source (the DoA score's
/// tolerance, `iasm ssl --score`).
pub const HEARD_TOL_DEG: f64 = 5.0;

/// A mapped source further than this outside the room's walls is "outside the free
/// space" (m): two cells of the simulated maps, so that a vent 0.1 m off a wall placed a
/// few centimetres into it is not counted.
pub const OUTSIDE_TOLERANCE_M: f64 = 0.1;

/// What to draw and how often to render and map it.
#[derive(Clone, Debug)]
pub struct DrawOptions {
    /// The draw's seeds.
    pub seeds: Range<u64>,
    /// Renderings per scene (each with its own signals, sensor noise and late tail).
    pub renderings: usize,
    /// Maps per rendering and method (each with its own particle draw).
    pub map_seeds: usize,
    /// Talkers' recordings; empty: speech-shaped noise.
    pub talkers: Vec<PathBuf>,
    /// Map from true bearings only, rendering nothing: the mapper's own loss over many
    /// scenes in seconds.
    pub floor_only: bool,
    /// Draw changes too ([`sim::draw::DrawConfig::changes`]).
    pub changes: bool,
}

impl DrawOptions {
    /// The scene generator's configuration: every array preset, these talkers.
    pub fn draw_config(&self) -> DrawConfig {
        let mut c = DrawConfig::new(ssl::array::PRESETS.iter().map(|s| s.to_string()).collect());
        c.talkers = self.talkers.clone();
        c.changes = self.changes;
        c
    }
}

/// The talkers' recordings in `dir`: every `*.wav` in natural name order.
///
/// # Errors
/// A folder that cannot be read, or holds no WAV.
pub fn talkers_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let files = crate::dataset::list_files(dir, "wav")?;
    anyhow::ensure!(!files.is_empty(), "no talker (*.wav) in {}", dir.display());
    Ok(files)
}

/// One map of one rendering of one drawn scene.
#[derive(Clone, Debug, Serialize)]
pub struct MapRecord {
    /// The scene's name (`family-seed`).
    pub scene: String,
    /// The draw's seed.
    pub seed: u64,
    /// Its plan's family.
    pub family: Family,
    /// The array preset.
    pub array: String,
    /// An SSL method, or [`TRUE_BEARINGS`].
    pub method: String,
    /// The rendering (0, 1, ...).
    pub rendering: usize,
    /// True sources.
    pub sources: usize,
    /// N, DoAs per stop.
    pub n: usize,
    /// The stops' DoA score (first N DoAs within 5 degrees; 1 for true bearings).
    pub doa_score: f64,
    /// Sources the map found.
    pub found: usize,
    /// OSPA (m, p = 1, c = 1).
    pub ospa: f64,
    /// Mapped sources outside the room's walls (beyond [`OUTSIDE_TOLERANCE_M`]).
    pub outside: usize,
    /// For a scene that changes (`--changes`): OSPA (m) of the map's active sources
    /// against the places sounding at the last stop ([`crate::changes`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ospa_now: Option<f64>,
    /// For such a scene, when a stop saw its change happen: whether the map dated it
    /// within [`crate::changes::CHANGE_TOLERANCE_STOPS`] stops of the first stop that
    /// could tell ([`crate::changes`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub change_dated: Option<bool>,
}

/// The distribution of a group of maps.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Distribution {
    /// Maps.
    pub maps: usize,
    /// Mean OSPA (m).
    pub mean: f64,
    /// Median OSPA (m).
    pub median: f64,
    /// 90th percentile of OSPA (m; nearest rank).
    pub p90: f64,
    /// The share of maps that found as many sources as there are.
    pub right_count: f64,
    /// Mapped sources outside the free space, over all the maps.
    pub outside: usize,
    /// The mean, over scenes, of the largest difference between the mean OSPA of two
    /// renderings of the scene (m): how much a scene's figure owes to its rendering.
    pub spread: f64,
    /// Over the maps of scenes that change: mean OSPA now (m), and the share that dated
    /// the change; `None` when no scene changes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub now: Option<f64>,
    /// The share of those maps that dated the change within two stops.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dated: Option<f64>,
}

impl Distribution {
    /// The distribution of `maps`.
    pub fn of<'a>(maps: impl IntoIterator<Item = &'a MapRecord>) -> Self {
        let maps: Vec<&MapRecord> = maps.into_iter().collect();
        if maps.is_empty() {
            return Self::default();
        }
        let mut o: Vec<f64> = maps.iter().map(|m| m.ospa).collect();
        o.sort_by(f64::total_cmp);
        let n = o.len();
        let rank = |q: f64| o[((q * n as f64).ceil() as usize).clamp(1, n) - 1];
        let median = if n % 2 == 1 {
            o[n / 2]
        } else {
            0.5 * (o[n / 2 - 1] + o[n / 2])
        };
        // Per scene, the mean OSPA of each rendering; its range is the scene's spread.
        let mut per: BTreeMap<u64, BTreeMap<usize, (f64, usize)>> = BTreeMap::new();
        for m in &maps {
            let e = per
                .entry(m.seed)
                .or_default()
                .entry(m.rendering)
                .or_default();
            e.0 += m.ospa;
            e.1 += 1;
        }
        let spreads: Vec<f64> = per
            .values()
            .map(|r| {
                let means = r.values().map(|(s, k)| s / *k as f64);
                let (lo, hi) = means.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                });
                hi - lo
            })
            .collect();
        Self {
            maps: n,
            mean: o.iter().sum::<f64>() / n as f64,
            median,
            p90: rank(0.9),
            right_count: maps.iter().filter(|m| m.found == m.sources).count() as f64 / n as f64,
            outside: maps.iter().map(|m| m.outside).sum(),
            spread: spreads.iter().sum::<f64>() / spreads.len() as f64,
            now: {
                let v: Vec<f64> = maps.iter().filter_map(|m| m.ospa_now).collect();
                (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
            },
            dated: {
                let v: Vec<bool> = maps.iter().filter_map(|m| m.change_dated).collect();
                (!v.is_empty()).then(|| v.iter().filter(|&&d| d).count() as f64 / v.len() as f64)
            },
        }
    }
}

/// One group's row of the report: a method's maps of one family, one array, one range of
/// source counts, or all.
#[derive(Clone, Debug, Serialize)]
pub struct GroupRow {
    /// `all`, a family's name, an array preset or a range of source counts.
    pub group: String,
    /// An SSL method.
    pub method: String,
    /// The method's maps.
    pub maps: Distribution,
    /// The true-bearing maps of the same scenes and renderings.
    pub floor: Distribution,
    /// The maps from the exact bearings of the sources the method's DoAs heard
    /// ([`heard_bearings`]); empty (no maps) for the true bearings themselves.
    pub heard: Distribution,
}

/// The generated benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct GeneratedReport {
    /// Version of this JSON.
    pub schema_version: u32,
    /// The draw's seeds, `[first, end)`.
    pub seeds: [u64; 2],
    /// Renderings per scene.
    pub renderings: usize,
    /// Maps per rendering and method.
    pub map_seeds: usize,
    /// The talkers' recordings the draw played (file names); empty: speech-shaped noise.
    /// The same seeds give other scenes with other talkers, so a report says which.
    pub talkers: Vec<String>,
    /// Every map.
    pub maps: Vec<MapRecord>,
    /// Every method over all scenes, then per family, then per array.
    pub groups: Vec<GroupRow>,
    /// Wall time (s).
    pub seconds: f64,
}

/// Thresholds on each method's distribution over the whole draw.
#[derive(Clone, Debug, Default)]
pub struct DrawThresholds {
    /// Highest mean OSPA (m).
    pub max_mean: Option<f64>,
    /// Highest 90th percentile of OSPA (m).
    pub max_p90: Option<f64>,
    /// Lowest share of maps with the right count.
    pub min_right_count: Option<f64>,
    /// Most mapped sources outside the free space, over all maps.
    pub max_outside: Option<usize>,
}

impl GeneratedReport {
    /// The rows of group `group` (`all`, a family or an array).
    pub fn group(&self, group: &str) -> impl Iterator<Item = &GroupRow> {
        self.groups.iter().filter(move |g| g.group == group)
    }

    /// The thresholds each method's whole-draw distribution misses, in words.
    pub fn breaches(&self, t: &DrawThresholds) -> Vec<String> {
        let mut out = Vec::new();
        for g in self.group("all") {
            let d = &g.maps;
            let m = &g.method;
            if let Some(x) = t.max_mean
                && d.mean > x
            {
                out.push(format!("{m}: mean OSPA {:.3} > {x}", d.mean));
            }
            if let Some(x) = t.max_p90
                && d.p90 > x
            {
                out.push(format!("{m}: 90th percentile {:.3} > {x}", d.p90));
            }
            if let Some(x) = t.min_right_count
                && d.right_count < x
            {
                out.push(format!("{m}: right count {:.2} < {x}", d.right_count));
            }
            if let Some(x) = t.max_outside
                && d.outside > x
            {
                out.push(format!(
                    "{m}: {} sources outside the walls > {x}",
                    d.outside
                ));
            }
        }
        out
    }

    /// The report as tables: each method over all scenes, per family, per array; each
    /// beside its true-bearing floor.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<13} {:<9} {:>5} {:>7} {:>7} {:>7} {:>6} {:>4} {:>7} | {:>7} {:>7} | {:>7} {:>7} {:>6} {:>6}\n",
            "group",
            "method",
            "maps",
            "mean",
            "median",
            "p90",
            "right",
            "out",
            "spread",
            "heard",
            "h.right",
            "floor",
            "f.p90",
            "f.right",
            "ratio"
        );
        for g in &self.groups {
            let (d, f, h) = (&g.maps, &g.floor, &g.heard);
            s.push_str(&format!(
                "{:<13} {:<9} {:>5} {:>7.3} {:>7.3} {:>7.3} {:>5.0}% {:>4} {:>7.3} | {:>7.3} {:>6.0}% | {:>7.3} {:>7.3} {:>5.0}% {:>6.2}\n",
                g.group,
                g.method,
                d.maps,
                d.mean,
                d.median,
                d.p90,
                100.0 * d.right_count,
                d.outside,
                d.spread,
                h.mean,
                100.0 * h.right_count,
                f.mean,
                f.p90,
                100.0 * f.right_count,
                d.mean / f.mean.max(1e-3),
            ));
        }
        // Scenes that change (`--changes`): each group's maps against the places sounding
        // at the last stop, and the share that dated the change.
        if self.groups.iter().any(|g| g.maps.now.is_some()) {
            s.push_str(&format!(
                "\nscenes that change: {:<13} {:<9} {:>7} {:>7} | {:>7} {:>7}\n",
                "group", "method", "now", "dated", "floor", "f.dated"
            ));
            for g in self.groups.iter().filter(|g| g.maps.now.is_some()) {
                s.push_str(&format!(
                    "                    {:<13} {:<9} {:>7.3} {:>6.0}% | {:>7.3} {:>6.0}%\n",
                    g.group,
                    g.method,
                    g.maps.now.unwrap_or(0.0),
                    100.0 * g.maps.dated.unwrap_or(0.0),
                    g.floor.now.unwrap_or(0.0),
                    100.0 * g.floor.dated.unwrap_or(0.0)
                ));
            }
        }
        s
    }

    /// Per scene and method, the mean OSPA over its maps and its floor, worst first.
    pub fn scenes_table(&self) -> String {
        let mut rows: BTreeMap<(String, String), Vec<&MapRecord>> = BTreeMap::new();
        for m in &self.maps {
            rows.entry((m.scene.clone(), m.method.clone()))
                .or_default()
                .push(m);
        }
        let mut lines: Vec<(f64, String)> = Vec::new();
        for ((scene, method), maps) in &rows {
            if method == TRUE_BEARINGS {
                continue;
            }
            let d = Distribution::of(maps.iter().copied());
            let floor = Distribution::of(
                rows.get(&(scene.clone(), TRUE_BEARINGS.to_owned()))
                    .into_iter()
                    .flatten()
                    .copied(),
            );
            let m = maps[0];
            lines.push((
                d.mean,
                format!(
                    "{:<16} {:<10} {:<9} {:>2} {:>2} {:>6.3} {:>7.3} {:>7.3} {:>5.0}% {:>7.3}\n",
                    scene,
                    m.array,
                    method,
                    m.sources,
                    m.n,
                    maps.iter().map(|m| m.doa_score).sum::<f64>() / maps.len() as f64,
                    d.mean,
                    d.spread,
                    100.0 * d.right_count,
                    floor.mean
                ),
            ));
        }
        lines.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut s = format!(
            "{:<16} {:<10} {:<9} {:>2} {:>2} {:>6} {:>7} {:>7} {:>6} {:>7}\n",
            "scene", "array", "method", "S", "N", "DoA", "OSPA", "spread", "right", "floor"
        );
        for (_, l) in lines {
            s.push_str(&l);
        }
        s
    }
}

/// Draws, renders, localises and maps every scene of `opts`, with `base` settings (each
/// method and each scene's N replacing its own).
///
/// # Errors
/// A scene the simulator refuses (a bug in the generator, named by its seed), or settings
/// refused for a scene's array.
pub fn run_draw(opts: &DrawOptions, base: &Settings) -> Result<GeneratedReport> {
    anyhow::ensure!(opts.renderings >= 1, "renderings: at least 1");
    anyhow::ensure!(opts.map_seeds >= 1, "map seeds: at least 1");
    anyhow::ensure!(!opts.seeds.is_empty(), "the draw has no seed");
    let t0 = std::time::Instant::now();
    let config = opts.draw_config();
    let bar = crate::progress(opts.seeds.end - opts.seeds.start, "scenes");
    let mut maps = Vec::new();
    for seed in opts.seeds.clone() {
        let drawn = draw(seed, &config)?;
        maps.extend(run_drawn(&drawn, opts, base).with_context(|| format!("drawn scene {seed}"))?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(GeneratedReport {
        schema_version: 1,
        seeds: [opts.seeds.start, opts.seeds.end],
        renderings: opts.renderings,
        map_seeds: opts.map_seeds,
        talkers: opts
            .talkers
            .iter()
            .map(|t| {
                t.file_name()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect(),
        groups: groups(&maps),
        maps,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The maps of one drawn scene: every rendering, every method and the true bearings (only
/// those with [`DrawOptions::floor_only`]: nothing is rendered then).
fn run_drawn(drawn: &Drawn, opts: &DrawOptions, base: &Settings) -> Result<Vec<MapRecord>> {
    let mut out = Vec::new();
    let seed = drawn.scene.seed;
    for r in 0..opts.renderings {
        let mut scene = drawn.scene.clone();
        // Rendering r draws its signals, sensor noise and tail from its own seed.
        scene.seed = seed.wrapping_mul(16).wrapping_add(r as u64);
        let prepared = prepare(scene)?;
        let floor = true_bearings(&prepared)?;
        let truth = floor.truth.clone().unwrap_or_default();
        let room = prepared.room.clone();
        let places = prepared.places();
        let stops = prepared.stops.len();
        let stop_xy: Vec<[f64; 2]> = prepared.stops.iter().map(|p| [p.x, p.y]).collect();
        let changing = !crate::changes::changes(&places, stops).is_empty();
        let record = |method: &str, doa_score: f64, map: &asm::MapResult| {
            let found = map.positions();
            let judged = changing
                .then(|| crate::changes::judge(map, &places, &stop_xy, &|a, b| room.sees(a, b)));
            MapRecord {
                scene: drawn.scene.name.clone(),
                seed,
                family: drawn.family,
                array: drawn.scene.array.preset.clone().unwrap_or_default(),
                method: method.to_owned(),
                rendering: r,
                sources: truth.len(),
                n: drawn.num,
                doa_score,
                found: found.len(),
                ospa: asm::ospa::ospa(&found, &truth, 1.0, 1.0).total,
                outside: found.iter().filter(|p| outside(&room, **p)).count(),
                ospa_now: judged.map(|j| j.ospa_now),
                // A scene whose changes no stop saw happen has nothing to date.
                change_dated: judged.filter(|j| j.changes > 0).map(|j| j.all_found()),
            }
        };
        let map_seed = |j: usize| prepared.scene.seed + 1000 * j as u64;
        let settings = scene_settings(base, Method::PAPER[0], drawn.num);
        for j in 0..opts.map_seeds {
            let map = floor.map(&settings.iasm, map_seed(j))?;
            out.push(record(TRUE_BEARINGS, 1.0, &map));
        }
        if opts.floor_only {
            continue;
        }
        let map_seed0 = map_seed(0);
        let sim = Simulated::render(prepared, drawn.scene.name.clone())?;
        for &method in Method::PAPER.iter() {
            let settings = scene_settings(base, method, drawn.num);
            let run = sim.run(&settings, map_seed0)?;
            out.push(record(method.name(), run.score.score, &run.map));
            for j in 1..opts.map_seeds {
                let map = run
                    .survey
                    .map(&settings.iasm, map_seed0 + 1000 * j as u64)?;
                out.push(record(method.name(), run.score.score, &map));
            }
            let heard = heard_bearings(&run.survey, &truth, HEARD_TOL_DEG);
            let label = format!("{}{HEARD}", method.name());
            for j in 0..opts.map_seeds {
                let map = heard.map(&settings.iasm, map_seed0 + 1000 * j as u64)?;
                out.push(record(&label, run.score.score, &map));
            }
        }
    }
    Ok(out)
}

/// The survey a perfect front end would give: at every stop, the exact bearing of every
/// source in its line of sight (array frame, degrees), nearest first, and no row cut. A
/// source around a corner reaches the stop only by reflection, and its direct bearing is
/// not something any front end could hear there. Nothing is rendered: the scene's
/// geometry is all it takes.
///
/// # Errors
/// A scene whose array is refused.
pub fn true_bearings(scene: &PreparedScene) -> Result<Survey> {
    let poses = scene.stops.clone();
    // Every place a source stands at during the run, each heard at the stops it plays at.
    let places = scene.places();
    let truth: Vec<[f64; 2]> = places.iter().map(|p| [p.pos[0], p.pos[1]]).collect();
    let doas_deg = poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut by_distance: Vec<(f64, f64)> = truth
                .iter()
                .zip(&places)
                .filter(|(_, place)| place.plays_at(k))
                .map(|(t, _)| t)
                .filter(|t| scene.room.sees([p.x, p.y], **t))
                .map(|t| {
                    let az = p.azimuth_to(*t).to_degrees();
                    ((t[0] - p.x).hypot(t[1] - p.y), az)
                })
                .collect();
            by_distance.sort_by(|a, b| a.0.total_cmp(&b.0));
            by_distance.into_iter().map(|(_, az)| Some(az)).collect()
        })
        .collect();
    let array = ssl::MicArray::new(scene.scene.name.clone(), scene.mics.clone())?;
    Ok(Survey {
        map: crate::scenes::scene_map(scene),
        open_margin_m: None,
        cut: Some(vec![false; poses.len()]),
        poses,
        doas_deg,
        truth: Some(truth),
        doa_source: TRUE_BEARINGS.to_owned(),
        mirror_axis_deg: array.mirror_axis_deg(),
    })
}

/// The survey of what a front end heard, placed exactly: at each stop, for each of its
/// DoAs within `tol_deg` of the bearing to a source of `truth`, that source's exact
/// bearing (array frame, degrees; the nearest source, once per stop, in the DoAs' order),
/// and nothing for the DoAs that heard no source. Mapped, it splits a method's loss from
/// its true-bearing floor in two: the sources its DoAs never heard (the floor against
/// this), and what its DoAs' errors and clutter cost the mapper (this against the
/// method's own maps). Every other field is `survey`'s, the rows' cut flags included: a
/// row the SSL cut at `N` stays one the mapper counts as cut.
pub fn heard_bearings(survey: &Survey, truth: &[[f64; 2]], tol_deg: f64) -> Survey {
    let tol = tol_deg.to_radians();
    let doas_deg = survey
        .poses
        .iter()
        .zip(&survey.doas_deg)
        .map(|(p, row)| {
            let bearings: Vec<f64> = truth.iter().map(|t| p.azimuth_to(*t)).collect();
            let mut heard: Vec<usize> = Vec::new();
            for az in row.iter().flatten() {
                let miss = |i: &usize| geom::wrap_rad(bearings[*i] - az.to_radians()).abs();
                let nearest = (0..truth.len()).min_by(|a, b| miss(a).total_cmp(&miss(b)));
                if let Some(i) = nearest.filter(|i| miss(i) <= tol && !heard.contains(i)) {
                    heard.push(i);
                }
            }
            heard
                .into_iter()
                .map(|i| Some(bearings[i].to_degrees()))
                .collect()
        })
        .collect();
    Survey {
        doas_deg,
        doa_source: format!("{}{HEARD}", survey.doa_source),
        ..survey.clone()
    }
}

/// Whether the plan point `p` lies outside the room by more than [`OUTSIDE_TOLERANCE_M`].
pub fn outside(room: &sim::Space, p: [f64; 2]) -> bool {
    match room {
        sim::Space::Shoebox(r) => {
            let [lx, ly, _] = r.dims();
            let t = OUTSIDE_TOLERANCE_M;
            !(-t..=lx + t).contains(&p[0]) || !(-t..=ly + t).contains(&p[1])
        }
        sim::Space::Plan(plan) => {
            !plan.contains_plan(p) && plan.distance_to_walls(p) > OUTSIDE_TOLERANCE_M
        }
    }
}

/// Each method's distribution over all maps, then per family and per array, each with
/// the true-bearing floor of the same scenes.
fn groups(maps: &[MapRecord]) -> Vec<GroupRow> {
    // The methods mapped (in the paper's order), or the true bearings alone when only
    // they were.
    let mut methods: Vec<String> = Method::PAPER
        .iter()
        .map(|m| m.name().to_owned())
        .filter(|m| maps.iter().any(|r| &r.method == m))
        .collect();
    if methods.is_empty() {
        methods.push(TRUE_BEARINGS.to_owned());
    }
    type Member = Box<dyn Fn(&MapRecord) -> bool>;
    let mut keys: Vec<(String, Member)> = vec![("all".to_owned(), Box::new(|_| true))];
    for f in Family::ALL {
        keys.push((f.name().to_owned(), Box::new(move |m| m.family == f)));
    }
    for a in ssl::array::PRESETS {
        keys.push((a.to_owned(), Box::new(move |m| m.array == a)));
    }
    for (lo, hi) in [(2, 3), (4, 5), (6, 8)] {
        keys.push((
            format!("{lo}-{hi} sources"),
            Box::new(move |m| (lo..=hi).contains(&m.sources)),
        ));
    }
    let mut out = Vec::new();
    for (group, member) in &keys {
        if !maps.iter().any(member) {
            continue;
        }
        let floor = Distribution::of(
            maps.iter()
                .filter(|m| m.method == TRUE_BEARINGS && member(m)),
        );
        for method in &methods {
            let heard = format!("{method}{HEARD}");
            out.push(GroupRow {
                group: group.clone(),
                method: method.clone(),
                maps: Distribution::of(maps.iter().filter(|m| &m.method == method && member(m))),
                floor: floor.clone(),
                heard: Distribution::of(maps.iter().filter(|m| m.method == heard && member(m))),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(seed: u64, rendering: usize, ospa: f64, found: usize) -> MapRecord {
        MapRecord {
            scene: format!("s{seed}"),
            seed,
            family: Family::L,
            array: "iasm6".into(),
            method: "mvdr".into(),
            rendering,
            sources: 3,
            n: 4,
            doa_score: 0.5,
            found,
            ospa,
            outside: 0,
            ospa_now: None,
            change_dated: None,
        }
    }

    /// The distribution's figures, computed by hand: ten maps 0.01 ... 0.10 m, the 90th
    /// percentile the ninth (nearest rank), the median between the fifth and sixth.
    #[test]
    fn a_distribution_is_its_maps_figures() {
        let maps: Vec<MapRecord> = (1..=10)
            .map(|i| {
                rec(
                    i / 6,
                    (i % 2) as usize,
                    i as f64 / 100.0,
                    if i <= 7 { 3 } else { 2 },
                )
            })
            .collect();
        let d = Distribution::of(&maps);
        assert_eq!(d.maps, 10);
        assert!((d.mean - 0.055).abs() < 1e-12, "{d:?}");
        assert!((d.median - 0.055).abs() < 1e-12, "{d:?}");
        assert!((d.p90 - 0.09).abs() < 1e-12, "{d:?}");
        assert!((d.right_count - 0.7).abs() < 1e-12, "{d:?}");
        // Seed 0 (maps 1-5): rendering 1 holds 0.01, 0.03, 0.05 (mean 0.03), rendering 0
        // 0.02, 0.04 (0.03): no spread. Seed 1 (6-10): rendering 0 holds 0.06, 0.08, 0.10
        // (0.08), rendering 1 0.07, 0.09 (0.08). Both spreads 0.
        assert!(d.spread.abs() < 1e-12, "{d:?}");
        let two = [rec(0, 0, 0.1, 3), rec(0, 1, 0.3, 3)];
        assert!((Distribution::of(&two).spread - 0.2).abs() < 1e-12);
    }

    /// The true bearings of a 6 x 6 m box with sources at (3, 5) and (1, 2), heard from
    /// `poses` (a TOML list of `[x, y, heading_deg]`).
    fn two_sources_seen_from(poses: &str) -> Survey {
        let (scene, _) = crate::scenes::parse_scene(&format!(
            "fs = 8000\nclip_s = 0.2\n[room]\ndims = [6.0, 6.0, 3.0]\nrt60 = 0.3\n\
             [array]\npreset = \"iasm6\"\nheight = 0.8\n\
             [[sources]]\npos = [3.0, 5.0, 1.0]\n[[sources]]\npos = [1.0, 2.0, 1.0]\n\
             [trajectory]\nposes = {poses}\n"
        ))
        .unwrap();
        true_bearings(&prepare(scene).unwrap()).unwrap()
    }

    /// True bearings are the geometry's: a source straight ahead of a robot facing +y is
    /// at 0 degrees in the array frame, one to its left at +90.
    #[test]
    fn true_bearings_are_the_geometry() {
        let s = two_sources_seen_from("[[3.0, 2.0, 90.0]]");
        let row: Vec<f64> = s.doas_deg[0].iter().map(|c| c.unwrap()).collect();
        // Nearest first: the source 2 m to the left (+90), then 3 m ahead (0).
        assert!(
            (row[0] - 90.0).abs() < 1e-9 && row[1].abs() < 1e-9,
            "{row:?}"
        );
    }

    #[test]
    fn heard_bearings_are_the_sources_the_doas_found_placed_exactly() {
        let mut survey = two_sources_seen_from("[[3.0, 2.0, 90.0], [3.0, 3.0, 90.0]]");
        let truth = survey.truth.clone().unwrap();
        // At the first stop (heading +y) the sources lie at 0 (ahead, 3 m) and +90 degrees
        // (left, 2 m); at the second at 0 and atan2(1, 2) + 90 = 116.57 degrees.
        survey.doas_deg = vec![
            // 3 degrees off the one ahead, 20 off anything, 4 off the one ahead again.
            vec![Some(3.0), Some(-70.0), Some(-4.0)],
            // The left one 4.9 degrees off, the one ahead 5.1 off (missed), an empty cell.
            vec![Some(121.47), Some(5.1), None],
        ];
        let heard = heard_bearings(&survey, &truth, HEARD_TOL_DEG);
        let rows: Vec<Vec<f64>> = heard
            .doas_deg
            .iter()
            .map(|r| r.iter().map(|c| c.unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].len(), 1);
        assert!(rows[0][0].abs() < 1e-9, "{rows:?}");
        assert_eq!(rows[1].len(), 1);
        let left = 90.0 + 0.5f64.atan().to_degrees();
        assert!((rows[1][0] - left).abs() < 1e-9, "{rows:?}");
        assert_eq!(heard.poses, survey.poses);
    }

    #[test]
    fn outside_counts_beyond_the_tolerance_only() {
        let plan = sim::PlanRoom::new(
            &[
                [0.0, 0.0],
                [4.0, 0.0],
                [4.0, 4.0],
                [2.0, 4.0],
                [2.0, 2.0],
                [0.0, 2.0],
            ],
            3.0,
            &[0.2; 8],
        )
        .unwrap();
        let room = sim::Space::Plan(plan);
        assert!(!outside(&room, [1.0, 1.0]));
        assert!(
            !outside(&room, [1.0, 2.05]),
            "within the tolerance of a wall"
        );
        assert!(outside(&room, [1.0, 3.0]), "the L's missing corner");
    }
}
