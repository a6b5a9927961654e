//! A robot run out of a bag: which topics hold its audio and poses, the audio as
//! continuous multichannel segments on the run's clock, and the poses.
//!
//! **Topics.** A bag holds many topics; the run needs one audio topic, its format, and a
//! pose topic, and may use an odometry topic beside it. Each is taken from the options when
//! named there, else chosen by type when the choice is unambiguous: the one audio topic;
//! the `AudioInfo` topic beside it; the one pose topic, or, when odometry and one other pose
//! topic are recorded (a localiser's `/amcl_pose` in the map's frame), that other one, with
//! the odometry kept to find the stops ([`crate::stops`]); without a pose topic, the chain
//! of `/tf` from the map to the robot's base ([`crate::tf`]). Anything else is an error that
//! lists the candidates and names the option to choose with.
//!
//! **Time.** A message's time is its header's stamp where it has one, else the time the
//! recorder received it. An audio message is taken to end at its time (a capture node
//! publishes a buffer when it is full), so the stream's start is the earliest of `time -
//! samples so far / rate` over its messages: the message that arrived with the least delay
//! says it best. Where that start jumps by more than [`GAP_S`] (dropped messages, a paused
//! recorder) the audio is cut into another segment, so that no sample is placed on the
//! clock by more than that. When a topic's stamps and its receipt times disagree by more
//! than [`CLOCK_MISMATCH_S`] (a bag recorded under simulated time, a device that stamps on
//! its own clock), the stamps of no topic are used and [`Run::notes`] says so: audio and
//! poses are then on one clock. Before that, a topic's stamps that stray from its usual lag
//! behind the receipt times by more than [`STAMP_JUMP_S`] (a clock stepped back or forth
//! mid-run, one wrong stamp) are set right by the receipt times, each run of them named in
//! [`Run::notes`]: a stop is never built from audio and poses on two clocks.
//!
//! **The robot's map.** A bag often holds the occupancy grid the robot localised in
//! (`nav_msgs/OccupancyGrid` on `/map`, latched). It is taken (its last message: a mapper's
//! grid grows) only where it can stand beside the poses: in their frame (its header's and
//! theirs agree: odometry is in `odom`, a map in `map`) and with an origin that is not
//! turned (a ROS map file's turned origin is one that most readers, ours among them,
//! refuse). Otherwise a note says why it was left out.

use std::collections::HashMap;
use std::io::Read;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::format::{self, Summary};
use crate::msg::{self, AudioInfo, Encoding, Grid, Kind};
pub use crate::track::TimedPose;

mod time;
mod topics;

use time::*;
pub use time::{STAMP_JUMP_S, StampJump};
use topics::*;

mod assemble;
pub(crate) use assemble::assemble;

/// Where an audio stream's start jumps by more than this (s), a new segment begins.
pub const GAP_S: f64 = 0.2;

/// Stamps that differ from the receipt times by more than this (s, median over a topic)
/// are on another clock, and receipt times are used for every topic.
pub const CLOCK_MISMATCH_S: f64 = 5.0;

/// A sample format, by GStreamer's names as `audio_capture` takes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleFormat {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    S8,
    /// Signed 16-bit little-endian.
    S16LE,
    /// Signed 24-bit little-endian, packed in 3 bytes.
    S24LE,
    /// Signed 32-bit little-endian.
    S32LE,
    /// 32-bit float little-endian.
    F32LE,
    /// 64-bit float little-endian.
    F64LE,
}

