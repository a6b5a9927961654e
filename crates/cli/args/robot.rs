//! The arguments of the commands that read a robot's run as it was recorded or as it
//! happens: `bag`, `watch`, `ros2` and `ros2-play`, and how a run is read ([`RunArgs`]).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::inputs::{AngleUnit, ChannelList, SettingsArgs, parse_channels};
use super::survey::FigureArgs;

/// `iasm ros2`.
#[cfg(feature = "ros2")]
#[derive(Debug, Clone, Args)]
pub struct Ros2Args {
    /// The topics, the audio's format and the stop rules (as `iasm bag` takes them).
    #[command(flatten)]
    pub run: RunArgs,
    /// The settings.
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Seed of the particle filter.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the map as JSON here after every stop, and the final map at the end.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write every update to this MCAP file (written when the run ends).
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// A map of an earlier run through the same building (JSON of `iasm map --out`, `iasm
    /// watch --out` or this node, in frame `map`): after every stop, what changed against it
    /// (kept, moved, removed, added; `asm::diff`) is published on `/iasm/changes` and
    /// listed in the map JSON.
    #[arg(long, value_name = "FILE")]
    pub prior: Option<PathBuf>,
    /// The DDS domain (ROS_DOMAIN_ID).
    #[arg(long, env = "ROS_DOMAIN_ID", default_value_t = 0)]
    pub domain_id: u16,
    /// The node's name.
    #[arg(long, default_value = "iasm")]
    pub node_name: String,
    /// End the run when no message has arrived for this long (s), counted from the node's
    /// start when none ever came [default: only on Ctrl-C].
    #[arg(long, value_name = "S", value_parser = parse_seconds)]
    pub until_idle: Option<f64>,
    /// Keep audio at most this long (s) while no pose comes; older audio is dropped with a
    /// warning (a minute of six channels at 48 kHz is 35 MB).
    #[arg(long, value_name = "S", default_value_t = bag::live::PENDING_AUDIO_S, value_parser = parse_seconds)]
    pub pending_audio: f64,
    /// Take the time from /clock (rosgraph_msgs/Clock), as `ros2 bag play --clock`
    /// publishes it, instead of the system clock (the parameter use_sim_time).
    #[arg(long)]
    pub use_sim_time: bool,
    /// Where the node's save_map service writes the map (JSON).
    #[arg(long, value_name = "FILE", default_value = "iasm_map.json")]
    pub save_to: PathBuf,
    /// The `--ros-args` block (namespace, node name, remaps; its parameters are flags).
    #[arg(skip)]
    pub ros: super::ros::RosArgs,
    /// The command line of `iasm ros2` with every parameter as its flag, from which a
    /// parameter set while the node runs is parsed again.
    #[arg(skip)]
    pub command_line: Vec<std::ffi::OsString>,
}

/// `iasm ros2-play`.
#[cfg(feature = "ros2")]
#[derive(Debug, Clone, Args)]
pub struct Ros2PlayArgs {
    /// The ROS 2 bag (MCAP or SQLite; its folder or one of its files).
    pub bag: PathBuf,
    /// The DDS domain (ROS_DOMAIN_ID).
    #[arg(long, env = "ROS_DOMAIN_ID", default_value_t = 0)]
    pub domain_id: u16,
    /// Wait this long (s) for a subscriber on every topic before playing.
    #[arg(long = "wait", default_value_t = 10.0, value_name = "S")]
    pub wait_s: f64,
    /// Listen to the node's /iasm/source_poses and write the last sources heard here (JSON).
    #[arg(long, value_name = "FILE")]
    pub listen: Option<PathBuf>,
    /// With --listen: how long to go on listening after the bag is played (s); Ctrl-C
    /// ends the listening sooner (half a second later), and the sources heard are written.
    #[arg(long = "linger", default_value_t = 5.0, value_name = "S")]
    pub linger_s: f64,
    /// Publish /clock (rosgraph_msgs/Clock) at the bag's time and keep the messages'
    /// stamps as recorded, as `ros2 bag play --clock` does (for a node with
    /// use_sim_time), instead of moving them to now.
    #[arg(long)]
    pub clock: bool,
    /// The `--ros-args` block: `-r __ns:=/robot1` puts the bag's topics in that namespace
    /// (as if recorded relative to it), `-r from:=to` renames one.
    #[arg(skip)]
    pub ros: super::ros::RosArgs,
}

