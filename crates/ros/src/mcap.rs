//! An MCAP file of ROS 2 messages, as `ros2 bag record` writes one (profile `ros2`, schemas
//! `ros2msg`, messages `cdr`): Foxglove opens it as it is, and `ros2 bag play` sends it to
//! RViz. Each channel carries the QoS its publisher would offer
//! (`offered_qos_profiles`, as rosbag2 records it), so that a player republishes `/map`
//! transient local, as a map server does and as RViz's map display asks for.

use std::collections::{BTreeMap, HashMap};
use std::io::{Seek, Write};

use crate::Error;
use crate::msg::Message;

/// How a topic is offered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Qos {
    /// Reliable, volatile: markers, paths, poses.
    Reliable,
    /// Reliable and transient local (the last message kept for late subscribers): `/map`.
    Latched,
}

impl Qos {
    /// rosbag2's YAML of the offered profile (enums as `rmw` numbers them: history 1 keep
    /// last, reliability 1 reliable, durability 1 transient local and 2 volatile).
    pub fn rosbag2_yaml(self) -> String {
        let durability = match self {
            Self::Reliable => 2,
            Self::Latched => 1,
        };
        let forever = "\n    sec: 2147483647\n    nsec: 4294967295";
        format!(
            "- history: 1\n  depth: 1\n  reliability: 1\n  durability: {durability}\n  \
             deadline:{forever}\n  lifespan:{forever}\n  liveliness: 1\n  \
             liveliness_lease_duration:{forever}\n  avoid_ros_namespace_conventions: false\n"
        )
    }
}

/// Writes messages to an MCAP file, a channel per topic.
pub struct Writer<W: Write + Seek> {
    inner: mcap::Writer<W>,
    channels: HashMap<String, (u16, &'static str)>,
    sequence: u32,
}

impl<W: Write + Seek> Writer<W> {
    /// A writer onto `w`.
    ///
    /// # Errors
    /// [`Error::Mcap`] when the header cannot be written.
    pub fn new(w: W) -> Result<Self, Error> {
        let inner = mcap::WriteOptions::new()
            .compression(None)
            .profile("ros2")
            .library(concat!("iasm-ros ", env!("CARGO_PKG_VERSION")))
            .create(w)
            .map_err(mcap_error)?;
        Ok(Self {
            inner,
            channels: HashMap::new(),
            sequence: 0,
        })
    }

    /// Writes `message` on `topic` at `log_time_ns` (ns since the epoch; a player sends it
    /// that long after the file's first message). A topic's first message sets its type and
    /// QoS.
    ///
    /// # Errors
    /// [`Error::Mcap`] when it cannot be written, or [`Error::Topic`] when `topic` already
    /// carries another type.
    pub fn write<M: Message>(
        &mut self,
        topic: &str,
        qos: Qos,
        log_time_ns: u64,
        message: &M,
    ) -> Result<(), Error> {
        let channel = match self.channels.get(topic) {
            Some(&(id, name)) if name == M::NAME => id,
            Some(&(_, name)) => {
                return Err(Error::Topic(format!(
                    "{topic} carries {name}, not {}",
                    M::NAME
                )));
            }
            None => {
                let schema = self
                    .inner
                    .add_schema(M::NAME, "ros2msg", M::schema().as_bytes())
                    .map_err(mcap_error)?;
                let metadata =
                    BTreeMap::from([("offered_qos_profiles".to_owned(), qos.rosbag2_yaml())]);
                let id = self
                    .inner
                    .add_channel(schema, topic, "cdr", &metadata)
                    .map_err(mcap_error)?;
                self.channels.insert(topic.to_owned(), (id, M::NAME));
                id
            }
        };
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        self.inner
            .write_to_known_channel(&header, &message.to_cdr())
            .map_err(mcap_error)
    }

    /// Ends the file (its summary and footer) and gives the sink back.
    ///
    /// # Errors
    /// [`Error::Mcap`] when the end cannot be written.
    pub fn finish(mut self) -> Result<W, Error> {
        self.inner.finish().map_err(mcap_error)?;
        Ok(self.inner.into_inner())
    }
}

fn mcap_error(e: mcap::McapError) -> Error {
    Error::Mcap(e.to_string())
}
