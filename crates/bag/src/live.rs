//! A run as it is recorded: messages arrive one at a time, and each stop is handed on as
//! soon as the robot has left it.
//!
//! A [`Recorder`] keeps what a bag reader keeps ([`crate::run`]), as if the messages so far
//! were a bag: [`Recorder::run`] reads that bag, with every rule of [`crate::read`] (the
//! topics chosen by type, the audio's format, its clock and its gaps, odometry beside a
//! localiser, `/tf` chains), and [`Recorder::finished_stops`] finds its stops with every
//! rule of [`crate::Run::stops`]. A stop is finished once the robot has moved on from it
//! (a pose after it lies outside its stretch) and the audio has reached the end of its
//! listening window, or the robot has been gone for [`AUDIO_WAIT_S`]. What finished stops
//! no longer need (the audio before the last one's end) is forgotten, so that memory holds
//! the audio of one drive and one stop, not of the whole run.
//!
//! ```
//! let mut live = iasm_bag::live::Recorder::new(iasm_bag::ReadOptions::default());
//! // A message that is not CDR of its type is refused as it comes, and the run goes on
//! // without it.
//! assert!(live.push("/odom", "nav_msgs/msg/Odometry", 1_000_000_000, &[0, 1, 0, 0]).is_err());
//! assert!(live.run().is_err()); // no audio yet
//! ```

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::format::{Connection, Message, Summary};
use crate::msg::{self, Encoding, Kind};
use crate::run::{Kept, ReadOptions, Run, assemble};
use crate::stops::{Stop, StopOptions};

/// How long after the robot left a stop its audio may still be arriving (s): past it, the
/// stop is taken with the audio there is.
pub const AUDIO_WAIT_S: f64 = 2.0;
/// How much of `/tf` before the last finished stop is kept (s): a localiser's `map -> odom`
/// is republished at every scan, so half a minute holds its latest.
pub const KEEP_TF_S: f64 = 30.0;
/// How long audio is kept while no pose comes (s): past it, the audio older than this is
/// dropped with a note. A stop listens for seconds, so a minute keeps every stop a pose
/// can still come for, and bounds what a run without poses holds (a minute of six
/// channels at 48 kHz in 16 bits is 35 MB).
pub const PENDING_AUDIO_S: f64 = 60.0;

/// A stop of a live run, with its audio.
#[derive(Clone, Debug)]
pub struct LiveStop {
    /// The stop, on the clock of [`LiveStop::run_start_ns`].
    pub stop: Stop,
    /// The origin of the stop's times (ns since the epoch).
    pub run_start_ns: i64,
    /// Its audio: one vector per channel, full scale at 1.
    pub audio: Vec<Vec<f32>>,
    /// Frames per second.
    pub sample_rate: u32,
}

impl LiveStop {
    /// When the robot arrived (ns since the epoch).
    pub fn arrived_ns(&self) -> i64 {
        self.run_start_ns + (self.stop.still_s.0 * 1e9) as i64
    }
}

/// The messages of a run so far, as a bag.
#[derive(Clone)]
pub struct Recorder {
    options: ReadOptions,
    summary: Summary,
    kept: Kept,
    ids: HashMap<String, u32>,
    /// Where the next stop must start (ns since the epoch): after the last one handed on.
    next_after_ns: i64,
    /// When the last pose, odometry or transform message came (ns since the epoch).
    last_pose_ns: Option<i64>,
    /// How long audio is kept while no pose comes (s; [`PENDING_AUDIO_S`] by default).
    pending_audio_s: f64,
    /// Audio dropped while no pose came and not yet said (s).
    dropped_s: f64,
    /// The stamp jumps said: (topic, the jump in tenths of a second).
    jumps_said: std::collections::HashSet<(String, i64)>,
    /// Notes not yet taken.
    notes: Vec<String>,
}

