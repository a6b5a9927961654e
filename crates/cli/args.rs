//! Command-line arguments (clap derive), and their conversion into the pipeline's
//! validated values ([`Settings`], [`SurveyInputs`]): ripgrep's two stages, so that the
//! library stays callable without a command line.

use std::path::PathBuf;

use anyhow::{Context, Result};
use asm::{Profile, Variant};
use clap::{Args, Parser, Subcommand, ValueEnum};
use ssl::{Method, Pooling};

use crate::pipeline::SurveyInputs;
use crate::settings::Settings;

/// iasm: from a robot's multichannel recordings to a map of the sound sources around it.
#[derive(Debug, Parser)]
#[command(name = "iasm", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands. (Parsed once per process: the size difference between variants is
/// irrelevant, so they are not boxed.)
#[derive(Debug, Subcommand)]
#[allow(clippy::large_enum_variant)]
pub enum Command {
    /// The whole pipeline on a built-in simulated scene: ten talkers, a robot driving
    /// between them; prints the map against the truth and draws it.
    Demo {
        /// Seed of the scene's signals, noise and particle filter.
        #[arg(long, default_value_t = 4)]
        seed: u64,
        /// Where to draw the map: PNG or SVG by the file's extension.
        #[arg(long, default_value = "iasm-demo.png")]
        png: PathBuf,
        /// Also write the map as ROS 2 messages to this MCAP file (see `iasm map --mcap`).
        #[arg(long, value_name = "FILE")]
        mcap: Option<PathBuf>,
        /// How the map is drawn.
        #[command(flatten)]
        figure: FigureArgs,
    },
    /// Directions of arrival from multichannel WAV files (or a whole data set).
    Ssl(SslArgs),
    /// Render a scene file (room, sources, array, trajectory) into a data set folder.
    Simulate {
        /// The scene (TOML).
        scene: PathBuf,
        /// The data set folder to write.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Worker threads, one stop each (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Replace the --out folder even if it is not empty and not an earlier output of
        /// iasm simulate (an earlier output is always replaced whole).
        #[arg(long)]
        force: bool,
    },
    /// The synthetic-room regression suite: simulate, localise and map every scene in a
    /// folder and check its thresholds.
    Regress {
        /// Folder of scene files.
        #[arg(default_value = "fixtures/rooms")]
        dir: PathBuf,
        /// A settings file (as for `map`); each method and each scene's N replace its own.
        #[arg(long, value_name = "FILE")]
        config: Option<PathBuf>,
        /// Map every scene with this N instead of its own (3, or 4 beyond three sources),
        /// to see how the pipeline holds when N is set higher or lower; the scenes'
        /// thresholds were set for their own N and are not judged then.
        #[arg(long, value_name = "N")]
        num: Option<usize>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Map the sound sources with I-ASM from DoA tables or raw audio.
    Map(MapArgs),
    /// The paper's Monte Carlo evaluation: OSPA of CA, WS and WDP over many seeds.
    Eval(EvalArgs),
    /// Every SSL method side by side on one data set: DoA score, errors by distance,
    /// recall, map OSPA over many seeds, speed; the published tables as extra rows.
    Compare(CompareArgs),
    /// Map while the robot records: follow a data set folder as recordings and poses
    /// appear, localise each new recording and update the map stop by stop; or replay a
    /// finished data set as if recorded live (--replay) and write the OSPA-per-stop curve.
    Watch(WatchArgs),
    /// A robot run recorded in a ROS bag made a data set: the stops at which it stood
    /// still, one WAV and one pose each, in the published layout for ssl, map and eval;
    /// without --out, what the bag holds and the stops it finds.
    Bag(BagArgs),
    /// The live node: subscribes to a ROS 2 robot's audio, poses and map, localises each
    /// stop as the robot leaves it, and publishes the map (markers, rays, path, poses)
    /// after every stop; Ctrl-C ends the run with its final map.
    #[cfg(feature = "ros2")]
    Ros2(Ros2Args),
    /// Publish a recorded ROS 2 bag on its topics at its pace, stamps moved to now, as the
    /// robot published it (to try the node without a robot).
    #[cfg(feature = "ros2")]
    Ros2Play(Ros2PlayArgs),
}

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
    /// The DDS domain (ROS_DOMAIN_ID).
    #[arg(long, env = "ROS_DOMAIN_ID", default_value_t = 0)]
    pub domain_id: u16,
    /// The node's name.
    #[arg(long, default_value = "iasm")]
    pub node_name: String,
    /// End the run when no message has arrived for this long (s) [default: only on Ctrl-C].
    #[arg(long, value_name = "S")]
    pub until_idle: Option<f64>,
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
    /// parts when the truth is known, ms of SSL and of mapping, whether a full map ran).
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
    #[arg(long, default_value_t = 1.0)]
    pub ospa_c: f64,
    /// OSPA order p.
    #[arg(long, default_value_t = 1.0)]
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

/// `iasm compare`.
#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    /// A data set folder in the published layout, with ground truth (src_gt*).
    #[arg(long, value_name = "DIR")]
    pub dataset: PathBuf,
    /// The methods: all, or a comma-separated list (gcc-phat, mvdr, srp-phat, music,
    /// normmusic, tops, cssm, waves).
    #[arg(long, default_value = "all")]
    pub methods: String,
    /// Maps per method (seeds seed..seed + runs).
    #[arg(long, default_value_t = 20)]
    pub runs: usize,
    /// The first seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write report.json, report.csv and the figures (ospa.svg, error_by_distance.svg,
    /// maps.svg) into this folder (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Without an occupancy map in the data set: how far from the stops to search for
    /// sources (m; default 3), as for `map`.
    #[arg(long, value_name = "M")]
    pub open_margin: Option<f64>,
    /// Also say, per method, why the sources within 3 m that no DoA found were missed (no
    /// peak there, N, the thresholds) and what N raised to 4N would add, as `iasm ssl
    /// --score --rules` does: six more localisations per recording and method.
    #[arg(long)]
    pub rules: bool,
    /// A DoA table of another tool on the same recordings (one row per recording in the
    /// audio's order, N azimuths in degrees in the array frame, strongest first; CSV or
    /// .xlsx, as `iasm ssl --out` writes and `scripts/pra_doa_tables.py` writes for
    /// pyroomacoustics' methods): a row beside ours, scored and mapped the same way.
    /// Repeatable; the row is named after the file.
    #[arg(long = "table", value_name = "FILE")]
    pub tables: Vec<PathBuf>,
    /// The settings (the method is each row's own).
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Output and metric.
    #[command(flatten)]
    pub report: ReportArgs,
}

