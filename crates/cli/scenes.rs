//! Scene files: reading them (the simulator's scene plus the regression suite's
//! `[expect]` table), and writing a rendered scene as a data set in the published layout,
//! so that `iasm ssl`, `iasm map` and `iasm eval` read it as they read real recordings.

use std::path::Path;

use anyhow::{Context, Result};
use rayon::prelude::*;
use serde::Deserialize;
use sim::scene::{PreparedScene, Scene};

/// Map resolution of simulated data sets (m per cell), as GMapping's in the paper.
const MAP_RES: f64 = 0.05;
/// Unknown margin around the room in the map (m).
const MAP_MARGIN: f64 = 0.5;

/// What the regression suite expects of the pipeline on a scene: the scene file's optional
/// `[expect]` table. The simulator never sees it: a scene is a room, sources and a path,
/// and the thresholds are the suite's business.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Expect {
    /// DoAs per stop, N. Default: as a user would set it ([`crate::suite::user_n`]: 3 for
    /// up to three sources, 4 beyond).
    pub num: Option<usize>,
    /// Seeds the scene runs with (`seed`, `seed + 1`, ...). Default:
    /// [`crate::suite::DEFAULT_SEEDS`].
    pub seeds: Option<usize>,
    /// Maps per seed's rendering, each with its own particle draw. Default:
    /// [`crate::suite::DEFAULT_MAP_SEEDS`].
    pub map_seeds: Option<usize>,
    /// Lowest acceptable mean DoA score (hit within 5 degrees), for every method.
    pub doa_score_min: Option<f64>,
    /// Highest acceptable mean OSPA (m, p = 1, c = 1) of the I-ASM maps, for every method.
    pub ospa_max: Option<f64>,
    /// Highest acceptable OSPA of the worst seed (m).
    pub ospa_worst_max: Option<f64>,
    /// Fewest sources any seed's map may find.
    pub found_min: Option<usize>,
    /// Most sources any seed's map may find.
    pub found_max: Option<usize>,
    /// For a scene whose sources start, stop or move: the highest acceptable mean OSPA (m)
    /// of the maps' active sources against the places sounding at the last stop
    /// ([`crate::changes`]).
    pub ospa_now_max: Option<f64>,
    /// For such a scene: the lowest acceptable share of maps that date every change within
    /// [`crate::changes::CHANGE_TOLERANCE_STOPS`].
    pub changes_found_min: Option<f64>,
    /// Settings the suite runs this scene with, over its own (a settings file's tables:
    /// `[expect.settings.ssl]`, `[expect.settings.iasm]`), for scenes that exercise a
    /// setting off by default.
    pub settings: Option<toml::Table>,
}

/// Parses a scene file's text into the scene and its `[expect]` table.
///
/// # Errors
/// Malformed TOML, or a scene or `[expect]` table the simulator or the suite refuses.
pub fn parse_scene(text: &str) -> Result<(Scene, Expect)> {
    let mut table: toml::Table =
        toml::from_str(text).map_err(|e| anyhow::anyhow!("{}", e.message()))?;
    let expect = match table.remove("expect") {
        Some(v) => v
            .try_into()
            .map_err(|e: toml::de::Error| anyhow::anyhow!("expect: {}", e.message()))?,
        None => Expect::default(),
    };
    let scene: Scene = table
        .try_into()
        .map_err(|e: toml::de::Error| sim::SimError::Parse(e.message().to_owned()))?;
    Ok((scene, expect))
}

/// The positions of a built-in array, for scenes that name a preset.
pub fn preset_positions(name: &str) -> Option<Vec<[f64; 3]>> {
    ssl::MicArray::preset(name)
        .ok()
        .map(|a| a.positions().to_vec())
}

/// Checks a parsed scene, resolving array presets with the `ssl` crate.
///
/// # Errors
/// A scene the simulator refuses (the message names the field).
pub fn prepare(scene: Scene) -> Result<PreparedScene> {
    let scene = scene.prepare(preset_positions)?;
    // The data set's occupancy map covers the room: one that no map may be is refused
    // before anything is rendered.
    let [lx, ly, _] = scene.room.dims();
    let (w, h) = map_size(lx, ly);
    asm::map::check_grid(w, h, MAP_RES, [-MAP_MARGIN, -MAP_MARGIN])
        .with_context(|| format!("room.dims: a {lx} x {ly} m room's occupancy map"))?;
    Ok(scene)
}

/// The cells across and down of the occupancy map of a room `lx` x `ly` m.
fn map_size(lx: f64, ly: f64) -> (usize, usize) {
    (
        ((lx + 2.0 * MAP_MARGIN) / MAP_RES).ceil() as usize,
        ((ly + 2.0 * MAP_MARGIN) / MAP_RES).ceil() as usize,
    )
}

/// Reads and checks a scene file, resolving array presets with the `ssl` crate and
/// recordings relative to the file.
///
/// # Errors
/// If the file cannot be read, or the scene is refused (the message names the field).
pub fn load_scene(path: &Path) -> Result<(PreparedScene, Expect)> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading scene {}", path.display()))?;
    let ctx = || format!("scene {}", path.display());
    let (mut scene, expect) = parse_scene(&text).with_context(ctx)?;
    scene.resolve_paths(path.parent().unwrap_or(Path::new(".")));
    Ok((prepare(scene).with_context(ctx)?, expect))
}

