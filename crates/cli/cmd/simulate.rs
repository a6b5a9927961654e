//! `iasm simulate`: renders a scene file into a data set in the published layout.

use std::path::Path;

use anyhow::Result;

use crate::Outcome;
use crate::output::replace_dir;
use crate::scenes::{load_scene, write_dataset};

/// Runs `iasm simulate`.
///
/// # Errors
/// A refused scene, or an output folder that is refused or cannot be written.
pub fn run(scene_path: &Path, out: &Path, force: bool) -> Result<Outcome> {
    let t0 = std::time::Instant::now();
    let (scene, _) = load_scene(scene_path)?;
    replace_dir(out, force, |dir| write_dataset(&scene, dir))?;
    println!(
        "{}: {} stops x {} microphones x {:.2} s at {} Hz, {} sources{}, written to {} ({:.1} s)",
        scene_path.display(),
        scene.stops.len(),
        scene.mics.len(),
        scene.scene.clip_s,
        scene.scene.fs,
        scene.room_sources().count(),
        match scene.scene.sources.len() - scene.room_sources().count() {
            0 => String::new(),
            k => format!(" and {k} on the robot (its noise alone in noise/robot.wav)"),
        },
        out.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(Outcome::Success)
}
