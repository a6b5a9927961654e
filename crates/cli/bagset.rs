//! A robot run recorded in a ROS bag (ROS 1, or ROS 2 in MCAP), written as a data set in the
//! published layout.
//!
//! The `bag` crate finds the stops at which the robot stood still, each with its pose and
//! its audio. Written as a data set (a WAV per stop, a pose table), every command runs on
//! the run as on the authors' recordings: `iasm ssl`, `map`, `eval`, `compare`, `watch
//! --replay`. The WAVs hold 32-bit float samples, which keep every source format (16, 24
//! or 32-bit integers, floats) exactly enough; `stops.csv` says where in the bag each
//! stop's audio was taken, so that a map can be traced back to the recording.

use std::path::Path;

use anyhow::{Context, Result, bail, ensure};
use rayon::prelude::*;
use ssl::MicArray;

/// A run read out of a bag, and its stops.
#[derive(Clone, Debug)]
pub struct BagRun {
    /// The run.
    pub run: bag::Run,
    /// Its stops, in time order.
    pub stops: Vec<bag::Stop>,
    /// The robot alone ([`BagRun::set_noise_window`]): a segment of the run's audio and
    /// its frames.
    pub noise: Option<(usize, std::ops::Range<usize>)>,
    /// Stops left out because they lay within the robot alone's window.
    pub dropped: usize,
}

/// The shortest recording of the robot alone taken (s): its covariance is a mean over its
/// frames.
pub const MIN_NOISE_S: f64 = 1.0;

impl BagRun {
    /// Takes the audio from `from` to `to` (s in the bag, as the stops count them) as the
    /// recording of the robot alone, and leaves out the stops whose listening window
    /// overlaps it (they hear the robot alone, no source).
    ///
    /// # Errors
    /// A window shorter than [`MIN_NOISE_S`], or that no one continuous stretch of the
    /// audio holds.
    pub fn set_noise_window(&mut self, (from, to): (f64, f64)) -> Result<()> {
        ensure!(
            to - from >= MIN_NOISE_S,
            "the robot alone must be heard for at least {MIN_NOISE_S} s (a few seconds are best)"
        );
        let Some(w) = self.run.window((from, to)) else {
            let spans: Vec<String> = self
                .run
                .segments
                .iter()
                .map(|s| {
                    let end = s.start_s + s.frames as f64 / f64::from(self.run.format.sample_rate);
                    format!("{:.2}-{:.2}", s.start_s, end)
                })
                .collect();
            bail!(
                "no continuous audio holds it: the audio of {} runs {} s",
                self.run.audio_topic,
                spans.join(", ")
            );
        };
        let before = self.stops.len();
        self.stops
            .retain(|s| s.listen_s.1 <= from || s.listen_s.0 >= to);
        self.dropped = before - self.stops.len();
        self.noise = Some(w);
        Ok(())
    }
}

/// Reads the run in the bag at `path` and finds its stops.
///
/// # Errors
/// What [`bag::read_file`] or [`bag::Run::stops`] refuses, named by the file.
pub fn read_bag(path: &Path, read: &bag::ReadOptions, stops: &bag::StopOptions) -> Result<BagRun> {
    let ctx = || format!("reading the bag {}", path.display());
    let run = bag::read_file(path, read).with_context(ctx)?;
    let stops = run.stops(stops).with_context(ctx)?;
    Ok(BagRun {
        run,
        stops,
        noise: None,
        dropped: 0,
    })
}

/// Checks `channels` (counted from 1) against the run's audio and `array`, and returns them
/// counted from 0 (every channel when `None`).
///
/// # Errors
/// A channel the audio does not have, or a count of channels that is not the array's.
pub fn picked_channels(
    run: &bag::Run,
    channels: Option<&[usize]>,
    array: Option<&MicArray>,
) -> Result<Vec<usize>> {
    let have = usize::from(run.format.channels);
    let picked: Vec<usize> = match channels {
        Some(c) => {
            if let Some(&bad) = c.iter().find(|&&c| c == 0 || c > have) {
                bail!(
                    "--channels names channel {bad}, but the audio of {} has channels 1 to {have}",
                    run.audio_topic
                );
            }
            c.iter().map(|c| c - 1).collect()
        }
        None => (0..have).collect(),
    };
    if let Some(a) = array {
        ensure!(
            picked.len() == a.len(),
            "the array {} has {} microphones but the audio of {} gives {} channels{}",
            a.name(),
            a.len(),
            run.audio_topic,
            picked.len(),
            if channels.is_none() && have > a.len() {
                ": name the microphones' channels with --channels (counted from 1)"
            } else {
                ""
            }
        );
    }
    Ok(picked)
}

