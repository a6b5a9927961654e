//! `iasm bag`: a robot run recorded in a ROS bag, made a data set.

use anyhow::{Context, Result, bail};

use crate::Outcome;
use crate::args::BagArgs;
use crate::bagset::{BagRun, picked_channels, read_bag, write_dataset};
use crate::output::replace_dir;

/// Runs `iasm bag`: the run read, what it holds and the stops it has said, and with
/// `--out` the data set written.
///
/// # Errors
/// A bag that cannot be read, options refused, no stop found with `--out`, or an output
/// folder that is refused or cannot be written.
pub fn run(a: &BagArgs) -> Result<Outcome> {
    let (read, stops) = (a.run.read_options()?, a.run.stop_options()?);
    let array = a
        .array
        .as_deref()
        .map(ssl::MicArray::from_spec)
        .transpose()
        .context("--array")?;
    let mut got = read_bag(&a.bag, &read, &stops)?;
    if let Some(w) = a.noise_window {
        got.set_noise_window(w)
            .with_context(|| format!("--noise-window {}-{} in {}", w.0, w.1, a.bag.display()))?;
    }
    let picked = picked_channels(
        &got.run,
        a.channels.as_ref().map(|c| c.0.as_slice()),
        array.as_ref(),
    )
    .with_context(|| format!("the bag {}", a.bag.display()))?;
    print_run(a, &got);
    print_stops(&got);
    let too_few = (got.stops.len() < 3).then(|| too_few(a, got.stops.len()));
    let Some(out) = &a.out else {
        if let Some(w) = &too_few {
            eprintln!("warning: {w}");
        }
        return Ok(Outcome::Success);
    };
    if got.stops.is_empty() {
        bail!(
            "nothing written to {}: {}",
            out.display(),
            too_few.unwrap_or_default()
        );
    }
    if let Some(w) = &too_few {
        eprintln!("warning: {w}");
    }
    replace_dir(out, a.force, |dir| {
        write_dataset(&got, &picked, array.as_ref(), dir)
    })?;
    println!(
        "written to {} (audio/, pose/poses.csv, stops.csv{}{}); next: iasm map --dataset {} --png map.png",
        out.display(),
        match (got.run.map.is_some(), array.is_some()) {
            (true, true) => ", map/, array.toml",
            (true, false) => ", map/",
            (false, true) => ", array.toml",
            (false, false) => "",
        },
        if got.noise.is_some() {
            ", noise/robot.wav"
        } else {
            ""
        },
        out.display()
    );
    Ok(Outcome::Success)
}

/// What the bag holds: its length and topics, the audio, the poses, the map, its notes,
/// and the recording of the robot alone.
fn print_run(a: &BagArgs, got: &BagRun) {
    let run = &got.run;
    let duration = run.topics.iter().map(|t| t.span_s.1).fold(0.0, f64::max);
    println!(
        "{}: {:.1} s, {} topics{}",
        a.bag.display(),
        duration,
        run.topics.len(),
        match run.truncated {
            Some(at) => format!(" (cut off: read up to byte {at}, its last whole record)"),
            None => String::new(),
        }
    );
    if a.out.is_none() {
        for t in &run.topics {
            println!(
                "  {:<32} {:<44} {:>7} messages",
                t.topic, t.msg_type, t.messages
            );
        }
    }
    let heard: f64 = run
        .segments
        .iter()
        .map(|s| s.frames as f64 / f64::from(run.format.sample_rate))
        .sum();
    println!(
        "audio: {} ({} channels, {} Hz, {:?}; {:.1} s in {} continuous segment{})",
        run.audio_topic,
        run.format.channels,
        run.format.sample_rate,
        run.format.sample,
        heard,
        run.segments.len(),
        if run.segments.len() == 1 { "" } else { "s" }
    );
    println!(
        "poses: {} ({} messages){}",
        run.pose_topic,
        run.poses.len(),
        match &run.odom_topic {
            Some(o) => format!("; stops found by {o} ({} messages)", run.odometry.len()),
            None => String::new(),
        }
    );
    if let Some(g) = &run.map {
        println!(
            "map: {} ({} x {} cells of {} m from ({}, {}), frame {})",
            run.map_topic.as_deref().unwrap_or("?"),
            g.width,
            g.height,
            g.resolution,
            g.origin.x,
            g.origin.y,
            g.frame_id
        );
    }
    for n in &run.notes {
        println!("note: {n}");
    }
    if let Some((seg, frames)) = &got.noise {
        let start = run.segments[*seg].start_s;
        let fs = f64::from(run.format.sample_rate);
        println!(
            "the robot alone: {:.2} - {:.2} s ({:.1} s; noise/robot.wav, subtracted by every command){}",
            start + frames.start as f64 / fs,
            start + frames.end as f64 / fs,
            frames.len() as f64 / fs,
            match got.dropped {
                0 => String::new(),
                1 => "; the stop within it left out".to_string(),
                k => format!("; the {k} stops within it left out"),
            }
        );
    }
}

/// The stops: when the robot listened, and where it stood.
fn print_stops(got: &BagRun) {
    println!("stop  listen (s in the bag)  pose (x m, y m, theta deg)");
    for (i, s) in got.stops.iter().enumerate() {
        println!(
            "{:>4}  {:>7.2} - {:<7.2}         ({:.3}, {:.3}, {:.1})",
            i + 1,
            s.listen_s.0,
            s.listen_s.1,
            s.pose.x,
            s.pose.y,
            s.pose.theta_deg()
        );
    }
    let listened: f64 = got.stops.iter().map(|s| s.listen_s.1 - s.listen_s.0).sum();
    println!("{} stops, {listened:.1} s of audio", got.stops.len());
}

/// Why `n` stops (fewer than the three a source needs) were all the bag gave: the rules
/// that make a stop, with the options that set them.
fn too_few(a: &BagArgs, n: usize) -> String {
    format!(
        "{} found (a stop: the robot within {} m and {} deg, --still-radius and --still-turn, \
         for {} s of audio, --min-listen, after {} s of settling, --settle, and before a {}-s \
         margin, --end-margin); a source needs three stops",
        match n {
            0 => "no stops".to_string(),
            1 => "only 1 stop".to_string(),
            n => format!("only {n} stops"),
        },
        a.run.still_radius,
        a.run.still_turn,
        a.run.min_listen,
        a.run.settle,
        a.run.end_margin,
    )
}