impl SampleFormat {
    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        match self {
            Self::U8 | Self::S8 => 1,
            Self::S16LE => 2,
            Self::S24LE => 3,
            Self::S32LE | Self::F32LE => 4,
            Self::F64LE => 8,
        }
    }

    /// One sample from its bytes, full scale at 1.
    fn decode(self, b: &[u8]) -> f32 {
        match self {
            Self::U8 => (f32::from(b[0]) - 128.0) / 128.0,
            Self::S8 => f32::from(b[0] as i8) / 128.0,
            Self::S16LE => f32::from(i16::from_le_bytes([b[0], b[1]])) / 32768.0,
            Self::S24LE => (i32::from_le_bytes([0, b[0], b[1], b[2]]) >> 8) as f32 / 8_388_608.0,
            Self::S32LE => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32 / 2_147_483_648.0,
            Self::F32LE => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            Self::F64LE => f64::from_le_bytes(b[..8].try_into().expect("8 bytes")) as f32,
        }
    }
}

impl FromStr for SampleFormat {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        Ok(match s.to_ascii_uppercase().as_str() {
            "U8" => Self::U8,
            "S8" => Self::S8,
            "S16LE" => Self::S16LE,
            "S24LE" => Self::S24LE,
            "S32LE" => Self::S32LE,
            "F32LE" => Self::F32LE,
            "F64LE" => Self::F64LE,
            _ => {
                return Err(Error::Audio(format!(
                    "sample format {s:?} is not one of U8, S8, S16LE, S24LE, S32LE, F32LE, F64LE"
                )));
            }
        })
    }
}

/// How the audio topic's bytes are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AudioFormat {
    /// Channels per frame (interleaved).
    pub channels: u16,
    /// Frames per second.
    pub sample_rate: u32,
    /// The sample format.
    pub sample: SampleFormat,
}

/// Which topics to read and how; `None` fields are chosen from the bag (module docs).
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// The audio topic.
    pub audio_topic: Option<String>,
    /// The topic of the poses the map is made in.
    pub pose_topic: Option<String>,
    /// An odometry (or any pose) topic to find the stops by, beside the pose topic; `Some("")`
    /// for none (the stops are found from the pose topic).
    pub odom_topic: Option<String>,
    /// The audio's format, instead of the bag's `AudioInfo`.
    pub format: Option<AudioFormat>,
    /// The occupancy grid topic; `Some("")` for none.
    pub map_topic: Option<String>,
    /// The robot's base frame, for poses out of `/tf` ([`crate::tf`]; default: the first of
    /// [`crate::tf::BASE_FRAMES`] the transforms have).
    pub base_frame: Option<String>,
}

/// A topic of the bag.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicInfo {
    /// Its name.
    pub topic: String,
    /// Its type.
    pub msg_type: String,
    /// Its number of messages.
    pub messages: usize,
    /// Its first and last receipt time (s from the run's start).
    pub span_s: (f64, f64),
}

/// Continuous audio from one time on: a stretch of [`Run`]'s audio bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct AudioSegment {
    /// The time of its first sample (s from the run's start).
    pub start_s: f64,
    /// Where its first frame starts in the run's audio bytes.
    pub offset: usize,
    /// Its length in frames.
    pub frames: usize,
}

/// What a bag holds of a robot run.
#[derive(Clone)]
pub struct Run {
    /// Every topic of the bag.
    pub topics: Vec<TopicInfo>,
    /// The run's time origin: the first message's receipt time (ns since the epoch).
    pub start_ns: i64,
    /// The audio topic.
    pub audio_topic: String,
    /// The audio's format.
    pub format: AudioFormat,
    /// The audio, in segments of continuous samples, in time order.
    pub segments: Vec<AudioSegment>,
    /// The audio topic's samples as recorded (interleaved frames, [`Run::format`]),
    /// decoded only when asked for ([`Run::samples`]): a run's audio is kept at its
    /// recorded size, not as floats of twice or four times it.
    pub audio: Vec<u8>,
    /// The pose topic.
    pub pose_topic: String,
    /// Its poses, in time order.
    pub poses: Vec<TimedPose>,
    /// The odometry topic the stops are found by, when it is not the pose topic.
    pub odom_topic: Option<String>,
    /// Its poses, in time order (empty without one).
    pub odometry: Vec<TimedPose>,
    /// The frame the poses are given in (their headers' `frame_id`; `None` for `Pose2D`).
    pub pose_frame: Option<String>,
    /// The occupancy grid topic taken.
    pub map_topic: Option<String>,
    /// Its last message (a mapper's map grows; the last is the whole), when it is in the
    /// poses' frame and square to it (module docs).
    pub map: Option<Grid>,
    /// `Some(byte)` when the bag ends inside a record, where the last whole one ended.
    pub truncated: Option<u64>,
    /// What the reader decided that the user should know (a clock, a topic chosen).
    pub notes: Vec<String>,
    /// The usual lag of the stamps behind the receipt times on the clock the run began on
    /// (ns; `None` with fewer than three stamped messages): what a stamp that lies is
    /// judged against ([`STAMP_JUMP_S`]).
    pub clock_lag_ns: Option<i64>,
    /// The runs of messages whose stamps lied, set right by when they were recorded (each
    /// also a note).
    pub stamp_jumps: Vec<StampJump>,
}

