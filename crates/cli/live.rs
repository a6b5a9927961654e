//! The live mapper behind `iasm ros2`: a robot's messages in, a map out after every stop.
//!
//! It knows nothing of how messages arrive (DDS in `cmd::ros2`, a bag in its tests): each
//! message is handed to [`LiveMapper::push`] with its topic, type, receipt time and CDR
//! bytes. Messages are kept as a bag reader keeps them ([`bag::live::Recorder`]), so the
//! topics, the stops and their audio are found by every rule `iasm bag` finds them by; each
//! stop is localised as soon as the robot leaves it and added to the stop-by-stop mapper
//! (the session `iasm watch` maps with); [`LiveMapper::finish`] ends with the
//! full map over every stop, which is the map `iasm bag --out D` then `iasm map --dataset
//! D` makes of the same run with the same seed.
//!
//! The map is searched in the robot's occupancy grid (`/map`) once it has one in the poses'
//! frame, and until then within [`crate::pipeline::OPEN_MARGIN_M`] of the stops, as
//! `iasm map` searches without a map; when that region changes, the mapper is rebuilt over
//! the stops so far (their DoAs are kept, not localised again).
//!
//! Nothing a robot sends stops it: a message that does not decode, a sample rate that
//! changes, a stop whose audio has a gap, a recording the SSL refuses, is a warning, counted
//! in [`LiveMapper::notes`], and the run goes on.

use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::Result;
use asm::map::OccupancyMap;
use asm::{MapResult, Pose};
use serde::Serialize;
use ssl::Audio;

use crate::online::{Session, StopRecord};
use crate::rosmap::MapMessages;
use crate::settings::Settings;

/// A stop as the mapper took it.
#[derive(Clone, Debug, Serialize)]
pub struct LiveStopRow {
    /// When the robot arrived (ns since the epoch).
    pub arrived_ns: i64,
    /// Where it stood.
    pub pose: Pose,
    /// Its DoAs (degrees, array frame, strongest first).
    pub doas_deg: Vec<f64>,
    /// Whether N cut its row.
    pub cut: bool,
    /// The SSL method that found them.
    pub method: ssl::Method,
}

/// What the node does after each stop.
pub struct Update {
    /// The stop's line (as `iasm watch` prints it).
    pub record: StopRecord,
    /// The map now.
    pub map: MapResult,
}

/// The robot's messages in, the map out.
pub struct LiveMapper {
    recorder: bag::live::Recorder,
    stop_options: bag::StopOptions,
    settings: Settings,
    seed: u64,
    session: Option<Session>,
    /// The map the session searches, and whether it is the robot's grid.
    map: Option<(OccupancyMap, bool)>,
    stops: Vec<LiveStopRow>,
    /// Warnings by kind, counted (the map's notes).
    notes: BTreeMap<String, usize>,
    /// The last "not yet" state of the run (no audio yet, ...), said once.
    waiting: Option<String>,
    /// A map of an earlier run that each map is compared with (`iasm ros2 --prior`).
    prior: Option<crate::mapfile::MapFile>,
}

/// The map JSON the node writes.
#[derive(Serialize)]
pub struct LiveReport<'a> {
    /// Its version.
    pub schema_version: u32,
    /// The frame of every coordinate.
    pub frame_id: &'static str,
    /// The particle filter's seed.
    pub seed: u64,
    /// Whether this is the final (full) map.
    pub final_map: bool,
    /// The stops mapped.
    pub stops: &'a [LiveStopRow],
    /// The mapper's settings.
    pub params: &'a asm::IasmConfig,
    /// The SSL's settings.
    pub ssl: &'a ssl::SslConfig,
    /// The sources.
    pub sources: &'a [asm::Source],
    /// What was refused, and why.
    pub refused: &'a [asm::Refused],
    /// What went wrong on the way, counted.
    pub notes: Vec<String>,
    /// With a prior map: the file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior: Option<&'a std::path::Path>,
    /// With a prior map: what changed against it (as `iasm diff` lists it, `before`
    /// indexing the prior's sources and `after` these).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub changes: Option<Vec<asm::diff::Change>>,
}