/// Writes the stops of `run` into the folder `out` (which must exist): `audio/stopNN.wav`
/// (the channels `picked`, counted from 0), `pose/poses.csv` (x, y, theta in degrees),
/// `noise/robot.wav` (the robot alone, when [`BagRun::set_noise_window`] set it),
/// `stops.csv`, `map/map.pgm` and `map/map.yaml` when the bag holds the robot's map in the
/// poses' frame ([`bag::Run::map`]), and `array.toml` when `array` is given.
///
/// # Errors
/// A file that cannot be written.
pub fn write_dataset(
    run: &BagRun,
    picked: &[usize],
    array: Option<&MicArray>,
    out: &Path,
) -> Result<()> {
    for d in ["audio", "pose"] {
        std::fs::create_dir_all(out.join(d))
            .with_context(|| format!("creating {}", out.join(d).display()))?;
    }
    let width = run.stops.len().to_string().len().max(2);
    let fs = run.run.format.sample_rate;
    let mut poses = String::from("x,y,theta_deg\n");
    let mut table = String::from(
        "stop,file,listen_start_s,listen_end_s,still_start_s,still_end_s,x,y,theta_deg\n",
    );
    // One stop decoded at a time per worker: the run's audio stays as recorded.
    run.stops.par_iter().enumerate().try_for_each(|(i, s)| {
        let audio = run.run.stop_audio(s);
        let channels: Vec<&[f32]> = picked.iter().map(|&c| audio[c].as_slice()).collect();
        crate::output::write_float_wav(&out.join("audio").join(stop_file(i, width)), &channels, fs)
    })?;
    for (i, s) in run.stops.iter().enumerate() {
        let name = stop_file(i, width);
        poses.push_str(&format!(
            "{:.4},{:.4},{:.4}\n",
            s.pose.x,
            s.pose.y,
            s.pose.theta_deg()
        ));
        table.push_str(&format!(
            "{},{name},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}\n",
            i + 1,
            s.listen_s.0,
            s.listen_s.1,
            s.still_s.0,
            s.still_s.1,
            s.pose.x,
            s.pose.y,
            s.pose.theta_deg()
        ));
    }
    crate::output::write_atomic(&out.join("pose/poses.csv"), poses.as_bytes())?;
    if let Some((seg, frames)) = &run.noise {
        let audio = run.run.samples(*seg, frames.clone());
        let channels: Vec<&[f32]> = picked.iter().map(|&c| audio[c].as_slice()).collect();
        let dir = out.join(crate::settings::DATASET_NOISE_DIR);
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        crate::output::write_float_wav(&dir.join("robot.wav"), &channels, fs)?;
    }
    crate::output::write_atomic(&out.join("stops.csv"), table.as_bytes())?;
    if let Some(grid) = &run.run.map {
        std::fs::create_dir_all(out.join("map"))
            .with_context(|| format!("creating {}", out.join("map").display()))?;
        crate::output::write_atomic(&out.join("map/map.pgm"), &grid_pgm(grid))?;
        let yaml = format!(
            "image: map.pgm\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
            // The message's f32, written as its shortest decimal (0.05, not 0.0500000007).
            grid.resolution,
            grid.origin.x,
            grid.origin.y
        );
        crate::output::write_atomic(&out.join("map/map.yaml"), yaml.as_bytes())?;
    }
    if let Some(a) = array {
        let text = crate::dataset::array_file_toml(a.name(), a.positions())?;
        crate::output::write_atomic(&out.join("array.toml"), text.as_bytes())?;
    }
    Ok(())
}

/// An occupancy grid as ROS's `map_saver` writes it: a binary PGM, its first row the grid's
/// last (the image's top is the map's far side), free cells (0 to 25 %) 254, occupied ones
/// (65 % and more) 0, the rest and the unknown 205; with the thresholds of the YAML beside
/// it, read back as free, occupied and unknown.
fn grid_pgm(grid: &bag::msg::Grid) -> Vec<u8> {
    let mut out = format!("P5\n{} {}\n255\n", grid.width, grid.height).into_bytes();
    for row in grid.data.chunks_exact(grid.width).rev() {
        out.extend(row.iter().map(|&v| match v {
            0..=25 => 254u8,
            65.. => 0,
            _ => 205,
        }));
    }
    out
}

fn stop_file(i: usize, width: usize) -> String {
    format!("stop{:0width$}.wav", i + 1)
}

/// The robot's occupancy grid as the mapper's map: the cells `iasm bag --out` writes as a
/// PGM and `iasm map` reads back from it (free to 25 %, occupied from 65 %, the rest and
/// the unknown unknown), so that a live map and one made from the written data set search
/// the same cells.
///
/// # Errors
/// A grid whose cells do not fill it, or of no positive resolution.
pub fn grid_map(grid: &bag::msg::Grid) -> Result<asm::map::OccupancyMap> {
    use asm::map::Cell;
    ensure!(
        grid.width > 0 && grid.data.len() == grid.width * grid.height,
        "an occupancy grid of {} x {} cells holds {}",
        grid.width,
        grid.height,
        grid.data.len()
    );
    // As the YAML gives it: the f32's shortest decimal, read as f64.
    let resolution: f64 = grid.resolution.to_string().parse().unwrap_or(f64::NAN);
    asm::map::check_grid(
        grid.width,
        grid.height,
        resolution,
        [grid.origin.x, grid.origin.y],
    )?;
    let cells = grid
        .data
        .chunks_exact(grid.width)
        .rev()
        .flat_map(|row| {
            row.iter().map(|&v| match v {
                0..=25 => Cell::Free,
                65.. => Cell::Occupied,
                _ => Cell::Unknown,
            })
        })
        .collect();
    Ok(asm::map::OccupancyMap::new(
        grid.width,
        grid.height,
        resolution,
        [grid.origin.x, grid.origin.y],
        cells,
    ))
}
