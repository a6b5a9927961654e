//! iasm's maps as ROS 2 messages, for RViz, Foxglove and the programs of a robot.
//!
//! A map of sound sources is shown the way ROS shows everything: markers
//! (`visualization_msgs`), a path and an occupancy grid (`nav_msgs`), poses
//! (`geometry_msgs`). This crate has those messages as plain structs ([`msg`]), writes and
//! reads them in CDR, ROS 2's serialisation ([`cdr`]), and writes them to MCAP files as
//! `ros2 bag record` does ([`mod@mcap`]). It knows nothing of how a map is made: the app
//! turns a map into messages, and the same bytes go into a file or onto the wire.
//!
//! Why not generated bindings: the message types are fixed by ROS (Humble and Jazzy agree
//! on all of them), a map needs eight, and the code that writes them is shorter than a
//! build step that needs a ROS installation. Decoding is here too, for programs that
//! subscribe to the map and for the tests, which read every message back.
//!
//! ```
//! use iasm_ros::msg::{Header, Message, Pose, PoseArray};
//! let sources = PoseArray {
//!     header: Header::new("map", 1_000_000_000),
//!     poses: vec![Pose::planar(1.5, -0.5, 0.0, 0.0)],
//! };
//! let bytes = sources.to_cdr();
//! assert_eq!(PoseArray::from_cdr(&bytes)?, sources);
//!
//! let mut file = iasm_ros::mcap::Writer::new(std::io::Cursor::new(Vec::new()))?;
//! file.write("/iasm/source_poses", iasm_ros::mcap::Qos::Reliable, 1_000_000_000, &sources)?;
//! let bytes = file.finish()?.into_inner();
//! assert_eq!(&bytes[..8], b"\x89MCAP0\r\n");
//! # Ok::<(), iasm_ros::Error>(())
//! ```

pub mod cdr;
pub mod mcap;
pub mod msg;

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bytes that are not the message they should be.
    #[error("not a valid message: {0}")]
    Decode(String),
    /// The MCAP file could not be written.
    #[error("MCAP: {0}")]
    Mcap(String),
    /// A topic given two types.
    #[error("topic {0}")]
    Topic(String),
}
