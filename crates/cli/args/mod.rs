//! Command-line arguments (clap derive), and their conversion into the pipeline's
//! validated values ([`Settings`], [`SurveyInputs`]): ripgrep's two stages, so that the
//! library stays callable without a command line.

mod diff;
mod generated;
mod inputs;
mod robot;
#[cfg(feature = "ros2")]
pub mod ros;
mod survey;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

pub use diff::DiffArgs;
pub use generated::{DrawArgs, GeneratedArgs, ScenesCommand};
pub use inputs::AngleUnit;
#[cfg(feature = "ros2")]
pub use inputs::SettingsArgs;
pub use robot::{BagArgs, WatchArgs};
#[cfg(feature = "ros2")]
pub use robot::{Ros2Args, Ros2CallArgs, Ros2CallWhat, Ros2MergeArgs, Ros2PlayArgs};
pub use survey::{CompareArgs, EvalArgs, FigureArgs, MapArgs, SslArgs};

/// The command line `argv` (the program's name first) parsed, `iasm ros2`'s and `iasm
/// ros2-play`'s `--ros-args` block read ([`ros`]): its parameters become the command's
/// flags, its names and remaps go to the command.
///
/// # Errors
/// clap's, or the ROS block's (unknown options, a parameter that is no setting, a
/// parameters file that cannot be read), as a clap error that exits with status 2.
#[cfg(feature = "ros2")]
pub fn parse_from(argv: Vec<std::ffi::OsString>) -> Result<Cli, clap::Error> {
    use clap::CommandFactory;
    let ros_err = |e: anyhow::Error| {
        clap::Error::raw(clap::error::ErrorKind::InvalidValue, format!("{e:#}\n"))
    };
    let (argv, tokens) = ros::split(argv).map_err(ros_err)?;
    let Some(tokens) = tokens else {
        let mut cli = Cli::try_parse_from(&argv)?;
        if let Command::Ros2(a) = &mut cli.command {
            a.command_line = argv;
        }
        return Ok(cli);
    };
    let r = ros::RosArgs::parse(&tokens).map_err(ros_err)?;
    let (sub, node) = match Cli::try_parse_from(&argv)?.command {
        Command::Ros2(a) => ("ros2", a.node_name),
        Command::Ros2Play(_) => ("ros2-play", play_node_name().to_owned()),
        Command::Ros2Merge(a) => ("ros2-merge", a.node_name),
        _ => {
            return Err(ros_err(anyhow::anyhow!(
                "--ros-args is read by iasm ros2, ros2-merge and ros2-play only"
            )));
        }
    };
    let params = r.parameters(&r.fully_qualified(&node)).map_err(ros_err)?;
    let cmd = Cli::command();
    let flags =
        ros::to_flags(&params, cmd.find_subcommand(sub).expect("a subcommand")).map_err(ros_err)?;
    let mut argv = argv;
    argv.extend(flags);
    let mut cli = Cli::try_parse_from(&argv)?;
    for i in &r.ignored {
        eprintln!("note: --ros-args {i}: accepted, not used by iasm");
    }
    match &mut cli.command {
        Command::Ros2(a) => {
            a.ros = r;
            a.command_line = argv;
        }
        Command::Ros2Play(a) => a.ros = r,
        Command::Ros2Merge(a) => a.ros = r,
        _ => unreachable!("checked above"),
    }
    Ok(cli)
}

/// The node name of `iasm ros2-play`.
#[cfg(feature = "ros2")]
#[must_use]
pub const fn play_node_name() -> &'static str {
    "iasm_play"
}

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
    /// Two maps of one building compared (say last week's and today's): the sources kept,
    /// moved, removed and added, each with its distance and a confidence from the maps'
    /// covariances; as a table, JSON and a figure of both maps.
    Diff(DiffArgs),
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
    /// The building's map from several robots' stops, live: subscribes to each robot
    /// node's ~/stops (poses and DoAs, no audio) and publishes the map of them all on its
    /// own topics; Ctrl-C ends the run with its final map.
    #[cfg(feature = "ros2")]
    Ros2Merge(Ros2MergeArgs),
    /// Ask a running node: list, get or set its parameters, save, print or clear its map
    /// (what `ros2 param` and `ros2 service call` do, with no ROS installed).
    #[cfg(feature = "ros2")]
    Ros2Call(Ros2CallArgs),
}