/// The settings every command reads the same way: one file, then the flags that were given.
#[derive(Debug, Clone, Default, Args)]
pub struct SettingsArgs {
    /// A settings file (TOML): `[ssl]` (the `ssl::SslConfig` fields), `[iasm]` (the
    /// `asm::IasmConfig` fields), `array`, `channels` and `noise`. Flags given here
    /// override it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Microphone array: a preset (iasm6, respeaker4, respeaker6, uma8) or a TOML/JSON
    /// file [default: iasm6, or the settings file's].
    #[arg(long)]
    pub array: Option<String>,
    /// Which channels of each WAV are the array's microphones, in the array's order,
    /// counted from 1: a list and ranges, `2-5` or `2,3,4,5` (a ReSpeaker 4-mic's
    /// 6-channel firmware records its microphones on channels 2-5) [default: every
    /// channel, or the settings file's `channels`].
    #[arg(long, value_name = "LIST", value_parser = parse_channels)]
    pub channels: Option<ChannelList>,
    /// A recording of the robot alone (WAV: its fans running, no other source, a few
    /// seconds, the same microphones and channels as the recordings): the robot's own
    /// noise is subtracted from every statistic of the SSL (see `ssl::noise`) [default:
    /// the settings file's `noise`, or the one WAV in the data set's noise/ folder].
    #[arg(long, value_name = "WAV")]
    pub noise: Option<PathBuf>,
    /// Angular-spectrum method: gcc-phat, mvdr, srp-phat, music, normmusic, tops, cssm or waves [default:
    /// mvdr, or the settings file's].
    #[arg(long)]
    pub method: Option<Method>,
    /// N, the DoAs per stop, strongest first, for the SSL and the mapper alike
    /// [default: 4, or the settings file's].
    #[arg(long, value_name = "N")]
    pub num: Option<usize>,
    /// Lower edge of the analysis band (Hz).
    #[arg(long)]
    pub fmin: Option<f64>,
    /// Upper edge of the analysis band (Hz).
    #[arg(long)]
    pub fmax: Option<f64>,
    /// Frames per pooling block.
    #[arg(long)]
    pub block_frames: Option<usize>,
    /// Block pooling: auto (the default: the mean for a recording whose sound is steady and
    /// noise-like in every octave, max for any other; see `ssl::steady`), max or mean.
    #[arg(long)]
    pub pooling: Option<Pooling>,
    /// With max pooling: keep the mean of each direction's K largest block values
    /// (1, the default, is the plain maximum; see `ssl::SslConfig::pool_top`).
    #[arg(long, value_name = "K")]
    pub pool_top: Option<usize>,
    /// With max pooling: place each DoA that was the strongest direction of a block at the
    /// peak of the mean of its best SHARE of the blocks, within half the minimum
    /// separation (0 keeps the pooled peak's azimuth; default 0.25; see
    /// `ssl::SslConfig::placement_share`).
    #[arg(long, value_name = "SHARE")]
    pub placement_share: Option<f64>,
    /// Refine each weaker DoA of a row with the stronger ones projected out (deflation),
    /// whatever the array [default: on for a compact array, whose far-field distance at
    /// the band's top is under 1 m, such as a ReSpeaker; see `ssl::SslConfig::deflate`]
    #[arg(long, conflicts_with = "no_deflate")]
    pub deflate: bool,
    /// Never deflate, not even for a compact array (see --deflate).
    #[arg(long)]
    pub no_deflate: bool,
    /// I-ASM profile: paper (the paper's algorithm exactly, Table I) or robust (bearing
    /// refinement, three observing stops per source, a vote for missed sources, no source
    /// on the robot's path, contradicted by stops that heard nothing, heard through a
    /// wall as another's image, or made of another's reflections in the map's walls)
    /// [default: robust, or the settings file's].
    #[arg(long)]
    pub profile: Option<Profile>,
}