/// `iasm ros2-merge`.
#[cfg(feature = "ros2")]
#[derive(Debug, Clone, Args)]
pub struct Ros2MergeArgs {
    /// The robots' nodes whose stops to merge, fully qualified (`/robot1/iasm`)
    /// [default: every node that publishes iasm_msgs/msg/Stop, as discovery finds them].
    pub robots: Vec<String>,
    /// The mapper's settings (the robots localise; `[iasm]` and --num apply here).
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Seed of the particle filter.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The building's occupancy grid (nav_msgs/OccupancyGrid, in the frame of the robots'
    /// poses); "none" searches around the stops.
    #[arg(long, value_name = "TOPIC", default_value = "/map")]
    pub map_topic: String,
    /// Write the map as JSON here after every stop, and the final map at the end.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write every update to this MCAP file (written when the run ends).
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// The DDS domain (ROS_DOMAIN_ID).
    #[arg(long, env = "ROS_DOMAIN_ID", default_value_t = 0)]
    pub domain_id: u16,
    /// The node's name.
    #[arg(long, default_value = "iasm_merge")]
    pub node_name: String,
    /// End the run when no stop has arrived for this long (s), counted from the node's
    /// start when none ever came [default: only on Ctrl-C].
    #[arg(long, value_name = "S", value_parser = parse_seconds)]
    pub until_idle: Option<f64>,
    /// The `--ros-args` block (namespace, node name, remaps; its parameters are flags).
    #[arg(skip)]
    pub ros: super::ros::RosArgs,
}

/// `iasm ros2-call`.
#[cfg(feature = "ros2")]
#[derive(Debug, Clone, Args)]
pub struct Ros2CallArgs {
    /// The node, fully qualified (`/iasm`, `/robot1/mapper`).
    pub node: String,
    /// What to ask of it.
    #[command(subcommand)]
    pub what: Ros2CallWhat,
    /// The DDS domain (ROS_DOMAIN_ID).
    #[arg(long, env = "ROS_DOMAIN_ID", default_value_t = 0, global = true)]
    pub domain_id: u16,
    /// How long to wait for the answer (s).
    #[arg(long, default_value_t = 10.0, value_name = "S", value_parser = parse_seconds, global = true)]
    pub timeout: f64,
}

/// What `iasm ros2-call` asks of the node.
#[cfg(feature = "ros2")]
#[derive(Debug, Clone, clap::Subcommand)]
pub enum Ros2CallWhat {
    /// Its parameters' names (`ros2 param list`).
    List,
    /// A parameter's value (`ros2 param get`).
    Get {
        /// The parameter.
        name: String,
    },
    /// Sets a parameter (`ros2 param set`): the value is read as YAML (`8` an integer,
    /// `0.5` a double, `true` a boolean); the node's refusal, with its reason, exits 2.
    Set {
        /// The parameter.
        name: String,
        /// Its value.
        value: String,
    },
    /// Writes the current map to the node's save_to path (`~/save_map`).
    #[command(name = "save_map")]
    SaveMap,
    /// Prints the current map's JSON (`~/get_map`).
    #[command(name = "get_map")]
    GetMap,
    /// Forgets every stop (`~/clear_map`).
    #[command(name = "clear_map")]
    ClearMap,
}

/// `iasm bag`.
#[derive(Debug, Clone, Args)]
pub struct BagArgs {
    /// The bag: a ROS 1 .bag (format 2.0; chunks uncompressed, bz2 or lz4), or a ROS 2
    /// bag stored in MCAP (chunks uncompressed, zstd or lz4) or SQLite (.db3), compressed
    /// with zstd file by file (.mcap.zstd, .db3.zstd) or message by message or not at all:
    /// its folder or one of its files; a folder of ROS 1 bags that `rosbag record --split`
    /// wrote is read as one run.
    pub bag: PathBuf,
    /// The data set folder to write: audio/ (a WAV per stop), pose/poses.csv, stops.csv
    /// (each stop's times in the bag), map/ (the robot's map, when the bag holds one in the
    /// poses' frame), array.toml (with --array). Without it, nothing is written.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Replace the --out folder even if it is not empty and not an earlier output of iasm.
    #[arg(long)]
    pub force: bool,
    /// The topics, the audio's format and the stop rules.
    #[command(flatten)]
    pub run: RunArgs,
    /// The microphones that recorded the audio (a preset or an array file), written to
    /// array.toml so that every command on the data set uses them.
    #[arg(long)]
    pub array: Option<String>,
    /// Which channels of the audio are the array's microphones, in its order, counted from
    /// 1 (`2-5`); the WAVs hold those [default: every channel].
    #[arg(long, value_name = "LIST", value_parser = parse_channels)]
    pub channels: Option<ChannelList>,
    /// When the robot stood alone, its fans running and nobody else making a sound: from
    /// START to END seconds in the bag (as the stop table counts them, `3.0-8.5`). That
    /// audio is written as noise/robot.wav, the recording of the robot's own noise that
    /// every command then subtracts (see `ssl::noise`), and no stop is taken from it.
    #[arg(long, value_name = "START-END", value_parser = parse_window)]
    pub noise_window: Option<(f64, f64)>,
}