impl Recorder {
    /// An empty run read with `options` (topics chosen as [`crate::read`] chooses them).
    pub fn new(options: ReadOptions) -> Self {
        Self {
            options,
            summary: Summary::default(),
            kept: Kept::default(),
            ids: HashMap::new(),
            next_after_ns: i64::MIN,
            last_pose_ns: None,
            pending_audio_s: PENDING_AUDIO_S,
            dropped_s: 0.0,
            jumps_said: Default::default(),
            notes: Vec::new(),
        }
    }

    /// Keeps audio at most `seconds` while no pose comes (instead of [`PENDING_AUDIO_S`]).
    ///
    /// # Errors
    /// [`Error::Config`] for a duration that is not finite and positive.
    pub fn with_pending_audio(mut self, seconds: f64) -> Result<Self> {
        if !(seconds.is_finite() && seconds > 0.0) {
            return Err(Error::Config(format!(
                "the audio kept while no pose comes must be a positive duration (got {seconds} s)"
            )));
        }
        self.pending_audio_s = seconds;
        Ok(self)
    }

    /// Takes one message of `topic` (CDR, encapsulation header included), received at
    /// `time_ns` (ns since the epoch). Types the run does not use are counted and dropped.
    ///
    /// # Errors
    /// A message that does not decode as its type, or audio whose format changed: the
    /// message is not kept, and the run goes on without it.
    pub fn push(&mut self, topic: &str, msg_type: &str, time_ns: i64, data: &[u8]) -> Result<()> {
        let next = u32::try_from(self.ids.len()).unwrap_or(u32::MAX);
        let id = *self.ids.entry(topic.to_owned()).or_insert(next);
        if self.summary.connections.iter().all(|c| c.id != id) {
            self.summary.connections.push(Connection {
                id,
                topic: topic.to_owned(),
                msg_type: msg_type.to_owned(),
                encoding: Encoding::Cdr,
            });
        }
        let connection = self
            .summary
            .connections
            .iter()
            .find(|c| c.id == id)
            .expect("added above");
        if connection.msg_type != msg_type {
            return Err(Error::Topic(format!(
                "{topic} carried {} and now {msg_type}",
                connection.msg_type
            )));
        }
        // A bag reader decodes poses, transforms and grids when it assembles the run; here
        // each is decoded as it comes, so that one bad message is refused alone rather than
        // making every later run unreadable.
        let checked = match Kind::of(msg_type) {
            Some(k) if k.is_pose() => msg::pose(k, Encoding::Cdr, data).and_then(|p| {
                [p.pose.x, p.pose.y, p.pose.theta]
                    .iter()
                    .all(|v| v.is_finite())
                    .then_some(())
                    .ok_or_else(|| format!("a pose that is not finite ({:?})", p.pose))
            }),
            Some(Kind::Tf) => msg::transforms(Encoding::Cdr, data).and_then(|ts| {
                ts.iter()
                    .all(|t| {
                        [t.pose.x, t.pose.y, t.pose.theta]
                            .iter()
                            .all(|v| v.is_finite())
                    })
                    .then_some(())
                    .ok_or_else(|| "a transform that is not finite".to_owned())
            }),
            Some(Kind::OccupancyGrid) => msg::grid(Encoding::Cdr, data).map(|_| ()),
            Some(Kind::AudioInfo) => msg::audio_info(Encoding::Cdr, data).map(|_| ()),
            _ => Ok(()),
        };
        if let Err(what) = checked {
            return Err(Error::Message {
                topic: topic.to_owned(),
                msg_type: msg_type.to_owned(),
                index: self.summary.counts.get(&id).copied().unwrap_or(0) + 1,
                what,
            });
        }
        let kind = Kind::of(msg_type);
        self.kept.take(
            &Message {
                connection,
                time_ns,
                data,
            },
            &self.options,
        )?;
        self.summary.count(id, time_ns);
        if kind.is_some_and(|k| k.is_pose() || k == Kind::Tf) {
            self.last_pose_ns = Some(time_ns);
        } else if kind.is_some_and(Kind::is_audio) {
            self.bound_pending_audio(time_ns);
        }
        Ok(())
    }