impl LiveMapper {
    /// A mapper with `settings`, reading topics as `read` says and finding stops as `stops`
    /// says, its particle filter seeded by `seed`.
    ///
    /// # Errors
    /// Stop options that [`bag::StopOptions::validate`] refuses, or settings the SSL or
    /// the mapper refuse.
    pub fn new(
        settings: Settings,
        read: bag::ReadOptions,
        stops: bag::StopOptions,
        seed: u64,
    ) -> Result<Self> {
        stops.validate()?;
        settings.mic_array()?;
        Ok(Self {
            recorder: bag::live::Recorder::new(read),
            stop_options: stops,
            settings,
            seed,
            session: None,
            map: None,
            stops: Vec::new(),
            notes: BTreeMap::new(),
            waiting: None,
            prior: None,
        })
    }

    /// Compares every map with `prior`, a map of an earlier run in the same frame (`iasm
    /// ros2 --prior`): the messages then carry what changed (their `changes` markers) and
    /// the JSON its list ([`LiveReport::changes`]).
    #[must_use]
    pub fn with_prior(mut self, prior: crate::mapfile::MapFile) -> Self {
        self.prior = Some(prior);
        self
    }

    /// What changed between the prior map and `result` (`None` without a prior).
    pub fn changes(&self, result: &MapResult) -> Option<Vec<asm::diff::Change>> {
        let prior = self.prior.as_ref()?;
        Some(asm::diff::diff(
            &prior.placed(),
            &placed(result),
            &asm::diff::DiffConfig::default(),
        ))
    }

    /// Keeps audio at most `seconds` while no pose comes (`iasm ros2 --pending-audio`).
    ///
    /// # Errors
    /// A duration that is not finite and positive.
    pub fn with_pending_audio(mut self, seconds: f64) -> Result<Self> {
        self.recorder = self.recorder.with_pending_audio(seconds)?;
        Ok(self)
    }

    fn note(&mut self, what: String) -> String {
        *self.notes.entry(what.clone()).or_default() += 1;
        what
    }

    /// Takes one message; `Some(warning)` when it cannot be used (it is dropped, counted).
    pub fn push(
        &mut self,
        topic: &str,
        msg_type: &str,
        time_ns: i64,
        data: &[u8],
    ) -> Option<String> {
        match self.recorder.push(topic, msg_type, time_ns, data) {
            Ok(()) => None,
            // Counted by what is wrong, not by which message.
            Err(bag::Error::Message { what, .. }) => {
                Some(self.note(format!("a message of {topic} ({msg_type}) dropped: {what}")))
            }
            Err(e) => Some(self.note(format!("a message of {topic} dropped: {e}"))),
        }
    }