impl SettingsArgs {
    /// The settings file (or the defaults) with the given flags applied, validated.
    ///
    /// # Errors
    /// An unreadable or refused file, or a refused value.
    pub fn settings(&self) -> Result<Settings> {
        let mut s = Settings::load_with(self.config.as_deref(), self.profile)?;
        if let Some(a) = &self.array {
            s.array = Some(a.clone());
        }
        if let Some(ChannelList(c)) = &self.channels {
            s.channels = Some(c.clone());
        }
        if let Some(n) = &self.noise {
            s.noise = Some(n.clone());
        }
        if let Some(m) = self.method {
            s.ssl.method = m;
        }
        if let Some(n) = self.num {
            s.set_num(n);
        }
        if let Some(v) = self.fmin {
            s.ssl.fmin_hz = v;
        }
        if let Some(v) = self.fmax {
            s.ssl.fmax_hz = v;
        }
        if let Some(v) = self.block_frames {
            s.ssl.block_frames = v;
        }
        if let Some(v) = self.pooling {
            s.ssl.pooling = v;
        }
        if let Some(v) = self.pool_top {
            s.ssl.pool_top = v;
        }
        if let Some(v) = self.placement_share {
            s.ssl.placement_share = v;
        }
        if self.deflate {
            s.ssl.deflate = Some(true);
        }
        if self.no_deflate {
            s.ssl.deflate = Some(false);
        }
        s.validate().with_context(|| match &self.config {
            Some(p) => format!("settings {} with the command's flags", p.display()),
            None => "the command's flags".to_owned(),
        })?;
        Ok(s)
    }
}

