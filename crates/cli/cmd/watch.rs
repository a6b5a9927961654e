//! `iasm watch`: the map while the robot records (or a finished data set replayed stop by
//! stop), one line per stop, the map and its picture rewritten whole after each.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, ensure};
use asm::ospa::Ospa;
use asm::{IasmConfig, MapResult, Source};
use serde::Serialize;
use ssl::SslConfig;

use crate::Outcome;
use crate::args::{AngleUnit, WatchArgs};
use crate::dataset::{Dataset, file_name, first_with_ext, load_map, read_poses, read_sources};
use crate::figure::{Curve, Format, MapFigure};
use crate::online::{Follower, Next, Session, StopRecord, curve_csv};
use crate::settings::DEFAULT_ARRAY;

/// Version of the JSON `iasm watch` writes.
pub const SCHEMA_VERSION: u32 = 1;

/// The map after a stop, as written to `--out`.
#[derive(Serialize)]
struct WatchReport<'a> {
    schema_version: u32,
    /// The frame the sources' coordinates are in (ROS's name for it).
    frame_id: &'static str,
    dir: String,
    seed: u64,
    /// Stops mapped so far.
    stops: usize,
    /// Whether this is the run's final map (a full map over every stop).
    final_map: bool,
    params: &'a IasmConfig,
    ssl: &'a SslConfig,
    array: &'a str,
    sources: &'a [Source],
    ospa: Option<Ospa>,
    /// What the run passed over or could not follow (skipped stops, a broken pairing).
    notes: &'a [String],
}

/// What every stop's output needs.
struct Outputs<'a> {
    a: &'a WatchArgs,
    name: String,
    map: asm::map::OccupancyMap,
    settings: &'a crate::settings::Settings,
    /// The MCAP file of every update (`--mcap`), written whole when the run ends.
    mcap: std::cell::RefCell<Option<crate::rosmap::McapFile>>,
    /// Warnings of the run so far, each said on stderr and kept in the JSON's notes.
    notes: std::cell::RefCell<Vec<String>>,
}

impl Outputs<'_> {
    /// Says a warning and keeps it for the map's notes.
    fn note(&self, w: String) {
        eprintln!("warning: {w}");
        self.notes.borrow_mut().push(w);
    }

    /// Maps `audio` as the next stop and writes the map. A recording the session cannot
    /// use (channels, sample rate, samples) ends a replay, or a live run that has mapped
    /// nothing yet (the settings do not fit the recorder: said at once, not per stop);
    /// later in a live run it is a note, and the run goes on.
    fn add(
        &self,
        session: &mut Session,
        file: &Path,
        pose: asm::Pose,
        audio: &ssl::Audio,
        records: &mut Vec<StopRecord>,
        read_ms: f64,
    ) -> Result<()> {
        match session.add_recording(&file_name(file), pose, audio) {
            Ok(mut r) => {
                r.ssl_ms += read_ms;
                println!("{}", line(&r));
                self.write(session, &session.map(), false)?;
                records.push(r);
            }
            Err(e) if self.a.replay || records.is_empty() => return Err(e),
            Err(e) => self.note(format!("{}: skipped: {e:#}", file.display())),
        }
        Ok(())
    }

    /// Writes the map JSON and picture, each whole.
    fn write(&self, session: &Session, map: &MapResult, final_map: bool) -> Result<()> {
        let ospa = session.ospa(map);
        if let Some(file) = self.mcap.borrow_mut().as_mut() {
            // Each stop's update at its own second; the final map one second after the last.
            let k = session.poses().len();
            let t = crate::rosmap::stop_stamp_ns(if final_map { k } else { k.saturating_sub(1) });
            file.add(&crate::rosmap::of_session(session, map, &self.map, t), t)?;
        }
        if let Some(out) = &self.a.out {
            let report = WatchReport {
                schema_version: SCHEMA_VERSION,
                frame_id: crate::rosmap::FRAME,
                dir: self.a.dir.display().to_string(),
                seed: self.a.seed,
                stops: session.poses().len(),
                final_map,
                params: &self.settings.iasm,
                ssl: &self.settings.ssl,
                array: self.settings.array.as_deref().unwrap_or(DEFAULT_ARRAY),
                sources: &map.sources,
                ospa,
                notes: &self.notes.borrow(),
            };
            crate::output::write_atomic(out, serde_json::to_string_pretty(&report)?.as_bytes())?;
        }
        if let Some(png) = &self.a.png {
            let o = ospa.map_or(String::new(), |o| format!(", OSPA {:.3} m", o.total));
            let title = format!(
                "{}: {}, stop {}{}, {} sources{o}",
                self.name,
                self.settings.ssl.method,
                session.poses().len(),
                if final_map { " (final)" } else { "" },
                map.sources.len()
            );
            crate::figure::map(
                png,
                &MapFigure {
                    title,
                    map: &self.map,
                    poses: session.poses(),
                    result: map,
                    truth: session.truth(),
                    full_map: self.a.figure.full_map,
                    width: self.a.figure.figure_width,
                    kinds: Vec::new(),
                },
            )?;
        }
        Ok(())
    }
}

