//! `iasm ros2`: the live node; `iasm ros2-merge`: several robots' stops made one map;
//! `iasm ros2-play`: a recorded run published as a robot publishes it; `iasm ros2-call`: a
//! node's parameters and services from a shell.
//!
//! **Transport.** ros2-client gives the node its place in the ROS graph (a DDS participant
//! and a node, named and placed by `--ros-args`: [`crate::args::ros`]) and serves its
//! parameters (module `params`); the topics themselves are RustDDS readers and writers with
//! adapters of our own that pass CDR bytes through untouched. What arrives is decoded by the
//! `bag` crate, the code that reads the same messages out of bags; what leaves is encoded by
//! `iasm-ros`, the code that writes them to MCAP. Nothing of ROS needs to be installed, and
//! the node talks to Humble's and Jazzy's default DDS (RTPS over UDP).
//!
//! **Topics in.** The node subscribes to every topic a robot's publishers offer whose type
//! the bag reader knows (audio, poses, `/tf`, the occupancy grid), in its namespace or
//! named by a remap, as DDS discovery finds them, and the live mapper chooses among them by
//! the rules of `iasm bag` (`--audio-topic` and the other flags of `iasm bag` choose where
//! those rules would not). Audio and poses are read best effort (a lost buffer is a gap,
//! which the mapper cuts the audio at; a reliable reader would stall the stream on the
//! robot's network); a topic its publisher offers transient local (`/map`, `/tf_static`,
//! `/amcl_pose`) is read reliable and transient local, so that what was published before
//! the node started is received.
//!
//! **Topics out** (reliable, relative to the namespace): those of `--mcap`
//! (`crate::rosmap`), but the grid the sources were searched in is `iasm/map` (transient
//! local), so that the node never becomes a second publisher of the robot's `/map`; and
//! each stop on `~/stops` (`iasm_msgs/msg/Stop`, transient local) for a merging node.

mod call;
mod merge;
mod node;
mod params;
mod play;

use std::time::{SystemTime, UNIX_EPOCH};

use anyhow::{Result, anyhow};
use rustdds::no_key::{DataReader, DataWriter};
use rustdds::policy::{Durability, History, Reliability};
use rustdds::{DomainParticipant, QosPolicies, QosPolicyBuilder, TopicKind};

pub use call::call_node;
pub use merge::merge;
pub use node::run;
pub use play::play;

/// Raw CDR in and out of RustDDS: the message's bytes with their encapsulation header, as a
/// bag stores them and as `bag::msg` and `iasm_ros` read and write them.
mod raw {
    use rustdds::RepresentationIdentifier;
    use rustdds::no_key::{Decode, DefaultDecoder, DeserializerAdapter, SerializerAdapter};

    /// A message as CDR bytes, header included.
    pub struct Cdr(pub Vec<u8>);

    impl std::fmt::Debug for Cdr {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "{} bytes of CDR", self.0.len())
        }
    }

    /// The adapter.
    pub struct Adapter;

    /// Why bytes were refused.
    #[derive(Debug)]
    pub struct Refused(pub String);

    impl std::fmt::Display for Refused {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str(&self.0)
        }
    }

    impl std::error::Error for Refused {}

    /// The decoder (nothing to decode: the bytes are kept).
    #[derive(Clone)]
    pub struct Keep;

    impl<'de> Decode<'de, Cdr> for Keep {
        type Error = Refused;
        fn decode_bytes(
            self,
            input: &'de [u8],
            encoding: RepresentationIdentifier,
        ) -> Result<Cdr, Refused> {
            if encoding != RepresentationIdentifier::CDR_LE {
                return Err(Refused(format!(
                    "encapsulation {encoding:?}: only little-endian plain CDR is read"
                )));
            }
            let mut v = Vec::with_capacity(input.len() + 4);
            v.extend_from_slice(&iasm_ros::cdr::CDR_LE);
            v.extend_from_slice(input);
            Ok(Cdr(v))
        }
    }

    impl DeserializerAdapter<Cdr> for Adapter {
        type Error = Refused;
        type Decoded = Cdr;
        fn supported_encodings() -> &'static [RepresentationIdentifier] {
            &[RepresentationIdentifier::CDR_LE]
        }
        fn transform_decoded(decoded: Cdr) -> Cdr {
            decoded
        }
    }

    impl DefaultDecoder<Cdr> for Adapter {
        type Decoder = Keep;
        const DECODER: Keep = Keep;
    }

    impl SerializerAdapter<Cdr> for Adapter {
        type Error = Refused;
        fn output_encoding() -> RepresentationIdentifier {
            RepresentationIdentifier::CDR_LE
        }
        fn to_bytes(value: &Cdr) -> Result<rustdds::bytes::Bytes, Refused> {
            match value.0.get(..4) {
                Some(h) if h == iasm_ros::cdr::CDR_LE => {
                    Ok(rustdds::bytes::Bytes::copy_from_slice(&value.0[4..]))
                }
                _ => Err(Refused("not little-endian CDR".into())),
            }
        }
    }
}