/// How a robot run is read, from a bag or live: which topics, the audio's format when the
/// run does not say it, and what a stop is.
#[derive(Debug, Clone, Args)]
pub struct RunArgs {
    /// The audio topic (audio_common_msgs/AudioData, AudioDataStamped or AudioStamped)
    /// [default: the bag's one audio topic].
    #[arg(long, value_name = "TOPIC")]
    pub audio_topic: Option<String>,
    /// The topic of the poses to map in (nav_msgs/Odometry, geometry_msgs/PoseStamped,
    /// PoseWithCovarianceStamped or Pose2D), or /tf for the chain of transforms from the
    /// tree's root (map) to the robot's base frame [default: the bag's one pose topic, or,
    /// beside odometry, the one other: a localiser's, in the map's frame; /tf when the bag
    /// has no pose topic].
    #[arg(long, value_name = "TOPIC")]
    pub pose_topic: Option<String>,
    /// The odometry topic to find the stops by, when the pose topic is a localiser's that
    /// publishes only as the robot moves [default: the bag's one nav_msgs/Odometry topic
    /// beside a pose topic of another type]; "none" finds them by the pose topic.
    #[arg(long, value_name = "TOPIC")]
    pub odom_topic: Option<String>,
    /// The robot's base frame, for poses from /tf [default: base_footprint, else
    /// base_link].
    #[arg(long, value_name = "FRAME")]
    pub base_frame: Option<String>,
    /// The robot's map (nav_msgs/OccupancyGrid), written to map/ when it is in the poses'
    /// frame [default: the bag's one grid topic, or /map]; "none" for no map.
    #[arg(long, value_name = "TOPIC")]
    pub map_topic: Option<String>,
    /// The audio's channels, when the bag has no audio_common_msgs/AudioInfo (give
    /// --sample-rate too).
    #[arg(long, value_name = "C", requires = "sample_rate")]
    pub audio_channels: Option<u16>,
    /// The audio's sample rate (Hz), when the bag has no AudioInfo (give --audio-channels
    /// too).
    #[arg(long, value_name = "HZ", requires = "audio_channels")]
    pub sample_rate: Option<u32>,
    /// The audio's sample format with --audio-channels: U8, S8, S16LE, S24LE, S32LE, F32LE or
    /// F64LE.
    #[arg(
        long,
        value_name = "FORMAT",
        default_value = "S16LE",
        requires = "audio_channels"
    )]
    pub sample_format: String,
    /// How far the robot may move within a stop (m).
    #[arg(long, value_name = "M", default_value_t = bag::StopOptions::default().radius_m)]
    pub still_radius: f64,
    /// How far it may turn within a stop (degrees).
    #[arg(long, value_name = "DEG", default_value_t = bag::StopOptions::default().turn_deg)]
    pub still_turn: f64,
    /// Left out at the start of each stop, as the robot settles (s).
    #[arg(long, value_name = "S", default_value_t = bag::StopOptions::default().settle_s)]
    pub settle: f64,
    /// Left out at the end of each stop, as the motors start (s).
    #[arg(long, value_name = "S", default_value_t = bag::StopOptions::default().end_margin_s)]
    pub end_margin: f64,
    /// The shortest stop kept (s of audio after the margins).
    #[arg(long, value_name = "S", default_value_t = bag::StopOptions::default().min_listen_s)]
    pub min_listen: f64,
}

impl RunArgs {
    /// The topics and format to read.
    ///
    /// # Errors
    /// A `--sample-format` that is not one.
    pub fn read_options(&self) -> anyhow::Result<bag::ReadOptions> {
        use anyhow::Context;
        // A topic option: "none" is the empty name, which asks for no topic.
        let none_is_empty = |t: &str| {
            if t == "none" {
                String::new()
            } else {
                t.to_owned()
            }
        };
        let format = match (self.audio_channels, self.sample_rate) {
            (Some(channels), Some(sample_rate)) => Some(bag::AudioFormat {
                channels,
                sample_rate,
                sample: self.sample_format.parse().context("--sample-format")?,
            }),
            _ => None,
        };
        Ok(bag::ReadOptions {
            audio_topic: self.audio_topic.clone(),
            pose_topic: self.pose_topic.clone(),
            odom_topic: self.odom_topic.as_deref().map(none_is_empty),
            map_topic: self.map_topic.as_deref().map(none_is_empty),
            base_frame: self.base_frame.clone(),
            format,
        })
    }