/// The unit of theta in a pose table.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ValueEnum)]
pub enum AngleUnit {
    /// Degrees.
    #[default]
    #[value(alias = "degrees")]
    Deg,
    /// Radians.
    #[value(alias = "radians")]
    Rad,
}

/// Where the mapping inputs come from (shared by `map` and `eval`).
#[derive(Debug, Clone, Args)]
pub struct InputArgs {
    /// A data set folder in the published layout (map/, pose/, audio/, azimuth/, src_gt*).
    #[arg(long, value_name = "DIR")]
    pub dataset: Option<PathBuf>,
    /// ROS occupancy map YAML (overrides the data set's). Without one (and without a
    /// map/ folder in the data set) the sources are searched within --open-margin of the
    /// stops.
    #[arg(long, value_name = "YAML")]
    pub map: Option<PathBuf>,
    /// Without an occupancy map: how far from the stops to search for sources (m; default
    /// 3, a room's half-width). The particles per round grow with the region's area.
    #[arg(long, value_name = "M")]
    pub open_margin: Option<f64>,
    /// Pose table, one row per stop, CSV or .xlsx (overrides the data set's): plain x, y,
    /// theta columns, or a CSV whose header names them as ROS exports do: x and y (or
    /// `*position.x`, `*position.y`), and yaw or theta_rad (radians), theta_deg (degrees),
    /// theta (--theta-unit), or a quaternion qx, qy, qz, qw (or `*orientation.x..w`);
    /// other columns are ignored.
    #[arg(long, value_name = "FILE")]
    pub poses: Option<PathBuf>,
    /// Unit of theta in the pose table.
    #[arg(long, value_enum, default_value_t = AngleUnit::Deg)]
    pub theta_unit: AngleUnit,
    /// DoA table: azimuths per stop (degrees, array frame, strongest first), CSV or .xlsx;
    /// a wider table than N maps its first N columns.
    #[arg(long, value_name = "TABLE", conflicts_with = "audio")]
    pub doas: Option<PathBuf>,
    /// Folder of WAV recordings, one per stop, localised with the SSL settings (default:
    /// the data set's audio/ when no --doas is given).
    #[arg(long, value_name = "DIR")]
    pub audio: Option<PathBuf>,
    /// Ground-truth source positions (overrides the data set's src_gt*).
    #[arg(long, value_name = "FILE")]
    pub truth: Option<PathBuf>,
    /// One continuous multichannel WAV instead of one per stop: a window of --window
    /// seconds is cut from each pose's time, and the pose table has a time per row (plain
    /// t, x, y, theta columns, or a header naming t/time/stamp/%time beside the pose
    /// columns above).
    #[arg(long, value_name = "WAV", conflicts_with_all = ["doas", "audio"])]
    pub recording: Option<PathBuf>,
    /// Seconds of a continuous recording used from each pose's time.
    #[arg(long, value_name = "S", default_value_t = 3.0, requires = "recording")]
    pub window: f64,
    /// Refine each source by bearing least squares over the DoAs it explains (not in the
    /// paper; see `asm::IasmConfig::refine`).
    #[arg(long)]
    pub refine: bool,
    /// The settings.
    #[command(flatten)]
    pub settings: SettingsArgs,
}

impl InputArgs {
    /// The settings, with `--refine` when given.
    ///
    /// # Errors
    /// As [`SettingsArgs::settings`].
    pub fn settings(&self) -> Result<Settings> {
        let mut s = self
            .settings
            .settings()?
            .with_dataset_array(self.dataset.as_deref())
            .with_dataset_noise(self.dataset.as_deref())?;
        s.iasm.refine |= self.refine;
        Ok(s)
    }

    /// Where the survey comes from.
    pub fn survey_inputs(&self) -> SurveyInputs {
        SurveyInputs {
            dataset: self.dataset.clone(),
            map: self.map.clone(),
            poses: self.poses.clone(),
            theta_in_radians: self.theta_unit == AngleUnit::Rad,
            doas: self.doas.clone(),
            audio: self.audio.clone(),
            truth: self.truth.clone(),
            recording: self.recording.clone(),
            window_s: self.window,
            open_margin_m: self.open_margin,
        }
    }
}

