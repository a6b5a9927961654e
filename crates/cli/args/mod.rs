//! Command-line arguments (clap derive), and their conversion into the pipeline's
//! validated values ([`Settings`], [`SurveyInputs`]): ripgrep's two stages, so that the
//! library stays callable without a command line.

mod generated;
mod inputs;
mod robot;
mod survey;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

pub use generated::{DrawArgs, GeneratedArgs, ScenesCommand};
pub use inputs::AngleUnit;
pub use robot::{BagArgs, WatchArgs};
#[cfg(feature = "ros2")]
pub use robot::{Ros2Args, Ros2PlayArgs};
pub use survey::{CompareArgs, EvalArgs, FigureArgs, MapArgs, SslArgs};

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
        /// Instead of the folder's scenes, scenes drawn at random (`iasm scenes
        /// generate`): each rendered several times, mapped with every method and from true
        /// bearings, reported as a distribution per plan family and per array.
        #[command(flatten)]
        generated: GeneratedArgs,
    },
    /// Scenes drawn at random: floor plans of six families, sources, arrays and paths.
    Scenes {
        /// What to do with them.
        #[command(subcommand)]
        command: ScenesCommand,
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