/// Messages of one topic as read: (receipt time ns, bytes).
type Raw = Vec<(i64, Vec<u8>)>;

/// An audio topic as read: each message's receipt time, stamp and length in bytes, and
/// their samples end to end.
#[derive(Clone, Default)]
struct AudioRaw {
    msgs: Vec<(i64, Option<i64>, usize)>,
    bytes: Vec<u8>,
    /// The format its messages give (`AudioStamped`), the same in each.
    embedded: Option<msg::Embedded>,
}

/// How far back (messages) a stamped audio message is looked for as a duplicate, and may
/// be put back in its place: a loaded network delivers a message twice or two out of
/// order, not dozens.
const REORDER_WINDOW: usize = 8;

impl AudioRaw {
    /// Keeps one audio message (receipt time, stamp, samples). A stamped message that was
    /// delivered twice (the stamp and length of one of the last [`REORDER_WINDOW`]) is kept
    /// once; one delivered after a later one (its stamp before theirs, after an earlier
    /// one's within the window) is put back in its place, so that the samples lie end to
    /// end in the order they were captured. A stamp that fits nowhere in the window (a
    /// stamp that lies) is left to [`Run`]'s clock check.
    fn put(&mut self, time_ns: i64, stamp_ns: Option<i64>, data: &[u8]) {
        let n = self.msgs.len();
        let window = n.saturating_sub(REORDER_WINDOW)..n;
        if let Some(stamp) = stamp_ns {
            if self.msgs[window.clone()]
                .iter()
                .any(|m| m.1 == Some(stamp) && m.2 == data.len())
            {
                return;
            }
            let later = self.msgs[window.clone()]
                .iter()
                .rev()
                .take_while(|m| m.1.is_some_and(|s| s > stamp))
                .count();
            let at = n - later;
            // Its place: after an earlier stamp within the window, or first of all when the
            // whole stream so far is within it.
            let placed = if at == 0 {
                n <= REORDER_WINDOW
            } else {
                at > window.start && self.msgs[at - 1].1.is_some_and(|s| s < stamp)
            };
            if later > 0 && placed {
                let offset: usize = self.msgs[..at].iter().map(|m| m.2).sum();
                self.bytes.splice(offset..offset, data.iter().copied());
                // Its receipt time no later than the next one's, so that the messages
                // stay in receipt order for what forgets them by it.
                self.msgs
                    .insert(at, (time_ns.min(self.msgs[at].0), stamp_ns, data.len()));
                return;
            }
        }
        self.msgs.push((time_ns, stamp_ns, data.len()));
        self.bytes.extend_from_slice(data);
    }
}