/// How `map` and `eval` report: the format and the OSPA metric's parameters.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// OSPA order p.
    #[arg(long, default_value_t = 1.0)]
    pub ospa_p: f64,
    /// OSPA cutoff c (m).
    #[arg(long, default_value_t = 1.0)]
    pub ospa_c: f64,
}

/// `iasm map`.
#[derive(Debug, Clone, Args)]
pub struct MapArgs {
    /// The inputs.
    #[command(flatten)]
    pub input: InputArgs,
    /// Variant: ca (full I-ASM), ws (weighted sum) or wdp (no distance penalty)
    /// [default: ca, or the settings file's].
    #[arg(long)]
    pub variant: Option<Variant>,
    /// Seed of the particle filter.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the map as JSON here.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the sources as CSV here.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write the map as ROS 2 messages to this MCAP file (frame `map`): source markers with
    /// their 2-sigma ellipses and labels, each stop's DoA rays, the trajectory, the occupancy
    /// map and the sources as poses; Foxglove opens it, `ros2 bag play` sends it to RViz.
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// Draw the map here: PNG or SVG by the file's extension (axes in metres, legend, title).
    #[arg(long, value_name = "FILE", visible_alias = "figure")]
    pub png: Option<PathBuf>,
    /// Write the truth moved into the map's frame here (the inverse of the best similarity
    /// transform of the map onto the truth; the src_gt text format), to score DoAs against
    /// with `iasm ssl --score --truth FILE`: where the poses' and the truth's frames
    /// disagree, the DoAs are then judged in the frame they were heard in. Fit it to a map
    /// from other DoAs than those you score (e.g. a published table), or the score is
    /// partly of the fit.
    #[arg(long, value_name = "FILE")]
    pub write_aligned_truth: Option<PathBuf>,
    /// Also say why the map holds what it holds: the DoAs each source explains (stop,
    /// azimuth, miss), the DoAs no source explains, and, with ground truth, where the DoAs
    /// of each true source the map missed went (unheard, taken by another source, or
    /// left unexplained). In JSON: the `explain` object
    #[arg(long)]
    pub explain: bool,
    /// How the map is drawn.
    #[command(flatten)]
    pub figure: FigureArgs,
    /// Output and metric.
    #[command(flatten)]
    pub report: ReportArgs,
}

/// How a map figure is drawn.
#[derive(Debug, Clone, Copy, Args)]
pub struct FigureArgs {
    /// Draw the whole occupancy map [default: crop to the trajectory and the sources, with a
    /// margin].
    #[arg(long)]
    pub full_map: bool,
    /// Width of the figure in pixels (the height follows the region's aspect; text scales
    /// with it: 2000 for print at 200 dpi and 10 inches).
    #[arg(long, value_name = "PX", default_value_t = 1000,
          value_parser = clap::value_parser!(u32).range(200..=8000))]
    pub figure_width: u32,
}