    /// Drops the audio older than the pending bound ([`PENDING_AUDIO_S`] by default) before
    /// `now_ns` when no pose has come since then: no stop can be found in it until a pose
    /// comes.
    fn bound_pending_audio(&mut self, now_ns: i64) {
        let cutoff = now_ns - (self.pending_audio_s * 1e9) as i64;
        if self.last_pose_ns.is_some_and(|p| p >= cutoff) {
            return;
        }
        let before = self.kept.audio_span_ns();
        self.kept.forget_audio_before(cutoff);
        self.dropped_s += (before - self.kept.audio_span_ns()) as f64 * 1e-9;
    }

    /// The span of the audio kept (s): what a run without poses holds.
    pub fn kept_audio_s(&self) -> f64 {
        self.kept.audio_span_ns() as f64 * 1e-9
    }

    /// What the recorder had to drop since the last call, in words.
    pub fn take_notes(&mut self) -> Vec<String> {
        if self.dropped_s > 0.0 {
            self.dropped_s = 0.0;
            self.notes.push(format!(
                "audio older than {} s dropped: no pose came in that time",
                self.pending_audio_s
            ));
        }
        std::mem::take(&mut self.notes)
    }

    /// The run so far, read as a bag.
    ///
    /// # Errors
    /// What [`crate::read`] refuses of it (no audio or pose topic yet, topics to choose
    /// between, ...).
    pub fn run(&self) -> Result<Run> {
        assemble(&self.summary, self.kept.clone(), &self.options)
    }

    /// The stops finished since the last call, in order, each with its audio; with `all`
    /// (the run has ended) the stop the robot is still at too. Forgets what they no
    /// longer need.
    ///
    /// # Errors
    /// As [`Recorder::run`], and options [`StopOptions::validate`] refuses.
    pub fn finished_stops(&mut self, options: &StopOptions, all: bool) -> Result<Vec<LiveStop>> {
        let run = self.run()?;
        // The clock the run began on, kept: its first messages will be forgotten.
        if self.kept.lag_ns.is_none() {
            self.kept.lag_ns = run.clock_lag_ns;
        }
        // Each jump of the stamps said once, when it is first seen (a jump's first message
        // is forgotten once a stop after it is handed on: it is known by its size).
        for j in &run.stamp_jumps {
            if self
                .jumps_said
                .insert((j.topic.clone(), (j.jump_s * 10.0).round() as i64))
            {
                self.notes.push(format!(
                    "{}: stamps {:.1} s {} than the messages came, from {:.1} s on (a clock \
                     step or a wrong stamp): timed by when they came",
                    j.topic,
                    j.jump_s.abs(),
                    if j.jump_s > 0.0 { "earlier" } else { "later" },
                    (j.recorded_ns.0 - run.start_ns) as f64 * 1e-9
                ));
            }
        }
        let track = if run.odometry.is_empty() {
            &run.poses
        } else {
            &run.odometry
        };
        let last_pose = track.last().map_or(f64::NEG_INFINITY, |p| p.t);
        let fs = f64::from(run.format.sample_rate);
        let audio_end = run
            .segments
            .last()
            .map_or(f64::NEG_INFINITY, |s| s.start_s + s.frames as f64 / fs);
        let abs = |t: f64| run.start_ns + (t * 1e9) as i64;
        let mut out = Vec::new();
        for stop in run.stops(options)? {
            if abs(stop.still_s.0) <= self.next_after_ns {
                continue;
            }
            let left = stop.still_s.1 < last_pose;
            let heard = audio_end >= stop.still_s.1 - options.end_margin_s
                || last_pose > stop.still_s.1 + AUDIO_WAIT_S;
            if !(all || left && heard) {
                break;
            }
            self.next_after_ns = abs(stop.still_s.1);
            out.push(LiveStop {
                audio: run.stop_audio(&stop),
                run_start_ns: run.start_ns,
                sample_rate: run.format.sample_rate,
                stop,
            });
        }
        if let Some(s) = out.last() {
            let end = s.run_start_ns + (s.stop.listen_s.1 * 1e9) as i64;
            self.kept.forget_before(end, (KEEP_TF_S * 1e9) as i64);
        }
        Ok(out)
    }
}