impl std::fmt::Debug for Run {
    /// Every field but the audio's bytes, of which it gives the count.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Run")
            .field("topics", &self.topics)
            .field("start_ns", &self.start_ns)
            .field("audio_topic", &self.audio_topic)
            .field("format", &self.format)
            .field("segments", &self.segments)
            .field("audio", &format_args!("[{} bytes]", self.audio.len()))
            .field("pose_topic", &self.pose_topic)
            .field("poses", &self.poses.len())
            .field("odom_topic", &self.odom_topic)
            .field("odometry", &self.odometry.len())
            .field("pose_frame", &self.pose_frame)
            .field("map_topic", &self.map_topic)
            .field(
                "map",
                &self.map.as_ref().map(|g| (g.width, g.height, g.resolution)),
            )
            .field("truncated", &self.truncated)
            .field("notes", &self.notes)
            .finish()
    }
}

impl Run {
    /// The samples of frames `frames` of segment `segment`, one vector per channel, full
    /// scale at 1.
    ///
    /// # Panics
    /// If `segment` is not a segment of the run or `frames` reaches beyond its end.
    pub fn samples(&self, segment: usize, frames: std::ops::Range<usize>) -> Vec<Vec<f32>> {
        let seg = &self.segments[segment];
        assert!(
            frames.end <= seg.frames,
            "frames {frames:?} beyond a segment of {}",
            seg.frames
        );
        let ch = usize::from(self.format.channels);
        let width = self.format.sample.bytes();
        let frame_bytes = ch * width;
        let bytes = &self.audio
            [seg.offset + frames.start * frame_bytes..seg.offset + frames.end * frame_bytes];
        let mut out = vec![Vec::with_capacity(frames.len()); ch];
        for f in bytes.chunks_exact(frame_bytes) {
            for (c, s) in out.iter_mut().zip(f.chunks_exact(width)) {
                c.push(self.format.sample.decode(s));
            }
        }
        out
    }
}

/// Reads the run out of a bag's bytes ([`format::scan`]): only the topics of the types
/// [`msg`] reads are kept in memory.
///
/// # Errors
/// What [`format::scan`] refuses; no audio or pose topic, or more than one where none was
/// named; a named topic that is not in the bag or not of a fitting type; audio of no known
/// format, not raw PCM, or whose bytes are not whole frames; a message that does not
/// decode.
pub fn read<R: Read>(r: R, options: &ReadOptions) -> Result<Run> {
    let mut kept = Kept::default();
    let summary = format::scan(r, |m| kept.take(&m, options))?;
    assemble(&summary, kept, options)
}

/// Reads the run out of the bag at `path`: a ROS 1 bag, a ROS 2 bag in MCAP or SQLite (its
/// folder or one of its files), or the folder of a split ROS 1 run, told apart by their
/// first bytes ([`crate::ros2::bag_files`]).
///
/// # Errors
/// The file cannot be opened, or what [`read`] refuses.
pub fn read_file(path: &std::path::Path, options: &ReadOptions) -> Result<Run> {
    let mut kept = Kept::default();
    let summary = crate::ros2::scan_files(path, |m| kept.take(&m, options))?;
    assemble(&summary, kept, options)
}

/// What a scan keeps: the audio topics' samples, the last message of each occupancy grid,
/// every message of the other topics of a kind [`msg`] reads.
#[derive(Clone, Default)]
pub(crate) struct Kept {
    raw: HashMap<String, Raw>,
    audio: HashMap<String, AudioRaw>,
    encodings: HashMap<String, Encoding>,
    kinds: HashMap<String, Kind>,
    /// The run's usual lag of stamps behind receipt times (ns), once known: a live run
    /// keeps the one its first messages gave, which it forgets ([`Run::clock_lag_ns`]).
    pub(crate) lag_ns: Option<i64>,
}

impl Kept {
    /// The span of the audio kept (ns, from its first message's time to its last's).
    pub(crate) fn audio_span_ns(&self) -> i64 {
        self.audio
            .values()
            .map(|raw| match (raw.msgs.first(), raw.msgs.last()) {
                (Some(a), Some(b)) => b.0 - a.0,
                _ => 0,
            })
            .sum()
    }