/// Renders every stop of `scene` into `out` (created if needed): `audio/subNN.wav` (32-bit
/// float, pascals), `pose/poses.csv`, `map/map.yaml` + `map/map.pgm`, `src_gt.csv`, and
/// `array.toml`, the microphones that heard it (read by the commands given the data set
/// and no array; see [`crate::settings::DATASET_ARRAY_FILES`]).
///
/// # Errors
/// If a file cannot be written.
pub fn write_dataset(scene: &PreparedScene, out: &Path) -> Result<()> {
    for d in ["audio", "pose", "map"] {
        std::fs::create_dir_all(out.join(d))
            .with_context(|| format!("creating {}", out.join(d).display()))?;
    }
    let k = scene.stops.len();
    let width = k.to_string().len().max(2);
    let bar = crate::progress(k as u64, "rendering");
    (0..k).into_par_iter().try_for_each(|i| -> Result<()> {
        let audio = scene.render_stop(i);
        let path = out.join("audio").join(format!("sub{:0width$}.wav", i + 1));
        crate::output::write_float_wav(&path, &audio, scene.scene.fs)?;
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    if let Some(alone) = scene.render_robot_alone(0) {
        std::fs::create_dir_all(out.join("noise"))
            .with_context(|| format!("creating {}", out.join("noise").display()))?;
        crate::output::write_float_wav(&out.join("noise/robot.wav"), &alone, scene.scene.fs)?;
    }
    let mut poses = String::from("x,y,theta_deg\n");
    for s in &scene.stops {
        poses.push_str(&format!("{:.4},{:.4},{:.4}\n", s.x, s.y, s.theta_deg()));
    }
    write(&out.join("pose/poses.csv"), poses.as_bytes())?;
    let mut gt = String::from("x,y,z\n");
    for s in scene.room_sources() {
        gt.push_str(&format!("{},{},{}\n", s.pos[0], s.pos[1], s.pos[2]));
    }
    write(&out.join("src_gt.csv"), gt.as_bytes())?;
    let name = scene.scene.array.preset.as_deref().unwrap_or("scene-array");
    let array = crate::dataset::array_file_toml(name, &scene.mics)?;
    write(&out.join("array.toml"), array.as_bytes())?;
    let pgm = map_image(scene);
    write(&out.join("map/map.pgm"), &pgm)?;
    let yaml = format!(
        "image: map.pgm\nresolution: {MAP_RES}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
        -MAP_MARGIN, -MAP_MARGIN
    );
    write(&out.join("map/map.yaml"), yaml.as_bytes())
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    crate::output::write_atomic(path, bytes)
}

/// The occupancy map of a scene: walls a cell thick and obstacles occupied, the room free,
/// a margin unknown; origin at (-margin, -margin). A floor plan's map is its polygon: the
/// cells inside it free, those within a cell of a wall occupied, the rest (beyond the
/// walls, the corner outside an L) unknown, as a robot's range sensor leaves them.
pub fn scene_map(scene: &PreparedScene) -> asm::map::OccupancyMap {
    use asm::map::{Cell, OccupancyMap};
    let [lx, ly, _] = scene.room.dims();
    let (w, h) = map_size(lx, ly);
    let mut cells = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let x = -MAP_MARGIN + (i as f64 + 0.5) * MAP_RES;
            let y = -MAP_MARGIN + ((h - 1 - j) as f64 + 0.5) * MAP_RES;
            let (inside, wall) = match &scene.room {
                sim::Space::Shoebox(_) => {
                    let inside = (0.0..=lx).contains(&x) && (0.0..=ly).contains(&y);
                    let wall = inside
                        && (x < MAP_RES || y < MAP_RES || lx - x < MAP_RES || ly - y < MAP_RES);
                    (inside, wall)
                }
                sim::Space::Plan(plan) => {
                    let d = plan.distance_to_walls([x, y]);
                    let inside = plan.contains_plan([x, y]);
                    (inside || d < MAP_RES, d < MAP_RES)
                }
            };
            let obstacle =
                scene.scene.obstacles.iter().any(|o| {
                    (o.min[0]..=o.max[0]).contains(&x) && (o.min[1]..=o.max[1]).contains(&y)
                });
            cells.push(if !inside {
                Cell::Unknown
            } else if wall || obstacle {
                Cell::Occupied
            } else {
                Cell::Free
            });
        }
    }
    OccupancyMap::new(w, h, MAP_RES, [-MAP_MARGIN, -MAP_MARGIN], cells)
}

/// A map as a ROS PGM (0 occupied, 254 free, 205 unknown), row 0 at the top.
fn map_image(scene: &PreparedScene) -> Vec<u8> {
    use asm::map::Cell;
    let map = scene_map(scene);
    let mut img = format!("P5\n{} {}\n255\n", map.width(), map.height()).into_bytes();
    for j in 0..map.height() {
        for i in 0..map.width() {
            img.push(match map.cell(i, j) {
                Cell::Unknown => 205,
                Cell::Occupied => 0,
                Cell::Free => 254,
            });
        }
    }
    img
}