/// One line per stop.
fn line(r: &StopRecord) -> String {
    let o = r
        .ospa
        .map_or(String::new(), |o| format!("  OSPA {:.3} m", o.total));
    // A faulty microphone is named on the stop's line: a connector that works loose
    // mid-survey shows where it did.
    let faulty: String = r
        .faulty_channels
        .iter()
        .map(|f| {
            format!(
                "  channel {} {}{}",
                f.channel,
                match f.fault {
                    ssl::channels::Fault::Silent { .. } => "silent",
                    ssl::channels::Fault::Incoherent { .. } => "incoherent",
                },
                if f.left_out { ", left out" } else { "" }
            )
        })
        .collect();
    format!(
        "stop {:>3}  {:<14} {} DoAs  {:>2} sources{o}  ssl {:.0} ms  map {:.0} ms{}{}{faulty}",
        r.stop,
        r.file,
        r.doas,
        r.sources,
        r.ssl_ms,
        r.map_ms,
        r.full_map_ms.map_or(String::new(), |ms| format!(
            "  (took in the full map, {ms:.0} ms beside)"
        )),
        if r.full_map {
            "  (full map started)"
        } else {
            ""
        }
    )
}

/// Runs `iasm watch`.
///
/// # Errors
/// A data set folder without a map, bad settings, a recording or pose table that cannot be
/// read (named), or outputs that cannot be written.
pub fn run(a: &WatchArgs) -> Result<Outcome> {
    for p in a.png.iter().chain(&a.plot) {
        Format::of(p)?;
    }
    let mut settings = a
        .settings
        .settings()?
        .with_dataset_array(Some(&a.dir))
        .with_dataset_noise(Some(&a.dir))?;
    settings.iasm.refine |= a.refine;
    let ds = Dataset::open(&a.dir)?;
    let map_yaml = first_with_ext(&a.dir.join("map"), "yaml").with_context(|| {
        format!(
            "{}: the live map needs an occupancy map in map/ from the start (the region the robot will drive is not known in advance; `iasm map` searches around the stops without one)",
            a.dir.display()
        )
    })?;
    let map = load_map(&map_yaml)?;
    let truth = ds.sources.as_deref().map(read_sources).transpose()?;
    let mut session = Session::new(&map, &settings, a.seed, truth, a.ospa_c, a.ospa_p)?;
    if a.recompute {
        session = session.recompute_every_stop();
    }
    let out = Outputs {
        a,
        name: file_name(&a.dir),
        map,
        settings: &settings,
        mcap: std::cell::RefCell::new(
            a.mcap
                .as_deref()
                .map(crate::rosmap::McapFile::new)
                .transpose()?,
        ),
        notes: std::cell::RefCell::new(Vec::new()),
    };
    let theta_rad = a.theta_unit == AngleUnit::Rad;
    let mut records: Vec<StopRecord> = Vec::new();
    let t_run = Instant::now();
    if a.replay {
        replay(a, &ds, theta_rad, &mut session, &out, &mut records)?;
    } else {
        follow(a, theta_rad, &mut session, &out, &mut records)?;
    }
    finish(&mut session, &out, &records, t_run)?;
    Ok(Outcome::Success)
}

/// The run's end: the final map (a full map over every stop) written and said beside the
/// last live one, the warnings counted, the curve and its plot written.
fn finish(
    session: &mut Session,
    out: &Outputs<'_>,
    records: &[StopRecord],
    t_run: Instant,
) -> Result<()> {
    let a = out.a;
    let live = session.map();
    let live_ospa = session.ospa(&live);
    let fin = session.finish();
    out.write(session, &fin, true)?;
    if let Some(file) = out.mcap.take() {
        file.finish()?;
    }
    let elapsed = t_run.elapsed().as_secs_f64();
    let fo = session
        .ospa(&fin)
        .map_or(String::new(), |o| format!(", OSPA {:.3} m", o.total));
    let lo = live_ospa.map_or(String::new(), |o| format!(", OSPA {:.3} m", o.total));
    println!(
        "{} stops in {elapsed:.2} s; last live map: {} sources{lo}; final map (full, seed {}): {} sources{fo}",
        records.len(),
        live.sources.len(),
        a.seed,
        fin.sources.len()
    );
    let notes = out.notes.borrow();
    if !notes.is_empty() {
        println!(
            "{} warnings (in the map's notes): {}",
            notes.len(),
            notes.join("; ")
        );
    }
    if let Some(c) = &a.curve {
        crate::output::write_atomic(c, curve_csv(records).as_bytes())?;
    }
    let plot = a
        .plot
        .clone()
        .or_else(|| a.curve.as_ref().map(|c| c.with_extension("svg")));
    if let Some(p) = plot {
        crate::figure::curve(
            &p,
            &Curve {
                title: format!(
                    "{}: the map after each stop ({}, seed {})",
                    out.name, out.settings.ssl.method, a.seed
                ),
                records,
            },
        )?;
    }
    Ok(())
}