type Reader = DataReader<raw::Cdr, raw::Adapter>;
type Writer = DataWriter<raw::Cdr, raw::Adapter>;

/// A ROS name and type as DDS carries them: `/audio` is `rt/audio`, and
/// `nav_msgs/msg/Odometry` is `nav_msgs::msg::dds_::Odometry_`.
fn dds_names(topic: &str, msg_type: &str) -> (String, String) {
    let t = format!(
        "rt{}",
        if topic.starts_with('/') {
            topic.to_owned()
        } else {
            format!("/{topic}")
        }
    );
    let ty = match msg_type.rsplit_once('/') {
        Some((pkg, name)) => format!("{}::dds_::{name}_", pkg.replace('/', "::")),
        None => msg_type.to_owned(),
    };
    (t, ty)
}

/// The ROS name and type of a DDS topic, or `None` for one that is not a ROS topic.
fn ros_names(topic: &str, type_name: &str) -> Option<(String, String)> {
    let t = topic.strip_prefix("rt")?;
    let ty = type_name.replace("::dds_::", "::").replace("::", "/");
    Some((t.to_owned(), ty.strip_suffix('_')?.to_owned()))
}

fn qos(reliable: bool, latched: bool, depth: i32) -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(if reliable {
            Reliability::Reliable {
                max_blocking_time: rustdds::Duration::from_millis(100),
            }
        } else {
            Reliability::BestEffort
        })
        .durability(if latched {
            Durability::TransientLocal
        } else {
            Durability::Volatile
        })
        .history(History::KeepLast { depth })
        .build()
}

fn now_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

/// The participant and the node `namespace`/`name`, on `domain`, with `options`.
fn participant(
    domain: u16,
    namespace: &str,
    name: &str,
    options: ros2_client::NodeOptions,
) -> Result<(ros2_client::Context, ros2_client::Node, DomainParticipant)> {
    let ctx =
        ros2_client::Context::with_options(ros2_client::ContextOptions::new().domain_id(domain))
            .map_err(|e| anyhow!("cannot start DDS on domain {domain}: {e}"))?;
    let node = ctx
        .new_node(
            ros2_client::NodeName::new(namespace, name)
                .map_err(|e| anyhow!("node name {namespace} {name}: {e}"))?,
            options,
        )
        .map_err(|e| anyhow!("cannot create the node {name}: {e:?}"))?;
    let dp = ctx.domain_participant();
    Ok((ctx, node, dp))
}

fn writer(
    dp: &DomainParticipant,
    publisher: &rustdds::Publisher,
    topic: &str,
    msg_type: &str,
    latched: bool,
) -> Result<Writer> {
    let q = qos(true, latched, if latched { 1 } else { 10 });
    writer_with(dp, publisher, topic, msg_type, q)
}

/// A writer of `topic` with `q`.
fn writer_with(
    dp: &DomainParticipant,
    publisher: &rustdds::Publisher,
    topic: &str,
    msg_type: &str,
    q: QosPolicies,
) -> Result<Writer> {
    let (t, ty) = dds_names(topic, msg_type);
    let topic_ = dp
        .create_topic(t, ty, &q, TopicKind::NoKey)
        .map_err(|e| anyhow!("topic {topic}: {e}"))?;
    publisher
        .create_datawriter_no_key::<raw::Cdr, raw::Adapter>(&topic_, Some(q))
        .map_err(|e| anyhow!("a writer of {topic}: {e}"))
}

/// A reader of `topic` (its DDS name and type) with `q`, as [`writer`] makes writers.
fn reader(
    dp: &DomainParticipant,
    subscriber: &rustdds::Subscriber,
    (dds_topic, dds_type): (String, String),
    q: QosPolicies,
) -> Result<Reader> {
    let t = dp
        .create_topic(dds_topic.clone(), dds_type, &q, TopicKind::NoKey)
        .map_err(|e| anyhow!("topic {dds_topic}: {e}"))?;
    subscriber
        .create_datareader_no_key::<raw::Cdr, raw::Adapter>(&t, Some(q))
        .map_err(|e| anyhow!("a reader of {dds_topic}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros_names_are_dds_names_and_back() {
        let (t, ty) = dds_names("/iasm/sources", "visualization_msgs/msg/MarkerArray");
        assert_eq!(t, "rt/iasm/sources");
        assert_eq!(ty, "visualization_msgs::msg::dds_::MarkerArray_");
        assert_eq!(
            ros_names(&t, &ty),
            Some((
                "/iasm/sources".into(),
                "visualization_msgs/msg/MarkerArray".into()
            ))
        );
        assert_eq!(ros_names("ros_discovery_info", "x"), None);
    }
}