    /// The stop rules, checked.
    ///
    /// # Errors
    /// Options [`bag::StopOptions::validate`] refuses.
    pub fn stop_options(&self) -> anyhow::Result<bag::StopOptions> {
        use anyhow::Context;
        let stops = bag::StopOptions {
            radius_m: self.still_radius,
            turn_deg: self.still_turn,
            settle_s: self.settle,
            end_margin_s: self.end_margin,
            min_listen_s: self.min_listen,
        };
        stops.validate().context("stop options")?;
        Ok(stops)
    }
}

/// A `--noise-window`: two times in seconds, `START-END` (or `START,END`), START before END.
fn parse_window(text: &str) -> Result<(f64, f64), String> {
    let (a, b) = text
        .split_once(',')
        .or_else(|| text.split_once('-'))
        .ok_or_else(|| format!("{text:?} is not START-END (seconds in the bag)"))?;
    let num = |v: &str| {
        v.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{v:?} is not a time in seconds"))
    };
    let (a, b) = (num(a)?, num(b)?);
    if a < b {
        Ok((a, b))
    } else {
        Err(format!("{text:?}: the window must end after it starts"))
    }
}

/// `iasm watch`.
#[derive(Debug, Clone, Args)]
pub struct WatchArgs {
    /// The data set folder being written: map/ (needed from the start), audio/*.wav (one
    /// per stop, natural order), pose/ (a table with a row per stop), src_gt* (optional).
    pub dir: PathBuf,
    /// Pose table to follow instead of the first one in DIR/pose/ (the formats of `iasm map
    /// --poses`).
    #[arg(long, value_name = "FILE")]
    pub poses: Option<PathBuf>,
    /// Unit of theta in the pose table.
    #[arg(long, value_enum, default_value_t = AngleUnit::Deg)]
    pub theta_unit: AngleUnit,
    /// Seed of the particle filter.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the map as JSON here after every stop (atomically: a reader never sees half a
    /// file).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Draw the map here after every stop: PNG or SVG by the extension (atomically).
    #[arg(long, value_name = "FILE", visible_alias = "figure")]
    pub png: Option<PathBuf>,
    /// Write the map's growth as ROS 2 messages to this MCAP file: one update per stop,
    /// stamped, so that a player shows the map grow (see `iasm map --mcap`); written whole
    /// when the run ends.
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// How the map is drawn.
    #[command(flatten)]
    pub figure: FigureArgs,
    /// End after this many stops (default: on Ctrl-C; with --replay, at the data set's end).
    #[arg(long, value_name = "K")]
    pub stops: Option<usize>,
    /// Replay the finished data set in DIR stop by stop, as if recorded live.
    #[arg(long)]
    pub replay: bool,
    /// Write the curve here: one CSV row per stop (stop, file, DoAs, sources, OSPA and its
    /// parts when the truth is known, ms of SSL and of mapping, whether the stop started a
    /// full map, and the ms of the full map it took in, which ran beside the stops).
    #[arg(long, value_name = "FILE")]
    pub curve: Option<PathBuf>,
    /// Plot the curve here (PNG or SVG) [default: beside --curve, as .svg].
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// How often to look for new files when no notification comes (ms).
    #[arg(long, default_value_t = 500, value_name = "MS")]
    pub poll_ms: u64,
    /// A recording that stays unreadable and unchanged this long is an error (s).
    #[arg(long, default_value_t = 30.0, value_name = "S")]
    pub give_up_s: f64,
    /// OSPA cutoff c (m), when the truth is known.
    #[arg(long, default_value_t = 1.0, value_parser = super::inputs::parse_ospa_c)]
    pub ospa_c: f64,
    /// OSPA order p.
    #[arg(long, default_value_t = 1.0, value_parser = super::inputs::parse_ospa_p)]
    pub ospa_p: f64,
    /// Refine each source by bearing least squares (see `iasm map --refine`).
    #[arg(long)]
    pub refine: bool,
    /// Map from scratch at every stop, as the authors' online program does (a baseline to
    /// measure the incremental mapper against).
    #[arg(long)]
    pub recompute: bool,
    /// The settings.
    #[command(flatten)]
    pub settings: SettingsArgs,
}

/// A duration in seconds: finite and not negative (an idle time of NaN would never end a
/// run; of infinity, only Ctrl-C would).
#[cfg(feature = "ros2")]
fn parse_seconds(text: &str) -> Result<f64, String> {
    let s: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if s.is_finite() && s >= 0.0 {
        Ok(s)
    } else {
        Err(format!("{s} is not a duration in seconds"))
    }
}