    /// The settings the next stop is localised and mapped with.
    #[must_use]
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Localises and maps from the next stop on with `settings` and `seed` (the node's
    /// parameters set while it runs): the mapper is rebuilt over the stops so far, whose
    /// DoAs are kept.
    ///
    /// # Errors
    /// Settings that do not validate or name no array; the mapper keeps its own then.
    pub fn set_settings(&mut self, settings: Settings, seed: u64) -> Result<()> {
        settings.validate()?;
        settings.mic_array()?;
        self.settings = settings;
        self.seed = seed;
        self.session = None;
        Ok(())
    }

    /// Forgets every stop and the map (the node's `clear_map`); the robot's messages of the
    /// stop it stands at stay. How many stops were forgotten.
    pub fn clear(&mut self) -> usize {
        self.session = None;
        self.map = None;
        std::mem::take(&mut self.stops).len()
    }

    /// The stops mapped so far.
    pub fn stops(&self) -> &[LiveStopRow] {
        &self.stops
    }

    /// What went wrong on the way: each kind of warning with its count.
    pub fn notes(&self) -> Vec<String> {
        self.notes
            .iter()
            .map(|(w, n)| {
                if *n > 1 {
                    format!("{w} ({n} times)")
                } else {
                    w.clone()
                }
            })
            .collect()
    }

    /// Maps the stops the robot has finished (with `all`, the one it stands at too), one
    /// update per stop; warnings for what could not be used. `Err` only for what no
    /// message can mend (settings the SSL refuses for this audio are warnings per stop).
    pub fn step(&mut self, all: bool) -> (Vec<Update>, Vec<String>) {
        let mut warnings = Vec::new();
        for n in self.recorder.take_notes() {
            warnings.push(self.note(n));
        }
        let finished = match self.recorder.finished_stops(&self.stop_options, all) {
            Ok(s) => {
                self.waiting = None;
                s
            }
            Err(e) => {
                // Not yet a run (no audio or pose yet, or topics to choose between): said
                // once until it changes.
                let what = e.to_string();
                if self.waiting.as_deref() != Some(&what) {
                    warnings.push(format!("waiting: {what}"));
                    self.waiting = Some(what);
                }
                return (Vec::new(), warnings);
            }
        };
        let mut updates = Vec::new();
        for stop in finished {
            match self.add(&stop) {
                Ok(u) => updates.push(u),
                Err(e) => warnings.push(self.note(format!(
                    "the stop at {:.1} s skipped: {e:#}",
                    stop.stop.still_s.0
                ))),
            }
        }
        (updates, warnings)
    }

    /// The map to search: the robot's grid when the run has one, else the region around
    /// the stops (with `extra` among them).
    fn current_map(&self, extra: Pose) -> Result<(OccupancyMap, bool)> {
        if let Ok(run) = self.recorder.run()
            && let Some(grid) = &run.map
        {
            return Ok((crate::bagset::grid_map(grid)?, true));
        }
        let points: Vec<[f64; 2]> = self
            .stops
            .iter()
            .map(|s| [s.pose.x, s.pose.y])
            .chain([[extra.x, extra.y]])
            .collect();
        Ok((
            OccupancyMap::open_around(
                &points,
                crate::pipeline::OPEN_MARGIN_M,
                crate::pipeline::OPEN_RESOLUTION_M,
            )?,
            false,
        ))
    }

    fn add(&mut self, stop: &bag::live::LiveStop) -> Result<Update> {
        let t0 = Instant::now();
        let audio = Audio::new(stop.sample_rate, stop.audio.clone())?;
        let map = self.current_map(stop.stop.pose)?;
        if self.map.as_ref() != Some(&map) || self.session.is_none() {
            // A new region: one batch map over the stops so far (`Session::add_history`).
            let mut session = Session::new(&map.0, &self.settings, self.seed, None, 1.0, 1.0)?;
            session
                .add_history((self.stops.iter()).map(|s| (s.pose, &s.doas_deg[..], Some(s.cut))))?;
            self.session = Some(session);
            self.map = Some(map);
        }
        let session = self.session.as_mut().expect("set above");
        let (doas, cut) = session.localise_row(&audio)?;
        let ssl_ms = 1e3 * t0.elapsed().as_secs_f64();
        let name = format!("stop {}", self.stops.len() + 1);
        let mut record = session.add_row(&name, stop.stop.pose, &doas, Some(cut))?;
        record.ssl_ms = ssl_ms;
        self.stops.push(LiveStopRow {
            arrived_ns: stop.arrived_ns(),
            pose: stop.stop.pose,
            doas_deg: doas,
            cut,
            method: self.settings.ssl.method,
        });
        Ok(Update {
            record,
            map: session.map(),
        })
    }

    /// The full map over every stop so far (`None` before the first stop).
    pub fn finish(&mut self) -> Option<MapResult> {
        self.session.as_mut().map(Session::finish)
    }

    /// The messages of `result` over the stops so far, stamped `stamp_ns`.
    pub fn messages(&self, result: &MapResult, stamp_ns: i64) -> Option<MapMessages> {
        let (map, _) = self.map.as_ref()?;
        let stops = self
            .stops
            .iter()
            .map(|s| (s.pose, s.arrived_ns, s.doas_deg.as_slice()));
        let mut m = crate::rosmap::messages_over(result, stops, map, stamp_ns);
        if let Some(prior) = &self.prior {
            let (before, now) = (prior.placed(), placed(result));
            let changes = asm::diff::diff(&before, &now, &asm::diff::DiffConfig::default());
            m.changes = Some(crate::rosmap::change_markers(
                &before,
                &now,
                &changes,
                &m.sources.markers[0].header,
            ));
        }
        Some(m)
    }

    /// The map JSON of `result`.
    pub fn report<'a>(&'a self, result: &'a MapResult, final_map: bool) -> LiveReport<'a> {
        LiveReport {
            schema_version: 1,
            frame_id: crate::rosmap::FRAME,
            seed: self.seed,
            final_map,
            stops: &self.stops,
            params: &self.settings.iasm,
            ssl: &self.settings.ssl,
            sources: &result.sources,
            refused: &result.refused,
            notes: self.notes(),
            prior: self.prior.as_ref().map(|p| p.path.as_path()),
            changes: self.changes(result),
        }
    }
}

/// A map's sources as `asm::diff` compares them.
fn placed(result: &MapResult) -> Vec<asm::diff::Placed> {
    result.sources.iter().map(Into::into).collect()
}
