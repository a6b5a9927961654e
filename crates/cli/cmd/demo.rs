//! `iasm demo`: the whole pipeline on a built-in scene. A robot carrying the paper's
//! array drives between two rows of five talkers (the paper's arrangement II, in a
//! simulated room); every stop is rendered, localised with MVDR and mapped with I-ASM; the
//! sources found are printed against the truth, with the OSPA, and the map is drawn.

use std::path::Path;

use anyhow::Result;
use ssl::Method;

use crate::Outcome;
use crate::args::FigureArgs;
use crate::figure::MapFigure;
use crate::pipeline::{SceneRun, Simulated, scene_settings};
use crate::scenes::{parse_scene, prepare};
use crate::settings::Settings;

/// The built-in scene (also a scene of the regression suite).
pub const SCENE: &str = include_str!("../../../fixtures/rooms/rows_ten.toml");

/// DoAs per stop: a user who does not know the room sets 4 for a room of many talkers.
const N: usize = 4;

/// Renders the built-in scene with `seed` and runs the pipeline with `method`.
///
/// # Errors
/// Only if the built-in scene were refused, which would be a bug.
pub fn run_scene(seed: u64, method: Method) -> Result<(Simulated, SceneRun)> {
    let (mut scene, _) = parse_scene(SCENE)?;
    scene.seed = seed;
    let simulated = Simulated::render(prepare(scene)?, "demo".into())?;
    let run = simulated.run(&scene_settings(&Settings::default(), method, N), seed)?;
    Ok((simulated, run))
}

/// Runs `iasm demo`: prints the map against the truth, writes the picture to `png` and,
/// when asked, the map as ROS 2 messages to `mcap`.
///
/// # Errors
/// If the picture cannot be written.
pub fn run(seed: u64, png: &Path, mcap: Option<&Path>, figure: &FigureArgs) -> Result<Outcome> {
    crate::figure::Format::of(png)?;
    let t0 = std::time::Instant::now();
    let (sim, run) = run_scene(seed, Method::Mvdr)?;
    let [lx, ly, lz] = sim.scene.room.dims();
    println!(
        "iasm demo: a robot with the paper's 6-microphone array drives between two rows of five talkers\n\
         ({lx} x {ly} x {lz} m room, RT60 {} s, {} stops, seed {seed}); rendered, localised (mvdr) and mapped in {:.1} s",
        sim.scene.scene.room.rt60.unwrap_or_default(),
        sim.poses().len(),
        t0.elapsed().as_secs_f64()
    );
    print_map(&sim, &run);
    crate::figure::map(
        png,
        &MapFigure {
            title: format!(
                "iasm demo (seed {seed}): mvdr, {}, {} of {} sources found, OSPA {:.3} m",
                scene_settings(&Settings::default(), Method::Mvdr, N)
                    .iasm
                    .variant
                    .name(),
                run.map.sources.len(),
                sim.truth.len(),
                run.ospa.total
            ),
            map: &sim.map,
            poses: sim.poses(),
            result: &run.map,
            truth: Some(&sim.truth),
            full_map: figure.full_map,
            width: figure.figure_width,
            kinds: Vec::new(),
        },
    )?;
    println!("map drawn to {}", png.display());
    if let Some(path) = mcap {
        let messages = crate::rosmap::of_survey(&run.survey, &run.map);
        crate::rosmap::write_mcap(path, &messages, messages.path.header.stamp.ns())?;
        println!("map written as ROS 2 messages to {}", path.display());
    }
    Ok(Outcome::Success)
}

/// The demo's map beside the truth: the DoA score, a row per source with the nearest true
/// one, and the OSPA.
fn print_map(sim: &Simulated, run: &SceneRun) {
    println!(
        "DoA score {:.3} (first {} DoAs per stop within 5 deg of a true bearing)",
        run.score.score, N
    );
    println!(
        "{:>3} {:>8} {:>8}   {:>8} {:>8} {:>10}",
        "#", "x (m)", "y (m)", "true x", "true y", "error (m)"
    );
    for (i, s) in run.map.sources.iter().enumerate() {
        let t = sim
            .truth
            .iter()
            .min_by(|a, b| {
                (a[0] - s.x)
                    .hypot(a[1] - s.y)
                    .total_cmp(&(b[0] - s.x).hypot(b[1] - s.y))
            })
            .expect("a scene has sources");
        println!(
            "{:>3} {:>8.3} {:>8.3}   {:>8.2} {:>8.2} {:>10.3}",
            i + 1,
            s.x,
            s.y,
            t[0],
            t[1],
            (t[0] - s.x).hypot(t[1] - s.y)
        );
    }
    println!(
        "{} of {} sources found; OSPA {:.3} m (localisation {:.3}, cardinality {:.3})",
        run.map.sources.len(),
        sim.truth.len(),
        run.ospa.total,
        run.ospa.localization,
        run.ospa.cardinality
    );
}
