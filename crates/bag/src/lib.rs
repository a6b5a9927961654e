//! A robot run out of a ROS bag: its multichannel audio, its poses, and the stops at
//! which it listened.
//!
//! Robots record what they hear and where they are with `rosbag record`: the audio as
//! `audio_common_msgs/AudioData` messages (ROS's `audio_capture`), the poses as odometry
//! and a localiser's estimates. I-ASM wants one recording and one pose per stop. This crate
//! reads the bag once, front to back ([`mod@format`]), keeps only the messages it can use
//! ([`msg`]), puts audio and poses on one clock ([`run`]), and finds the stretches where
//! the robot stood still, each with its pose and its audio ([`stops`]).
//!
//! ```no_run
//! let run = iasm_bag::read_file("run.bag".as_ref(), &iasm_bag::ReadOptions::default())?;
//! for stop in run.stops(&iasm_bag::StopOptions::default())? {
//!     println!("{:.1}-{:.1} s at ({:.2}, {:.2})", stop.listen_s.0, stop.listen_s.1, stop.pose.x, stop.pose.y);
//! }
//! # Ok::<(), iasm_bag::Error>(())
//! ```
//!
//! ROS 2 bags are read too ([`ros2`]: CDR messages of the same types), stored in MCAP (the
//! default since Jazzy) or in SQLite (`.db3`, the default through Humble and Iron).

pub mod error;
pub mod format;
pub mod live;
pub mod msg;
pub mod ros2;
pub mod run;
pub mod stops;
pub mod tf;
pub mod track;

pub use error::{Error, Result};
pub use run::{
    AudioFormat, AudioSegment, ReadOptions, Run, SampleFormat, TimedPose, TopicInfo, read,
    read_file,
};
pub use stops::{Stop, StopOptions};
