//! What can go wrong reading a run out of a bag.

/// An error reading a bag or the run in it. Messages name the topic, the record or the
/// option concerned; the caller adds the file's name.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be read.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The file is not a bag this crate reads (ROS 1 format 2.0, or ROS 2 in MCAP or
    /// SQLite, compressed or not); `what` says what it looks like instead.
    #[error("not a ROS bag that iasm reads (ROS 1, or ROS 2 in MCAP or SQLite): {what}")]
    NotABag {
        /// What the file looks like.
        what: String,
    },
    /// A record that does not parse.
    #[error("corrupt record at byte {offset}: {what}")]
    Corrupt {
        /// Where the record starts in the file (or in its chunk's decompressed data).
        offset: u64,
        /// What is wrong with it.
        what: String,
    },
    /// A message that does not decode as its connection's type says.
    #[error("topic {topic} ({msg_type}), message {index}: {what}")]
    Message {
        /// The message's topic.
        topic: String,
        /// Its type, as the bag names it.
        msg_type: String,
        /// Its number on the topic, from 1.
        index: usize,
        /// What is wrong with it.
        what: String,
    },
    /// No topic, or more than one, fits a role (audio, poses, odometry) and none was named;
    /// or a named topic is not in the bag or has a type that cannot play the role.
    #[error("{0}")]
    Topic(String),
    /// The audio cannot be decoded: no format known for it, a coding other than raw PCM,
    /// or a sample format not supported.
    #[error("{0}")]
    Audio(String),
    /// A file of a bag compressed file by file (`.db3.zstd`, `.mcap.zstd`) that does not
    /// decompress: cut off, or not zstd.
    #[error("{path}: a zstd-compressed file that does not decompress ({what}); `zstd -t` tests it")]
    Decompress {
        /// The file.
        path: std::path::PathBuf,
        /// What the decoder said.
        what: String,
    },
    /// A ROS 2 SQLite bag that SQLite cannot read as rosbag2's tables.
    #[error("the SQLite database: {0}")]
    Database(String),
    /// An option out of its range.
    #[error("{0}")]
    Config(String),
}

/// The bag crate's result.
pub type Result<T> = std::result::Result<T, Error>;