/// `iasm eval`.
#[derive(Debug, Clone, Args)]
pub struct EvalArgs {
    /// The inputs.
    #[command(flatten)]
    pub input: InputArgs,
    /// Runs per variant (seeds seed..seed+runs).
    #[arg(long, default_value_t = 50)]
    pub runs: usize,
    /// First seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output and metric.
    #[command(flatten)]
    pub report: ReportArgs,
    /// Exit with status 1 if CA's mean OSPA is above this (m).
    #[arg(long, value_name = "M")]
    pub max_mean_ospa: Option<f64>,
    /// Exit with status 1 if CA's matched sources lie further than this (m, mean over the
    /// runs) from the truth after each map's best similarity transform onto it, or if no
    /// run matched three sources: the map's own accuracy, whatever the poses' and the
    /// truth's frames.
    #[arg(long, value_name = "M")]
    pub max_aligned: Option<f64>,
    /// Exit with status 1 unless WS and WDP both have a higher mean OSPA than CA.
    #[arg(long)]
    pub expect_ablation: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

/// `iasm ssl`.
#[derive(Debug, Clone, Args)]
pub struct SslArgs {
    /// WAV files to localise (one recording each).
    #[arg(required_unless_present = "dataset", conflicts_with = "dataset")]
    pub files: Vec<PathBuf>,
    /// A data set folder: localises every `DIR/audio/*.wav` in natural name order.
    #[arg(long, value_name = "DIR")]
    pub dataset: Option<PathBuf>,
    /// The settings.
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// With --dataset: write the DoA table (one row per recording, N azimuths in degrees,
    /// array frame, empty cells where fewer peaks were found) to this CSV file.
    #[arg(
        long,
        value_name = "FILE",
        requires = "dataset",
        conflicts_with = "files"
    )]
    pub out: Option<PathBuf>,
    /// With --out: write a header line first.
    #[arg(long, requires = "out", conflicts_with = "files")]
    pub header: bool,
    /// With --dataset: score the DoAs against the data set's poses and ground truth (and
    /// score the published tables in `azimuth/` beside them).
    #[arg(long, requires = "dataset", conflicts_with = "files")]
    pub score: bool,
    /// With --score: a DoA within this many degrees of a true source's bearing is a hit.
    #[arg(long, default_value_t = 5.0, value_name = "DEG")]
    pub tol_deg: f64,
    /// With --score: also print where the DoAs fail, for ours and the published tables:
    /// errors by the source's distance from the robot, bias towards the heading axis, and
    /// the recall of sources within 3 m.
    #[arg(long, requires = "score")]
    pub by_distance: bool,
    /// With --score: also print which of the SSL's rules left out each source within 3 m
    /// that no DoA found (no peak there at all, N, height, coherence, prominence,
    /// sidelobe, significance), and which let in each DoA that found no source (height,
    /// block votes, incoherence), and what N raised to 4N would add. With --json, every
    /// missed pair is listed with its stop, source, distance and reason. Localises every
    /// recording six times, each time with one rule off (see `iasm::rules`).
    #[arg(long, requires = "score")]
    pub rules: bool,
    /// With --score: ground-truth source positions to score against instead of the data
    /// set's src_gt* (e.g. the truth moved into the poses' frame by `iasm map
    /// --write-aligned-truth`).
    #[arg(long, value_name = "FILE", requires = "score")]
    pub truth: Option<PathBuf>,
    /// With --score: exit with status 1 if the score is below this.
    #[arg(long, value_name = "SCORE", requires = "score")]
    pub min_score: Option<f64>,
    /// With --score: exit with status 1 if the score is below that of the published table
    /// of the same method (`azimuth/*<METHOD>*`).
    #[arg(long, requires = "score")]
    pub beat_published: bool,
    /// Worker threads for --dataset (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

/// The channels of `--channels`, counted from 1.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelList(pub Vec<usize>);

/// A `--channels` list: channels counted from 1, single or as ranges (`2-5`, `1,3-4`).
fn parse_channels(text: &str) -> Result<ChannelList, String> {
    let number = |t: &str| {
        t.trim()
            .parse::<usize>()
            .ok()
            .filter(|&c| c >= 1)
            .ok_or_else(|| format!("`{t}` is not a channel number (counted from 1)"))
    };
    let mut out = Vec::new();
    for part in text.split(',') {
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (number(a)?, number(b)?);
                if a > b {
                    return Err(format!("`{part}` is an empty range"));
                }
                out.extend(a..=b);
            }
            None => out.push(number(part)?),
        }
    }
    Ok(ChannelList(out))
}

#[cfg(test)]
mod channel_list_tests {
    use super::*;

    #[test]
    fn channel_lists_take_numbers_and_ranges_from_1() {
        assert_eq!(parse_channels("2-5"), Ok(ChannelList(vec![2, 3, 4, 5])));
        assert_eq!(
            parse_channels("1, 3-4,6"),
            Ok(ChannelList(vec![1, 3, 4, 6]))
        );
        assert!(parse_channels("0-3").unwrap_err().contains("`0`"));
        assert!(parse_channels("5-2").unwrap_err().contains("empty range"));
        assert!(parse_channels("a").is_err());
    }
}