/// A finished data set, stop by stop, as fast as it goes: only the full map that a stop
/// starts beside the next ones ([`asm::online`]) is waited for between stops, untimed, as a
/// robot's driving and recording give it seconds.
fn replay(
    a: &WatchArgs,
    ds: &Dataset,
    theta_rad: bool,
    session: &mut Session,
    out: &Outputs<'_>,
    records: &mut Vec<StopRecord>,
) -> Result<()> {
    let table = a
        .poses
        .clone()
        .or_else(|| ds.poses.clone())
        .with_context(|| format!("{}: no pose table in pose/", ds.root.display()))?;
    let poses = read_poses(&table, theta_rad)?;
    ensure!(
        !ds.audio.is_empty(),
        "{}: no recording in audio/",
        ds.root.display()
    );
    ensure!(
        ds.audio.len() == poses.len(),
        "{} recordings but {} poses in {}: they must match one to one",
        ds.audio.len(),
        poses.len(),
        table.display()
    );
    let k = a.stops.unwrap_or(poses.len()).min(poses.len());
    for (file, pose) in ds.audio.iter().zip(&poses).take(k) {
        let t0 = Instant::now();
        let audio = ssl::read_wav(file)?;
        let read_ms = 1e3 * t0.elapsed().as_secs_f64();
        out.add(session, file, *pose, &audio, records, read_ms)?;
        session.wait_for_full_map();
    }
    Ok(())
}

/// Follows the folder until `--stops` or Ctrl-C.
fn follow(
    a: &WatchArgs,
    theta_rad: bool,
    session: &mut Session,
    out: &Outputs<'_>,
    records: &mut Vec<StopRecord>,
) -> Result<()> {
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        // Without a handler (another one is set), Ctrl-C still ends the process, and the
        // last map written stays whole on disk.
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    // Only a change wakes the loop: reading the folder's files (as every look does) makes
    // access events of its own, and waking on those kept an idle watch busy.
    let watcher = notify::recommended_watcher(move |e: notify::Result<notify::Event>| {
        if e.is_ok_and(|e| !e.kind.is_access()) {
            let _ = tx.send(());
        }
    })
    .and_then(|mut w| {
        use notify::Watcher;
        w.watch(&a.dir, notify::RecursiveMode::Recursive)
            .map(|()| w)
    });
    let poll = Duration::from_millis(a.poll_ms.max(10));
    let how = match &watcher {
        Ok(_) => format!(
            "file-system notifications, and a look every {} ms",
            poll.as_millis()
        ),
        Err(e) => format!(
            "a look every {} ms (notifications unavailable: {e})",
            poll.as_millis()
        ),
    };
    eprintln!(
        "watching {} ({how}); Ctrl-C ends with the final map",
        a.dir.display()
    );
    let mut follower = Follower::new(
        &a.dir,
        a.poses.clone(),
        theta_rad,
        Duration::from_secs_f64(a.give_up_s.max(0.0)),
    );
    let mut waiting: Option<String> = None;
    while !stop.load(Ordering::SeqCst) && a.stops.is_none_or(|k| follower.done() < k) {
        let next = follower.poll()?;
        for w in follower.take_warnings() {
            out.note(w);
        }
        match next {
            Next::Ready { file, audio, pose } => {
                waiting = None;
                out.add(session, &file, pose, &audio, records, 0.0)?;
            }
            Next::Skipped { file, reason } => {
                waiting = None;
                out.note(format!(
                    "stop {} ({}) skipped: {reason}",
                    follower.done(),
                    file_name(&file)
                ));
            }
            Next::Waiting(why) => {
                if waiting.as_deref() != Some(why.as_str()) {
                    eprintln!("waiting: {why}");
                    waiting = Some(why);
                }
                // Without notifications (the sender gone), a plain sleep: never a spin.
                if let Err(std::sync::mpsc::RecvTimeoutError::Disconnected) = rx.recv_timeout(poll)
                {
                    std::thread::sleep(poll);
                }
                while rx.try_recv().is_ok() {}
            }
        }
    }
    drop(watcher);
    Ok(())
}