    /// Forgets the audio received before `cutoff_ns` (its last message before it is kept,
    /// as [`Kept::forget_before`] keeps it), and nothing else.
    pub(crate) fn forget_audio_before(&mut self, cutoff_ns: i64) {
        for raw in self.audio.values_mut() {
            let n = raw.msgs.partition_point(|m| m.0 < cutoff_ns);
            let n = n.min(raw.msgs.len().saturating_sub(1));
            let bytes: usize = raw.msgs[..n].iter().map(|m| m.2).sum();
            raw.msgs.drain(..n);
            raw.bytes.drain(..bytes);
        }
    }

    /// Forgets what a run that starts at `cutoff_ns` does not need: audio messages
    /// received before it, and of each pose topic's messages before it all but the last
    /// (a localiser that publishes only when the robot moves may have said its last word
    /// long before); transforms before `cutoff_ns - keep_tf_ns`.
    pub(crate) fn forget_before(&mut self, cutoff_ns: i64, keep_tf_ns: i64) {
        self.forget_audio_before(cutoff_ns);
        for (topic, raw) in &mut self.raw {
            let tf = self.kinds.get(topic) == Some(&Kind::Tf);
            if tf && topic.ends_with("_static") {
                // Sent once, latched: the robot's fixed frames.
                continue;
            }
            let cut = if tf {
                cutoff_ns.saturating_sub(keep_tf_ns)
            } else {
                cutoff_ns
            };
            let n = raw.partition_point(|m| m.0 < cut);
            let n = if tf { n } else { n.saturating_sub(1) };
            raw.drain(..n);
        }
    }

    pub(crate) fn take(&mut self, m: &format::Message<'_>, options: &ReadOptions) -> Result<()> {
        let topic = &m.connection.topic;
        let kind = Kind::of(&m.connection.msg_type);
        if let Some(k) = kind {
            self.encodings.insert(topic.clone(), m.connection.encoding);
            self.kinds.insert(topic.clone(), k);
        }
        match kind {
            Some(kind)
                if kind.is_audio() && options.audio_topic.as_ref().is_none_or(|t| t == topic) =>
            {
                let raw = self.audio.entry(topic.clone()).or_default();
                let error = |what: String| Error::Message {
                    topic: topic.clone(),
                    msg_type: m.connection.msg_type.clone(),
                    index: raw.msgs.len() + 1,
                    what,
                };
                let chunk = msg::audio(kind, m.connection.encoding, m.data).map_err(error)?;
                if let Some(f) = chunk.format.filter(|_| !chunk.data.is_empty()) {
                    match raw.embedded {
                        None => raw.embedded = Some(f),
                        Some(before) if before != f => {
                            return Err(error(format!(
                                "its format ({} channels at {} Hz, {}) is not the one before it \
                                 ({} channels at {} Hz, {})",
                                f.channels,
                                f.rate,
                                f.sample,
                                before.channels,
                                before.rate,
                                before.sample
                            )));
                        }
                        Some(_) => {}
                    }
                }
                raw.put(m.time_ns, chunk.stamp_ns, chunk.data);
            }
            // Another audio topic than the one named: not kept.
            Some(kind) if kind.is_audio() => {}
            // A map is republished as it grows: only the last is kept.
            Some(Kind::OccupancyGrid) => {
                self.raw
                    .insert(topic.clone(), vec![(m.time_ns, m.data.to_vec())]);
            }
            Some(_) => self
                .raw
                .entry(topic.clone())
                .or_default()
                .push((m.time_ns, m.data.to_vec())),
            None => {}
        }
        Ok(())
    }
}

fn message_error(topic: &TopicInfo, i: usize, what: String) -> Error {
    Error::Message {
        topic: topic.topic.clone(),
        msg_type: topic.msg_type.clone(),
        index: i + 1,
        what,
    }
}

#[cfg(test)]
mod tests;
