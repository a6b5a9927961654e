//! `iasm ros2`: the live node; `iasm ros2-play`: a recorded run published as a robot
//! publishes it.
//!
//! **Transport.** ros2-client gives the node its place in the ROS graph (a DDS participant
//! and a node named `iasm`); the topics themselves are RustDDS readers and writers with
//! adapters of our own that pass CDR bytes through untouched. What arrives is decoded by the
//! `bag` crate, the code that reads the same messages out of bags; what leaves is encoded by
//! `iasm-ros`, the code that writes them to MCAP. Nothing of ROS needs to be installed, and
//! the node talks to Humble's and Jazzy's default DDS (RTPS over UDP).
//!
//! **Topics in.** The node subscribes to every topic a robot's publishers offer whose type
//! the bag reader knows (audio, poses, `/tf`, the occupancy grid), as DDS discovery finds
//! them, and the live mapper chooses among them by the rules of `iasm bag` (`--audio-topic`
//! and the other flags of `iasm bag` choose where those rules would not). Audio and poses
//! are read best effort (a lost buffer is a gap, which the mapper cuts the audio at; a
//! reliable reader would stall the stream on the robot's network); a topic its publisher
//! offers transient local (`/map`, `/tf_static`, `/amcl_pose`) is read reliable and
//! transient local, so that what was published before the node started is received.
//!
//! **Topics out** (reliable): those of `--mcap` (`crate::rosmap`), but the grid the sources
//! were searched in is `/iasm/map` (transient local), so that the node never becomes a
//! second publisher of the robot's `/map`.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context, Result, anyhow, bail};
use bag::msg::Kind;
use rustdds::no_key::{DataReader, DataWriter};
use rustdds::policy::{Durability, History, Reliability};
use rustdds::{DomainParticipant, QosPolicies, QosPolicyBuilder, TopicKind};

use crate::Outcome;
use crate::args::{Ros2Args, Ros2PlayArgs};
use crate::live::LiveMapper;
use crate::rosmap::{self, MapMessages};

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

/// The participant and node, on `domain`.
fn participant(
    domain: u16,
    name: &str,
) -> Result<(ros2_client::Context, ros2_client::Node, DomainParticipant)> {
    let ctx =
        ros2_client::Context::with_options(ros2_client::ContextOptions::new().domain_id(domain))
            .map_err(|e| anyhow!("cannot start DDS on domain {domain}: {e}"))?;
    let node = ctx
        .new_node(
            ros2_client::NodeName::new("/", name).map_err(|e| anyhow!("node name {name}: {e}"))?,
            ros2_client::NodeOptions::new(),
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
    let (t, ty) = dds_names(topic, msg_type);
    let q = qos(true, latched, if latched { 1 } else { 10 });
    let topic_ = dp
        .create_topic(t, ty, &q, TopicKind::NoKey)
        .map_err(|e| anyhow!("topic {topic}: {e}"))?;
    publisher
        .create_datawriter_no_key::<raw::Cdr, raw::Adapter>(&topic_, Some(q))
        .map_err(|e| anyhow!("a writer of {topic}: {e}"))
}

/// The node's publishers.
struct Outputs {
    sources: Writer,
    doas: Writer,
    path: Writer,
    source_poses: Writer,
    map: Writer,
    /// The last grid sent (it is latched: sent again only when it changes).
    grid_sent: Option<iasm_ros::msg::OccupancyGrid>,
}

/// Where the node publishes its grid.
pub const NODE_MAP_TOPIC: &str = "/iasm/map";

impl Outputs {
    fn new(dp: &DomainParticipant) -> Result<Self> {
        let p = dp
            .create_publisher(&qos(true, false, 10))
            .map_err(|e| anyhow!("a DDS publisher: {e}"))?;
        let ma = "visualization_msgs/msg/MarkerArray";
        Ok(Self {
            sources: writer(dp, &p, rosmap::SOURCES_TOPIC, ma, false)?,
            doas: writer(dp, &p, rosmap::DOAS_TOPIC, ma, false)?,
            path: writer(dp, &p, rosmap::PATH_TOPIC, "nav_msgs/msg/Path", false)?,
            source_poses: writer(
                dp,
                &p,
                rosmap::SOURCE_POSES_TOPIC,
                "geometry_msgs/msg/PoseArray",
                false,
            )?,
            map: writer(dp, &p, NODE_MAP_TOPIC, "nav_msgs/msg/OccupancyGrid", true)?,
            grid_sent: None,
        })
    }

    fn publish(&mut self, m: &MapMessages) -> Result<()> {
        use iasm_ros::msg::Message;
        let send = |w: &Writer, bytes: Vec<u8>, what: &str| {
            w.write(raw::Cdr(bytes), None)
                .map_err(|e| anyhow!("publishing {what}: {e:?}"))
        };
        if self.grid_sent.as_ref() != Some(&m.grid) {
            send(&self.map, m.grid.to_cdr(), NODE_MAP_TOPIC)?;
            self.grid_sent = Some(m.grid.clone());
        }
        send(&self.path, m.path.to_cdr(), rosmap::PATH_TOPIC)?;
        send(&self.doas, m.doas.to_cdr(), rosmap::DOAS_TOPIC)?;
        send(&self.sources, m.sources.to_cdr(), rosmap::SOURCES_TOPIC)?;
        send(
            &self.source_poses,
            m.source_poses.to_cdr(),
            rosmap::SOURCE_POSES_TOPIC,
        )
    }

    /// Waits until every reliable reader of every topic has acknowledged what was
    /// published, or until `max` has passed for a topic (a reader that vanished).
    fn wait_for_acknowledgments(&self, max: Duration) {
        for w in [
            &self.source_poses,
            &self.sources,
            &self.doas,
            &self.path,
            &self.map,
        ] {
            if !matches!(w.wait_for_acknowledgments(max), Ok(true)) {
                eprintln!(
                    "warning: {}: not every subscriber acknowledged the final map within {} s",
                    rustdds::TopicDescription::name(w.topic()),
                    max.as_secs()
                );
            }
        }
    }
}

/// Warnings said on the log: the first of each kind, then at 10, 100, 1000... (every one
/// is counted in the map's notes).
#[derive(Default)]
struct Log {
    seen: HashMap<String, u64>,
}

impl Log {
    fn warn(&mut self, what: &str) {
        // The kind: the message up to its first colon (a topic and what went wrong).
        let kind = what.split(':').take(2).collect::<Vec<_>>().join(":");
        let n = self.seen.entry(kind).or_default();
        *n += 1;
        if 10u64.pow(n.ilog10()) == *n {
            eprintln!(
                "warning: {what}{}",
                if *n > 1 {
                    format!(" ({n} so far)")
                } else {
                    String::new()
                }
            );
        }
    }
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

/// The node's subscriptions, and when each kind of message last came.
struct Inputs {
    subscriber: rustdds::Subscriber,
    /// Topic -> (type, reader).
    readers: BTreeMap<String, (String, Reader)>,
    last_message: Option<Instant>,
    last_pose: Option<Instant>,
    last_audio: Option<Instant>,
    told_no_pose: Instant,
}

impl Inputs {
    fn new(dp: &DomainParticipant) -> Result<Self> {
        Ok(Self {
            subscriber: dp
                .create_subscriber(&qos(false, false, 100))
                .map_err(|e| anyhow!("a DDS subscriber: {e}"))?,
            readers: BTreeMap::new(),
            last_message: None,
            last_pose: None,
            last_audio: None,
            told_no_pose: Instant::now(),
        })
    }

    /// Subscribes to every topic DDS discovery has found a publisher of, of a type the bag
    /// reader knows (not ours): best effort, or reliable and transient local where the
    /// publisher offers that.
    fn discover(&mut self, dp: &DomainParticipant) -> Result<()> {
        for w in dp.discovered_writers() {
            let d = &w.publication_topic_data;
            let Some((topic, ty)) = ros_names(&d.topic_name, &d.type_name) else {
                continue;
            };
            if self.readers.contains_key(&topic)
                || Kind::of(&ty).is_none()
                || topic.starts_with("/iasm/")
            {
                continue;
            }
            let latched = matches!(d.durability, Some(Durability::TransientLocal));
            let q = qos(latched, latched, if latched { 1 } else { 100 });
            let r = reader(
                dp,
                &self.subscriber,
                (d.topic_name.clone(), d.type_name.clone()),
                q,
            )?;
            eprintln!(
                "subscribed to {topic} ({ty}{})",
                if latched { ", transient local" } else { "" }
            );
            self.readers.insert(topic, (ty, r));
        }
        Ok(())
    }

    /// Hands every message waiting to `live`; how many there were.
    fn take(&mut self, live: &mut LiveMapper, log: &mut Log) -> usize {
        let mut got = 0usize;
        for (topic, (ty, r)) in &mut self.readers {
            loop {
                match r.take_next_sample() {
                    Ok(Some(s)) => {
                        got += 1;
                        let kind = Kind::of(ty);
                        if kind.is_some_and(Kind::is_pose) || kind == Some(Kind::Tf) {
                            self.last_pose = Some(Instant::now());
                        } else if kind.is_some_and(Kind::is_audio) {
                            self.last_audio = Some(Instant::now());
                        }
                        if let Some(w) = live.push(topic, ty, now_ns(), &s.value().0) {
                            log.warn(&w);
                        }
                    }
                    Ok(None) => break,
                    Err(e) => {
                        log.warn(&format!("a message of {topic} unreadable: {e:?}"));
                        break;
                    }
                }
            }
        }
        if got > 0 {
            self.last_message = Some(Instant::now());
        }
        got
    }

    /// Warns (every 30 s at most) when audio flows but no pose has come for 10 s: no stop
    /// can be found.
    fn check_poses(&mut self, log: &mut Log) {
        if self
            .last_audio
            .is_some_and(|t| t.elapsed() < Duration::from_secs(2))
            && self
                .last_pose
                .is_none_or(|p| p.elapsed() > Duration::from_secs(10))
            && self.told_no_pose.elapsed() > Duration::from_secs(30)
        {
            self.told_no_pose = Instant::now();
            log.warn("no pose received for 10 s while audio arrives: no stop can be found (is the robot's odometry or localisation publishing?)");
        }
    }
}

/// Runs `iasm ros2`: the node, until Ctrl-C (or `--until-idle`); then the final map.
///
/// # Errors
/// Settings refused, DDS that cannot start, or outputs that cannot be written.
pub fn run(a: &Ros2Args) -> Result<Outcome> {
    let settings = a.settings.settings()?;
    let mut live = LiveMapper::new(
        settings,
        a.run.read_options()?,
        a.run.stop_options()?,
        a.seed,
    )?;
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }
    let (_ctx, _node, dp) = participant(a.domain_id, &a.node_name)?;
    let mut inputs = Inputs::new(&dp)?;
    let mut sink = Sink {
        out: Outputs::new(&dp)?,
        mcap: a.mcap.as_deref().map(rosmap::McapFile::new).transpose()?,
        json: a.out.clone(),
    };
    let mut log = Log::default();
    let mut last_discovery = Instant::now() - Duration::from_secs(10);
    let mut last_step = Instant::now();
    eprintln!(
        "iasm ros2: node /{} on DDS domain {}; listening for audio, poses and the map (Ctrl-C ends the run with its final map)",
        a.node_name, a.domain_id
    );
    while !stop.load(Ordering::SeqCst) {
        if last_discovery.elapsed() >= Duration::from_millis(250) {
            last_discovery = Instant::now();
            inputs.discover(&dp)?;
        }
        let got = inputs.take(&mut live, &mut log);
        inputs.check_poses(&mut log);
        if last_step.elapsed() >= Duration::from_millis(200) {
            last_step = Instant::now();
            step(&mut live, &mut sink, &mut log, false)?;
        }
        if let (Some(idle), Some(t)) = (a.until_idle, inputs.last_message)
            && t.elapsed().as_secs_f64() > idle
        {
            eprintln!("no message for {idle} s: the run is over");
            break;
        }
        if got == 0 {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    // The run's end: the stop the robot stands at, then the full map over every stop.
    step(&mut live, &mut sink, &mut log, true)?;
    let out = finish(&mut live, sink, a.seed)?;
    // The writers go with the process: wait (a bounded time) until every reliable reader
    // has acknowledged the final map, so that a subscriber hears it whatever the load.
    // A write reaches the writer's history through DDS's own thread: asked at once, the
    // wait would find the samples before it already acknowledged and return.
    std::thread::sleep(Duration::from_millis(200));
    out.wait_for_acknowledgments(Duration::from_secs(5));
    Ok(Outcome::Success)
}

/// Publishes and writes the final map (the full map over every stop), says it, and ends
/// the MCAP file; gives back the topics' writers.
fn finish(live: &mut LiveMapper, mut sink: Sink, seed: u64) -> Result<Outputs> {
    match live.finish() {
        Some(fin) => {
            sink.publish(live, &fin, true)?;
            println!(
                "{} stops; final map (full, seed {seed}): {} sources",
                live.stops().len(),
                fin.sources.len()
            );
            for (k, s) in fin.sources.iter().enumerate() {
                println!(
                    "  s{} ({:.3}, {:.3}) m, {} DoAs",
                    k + 1,
                    s.x,
                    s.y,
                    s.observations
                );
            }
        }
        None => println!("no stop was mapped"),
    }
    for n in live.notes() {
        eprintln!("note: {n}");
    }
    if let Some(f) = sink.mcap {
        f.finish()?;
    }
    Ok(sink.out)
}

fn announce(live: &LiveMapper, u: &crate::live::Update) {
    let s = live.stops().last().expect("an update follows a stop");
    println!(
        "stop {:>3}  ({:.2}, {:.2}, {:.0} deg)  {} DoAs  {:>2} sources  ssl {:.0} ms  map {:.0} ms",
        u.record.stop,
        s.pose.x,
        s.pose.y,
        s.pose.theta_deg(),
        u.record.doas,
        u.record.sources,
        u.record.ssl_ms,
        u.record.map_ms
    );
}

/// Where each map update goes: the topics, the MCAP file, the JSON.
struct Sink {
    out: Outputs,
    mcap: Option<rosmap::McapFile>,
    json: Option<std::path::PathBuf>,
}

impl Sink {
    fn publish(&mut self, live: &LiveMapper, map: &asm::MapResult, final_map: bool) -> Result<()> {
        let t = now_ns();
        if let Some(m) = live.messages(map, t) {
            self.out.publish(&m)?;
            if let Some(f) = self.mcap.as_mut() {
                f.add(&m, t)?;
            }
        }
        if let Some(path) = &self.json {
            let report = live.report(map, final_map);
            crate::output::write_atomic(path, serde_json::to_string_pretty(&report)?.as_bytes())?;
        }
        Ok(())
    }
}

/// Maps the stops the robot has finished (with `all`, the one it stands at too), says so
/// and publishes each update.
fn step(live: &mut LiveMapper, sink: &mut Sink, log: &mut Log, all: bool) -> Result<()> {
    let (updates, warnings) = live.step(all);
    for w in &warnings {
        log.warn(w);
    }
    for u in updates {
        announce(live, &u);
        sink.publish(live, &u.map, false)?;
    }
    Ok(())
}

/// The header stamp of a message of `kind` moved by `shift_ns`, in place (`/tf`: every
/// transform's); a stamp of zero (unstamped) is left.
fn shift_stamps(kind: Kind, data: &mut [u8], shift_ns: i64) -> Result<()> {
    let shift = |data: &mut [u8], at: usize| -> Result<()> {
        let b = data
            .get(at..at + 8)
            .context("a message shorter than its header")?;
        let sec = i32::from_le_bytes(b[..4].try_into().expect("4"));
        let nsec = u32::from_le_bytes(b[4..8].try_into().expect("4"));
        if sec == 0 && nsec == 0 {
            return Ok(());
        }
        let t = iasm_ros::msg::Time { sec, nanosec: nsec }.ns() + shift_ns;
        let t = iasm_ros::msg::Time::from_ns(t);
        data[at..at + 4].copy_from_slice(&t.sec.to_le_bytes());
        data[at + 4..at + 8].copy_from_slice(&t.nanosec.to_le_bytes());
        Ok(())
    };
    match kind {
        Kind::AudioData | Kind::AudioInfo | Kind::Pose2D => Ok(()),
        Kind::Tf => {
            // transforms: count, then each: header (stamp, frame_id), child_frame_id,
            // translation and rotation (7 float64, aligned to 8 from the body's start).
            let rd = |d: &[u8], at: usize| -> Result<u32> {
                Ok(u32::from_le_bytes(
                    d.get(at..at + 4)
                        .context("a short /tf message")?
                        .try_into()
                        .expect("4"),
                ))
            };
            let align = |at: usize, n: usize| 4 + (at - 4).div_ceil(n) * n;
            let n = rd(data, 4)?;
            let mut at = 8;
            for _ in 0..n {
                at = align(at, 4);
                shift(data, at)?;
                at += 8;
                for _ in 0..2 {
                    at = align(at, 4);
                    at += 4 + rd(data, at)? as usize;
                }
                at = align(at, 8) + 7 * 8;
            }
            Ok(())
        }
        _ => shift(data, 4),
    }
}

/// A recorded message: topic, type, receipt time (ns), CDR bytes.
type Recorded = (String, String, i64, Vec<u8>);

/// A ROS 2 bag's messages of the types iasm reads, in time order.
///
/// # Errors
/// A bag that cannot be read, or a ROS 1 bag (its messages are not CDR).
fn bag_messages(path: &std::path::Path) -> Result<Vec<Recorded>> {
    let mut msgs = Vec::new();
    bag::ros2::scan_files(path, |m| {
        if m.connection.encoding != bag::msg::Encoding::Cdr {
            return Err(bag::Error::Topic(format!(
                "{} is a ROS 1 topic: ros2-play plays ROS 2 bags",
                m.connection.topic
            )));
        }
        if Kind::of(&m.connection.msg_type).is_some() {
            msgs.push((
                m.connection.topic.clone(),
                m.connection.msg_type.clone(),
                m.time_ns,
                m.data.to_vec(),
            ));
        }
        Ok(())
    })
    .with_context(|| format!("reading {}", path.display()))?;
    msgs.sort_by_key(|m| m.2);
    Ok(msgs)
}

/// Waits until DDS discovery has found a reader of every topic of `writers`, or `wait_s`
/// has passed (then says which have none).
fn wait_for_subscribers(dp: &DomainParticipant, writers: &BTreeMap<String, Writer>, wait_s: f64) {
    let unmatched = || -> Vec<String> {
        let readers: Vec<String> = dp
            .discovered_readers()
            .into_iter()
            .map(|r| r.subscription_topic_data.topic_name)
            .collect();
        writers
            .keys()
            .filter(|t| !readers.contains(&dds_names(t, "").0))
            .cloned()
            .collect()
    };
    let t0 = Instant::now();
    while !unmatched().is_empty() && t0.elapsed().as_secs_f64() < wait_s {
        std::thread::sleep(Duration::from_millis(20));
    }
    let left = unmatched();
    if !left.is_empty() {
        eprintln!("warning: no subscriber to {left:?} after {wait_s} s; playing anyway");
    }
    // Matched by discovery is not yet matched by the writer: a moment for that.
    std::thread::sleep(Duration::from_millis(500));
}

/// The node's sources as last heard on `/iasm/source_poses`.
struct Listener {
    reader: Option<Reader>,
    heard: Vec<[f64; 2]>,
    /// Updates taken.
    updates: usize,
}

impl Listener {
    /// A listener to the node's sources ([`rosmap::SOURCE_POSES_TOPIC`]) when `listen`,
    /// else one that hears nothing.
    fn new(dp: &DomainParticipant, listen: bool) -> Result<Self> {
        let reader = if listen {
            let sub = dp
                .create_subscriber(&qos(true, false, 10))
                .map_err(|e| anyhow!("a DDS subscriber: {e}"))?;
            let names = dds_names(rosmap::SOURCE_POSES_TOPIC, "geometry_msgs/msg/PoseArray");
            Some(reader(dp, &sub, names, qos(true, false, 10))?)
        } else {
            None
        };
        Ok(Self {
            reader,
            heard: Vec::new(),
            updates: 0,
        })
    }

    /// Takes what has come.
    fn take(&mut self) {
        use iasm_ros::msg::Message;
        if let Some(r) = &mut self.reader {
            while let Ok(Some(s)) = r.take_next_sample() {
                if let Ok(p) = iasm_ros::msg::PoseArray::from_cdr(&s.value().0) {
                    self.updates += 1;
                    self.heard = p
                        .poses
                        .iter()
                        .map(|p| [p.position.x, p.position.y])
                        .collect();
                }
            }
        }
    }

    /// Listens for `linger_s` or until Ctrl-C (say, once the node has ended), then half a
    /// second more: what the node sent last (its final map, just before it ended) may
    /// still be on its way from the reader's DDS thread. Writes the last sources heard to
    /// `path` as JSON.
    fn linger_and_write(mut self, linger_s: f64, path: &std::path::Path) -> Result<()> {
        let stop = Arc::new(AtomicBool::new(false));
        {
            let stop = Arc::clone(&stop);
            let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
        }
        let until = Instant::now() + Duration::from_secs_f64(linger_s);
        while Instant::now() < until && !stop.load(Ordering::SeqCst) {
            self.take();
            std::thread::sleep(Duration::from_millis(10));
        }
        let drain = Instant::now() + Duration::from_millis(500);
        while Instant::now() < drain {
            self.take();
            std::thread::sleep(Duration::from_millis(10));
        }
        let sources: Vec<serde_json::Value> = self
            .heard
            .iter()
            .map(|p| serde_json::json!({"x": p[0], "y": p[1]}))
            .collect();
        let json = serde_json::json!({ "frame_id": rosmap::FRAME, "sources": sources });
        crate::output::write_atomic(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
        println!(
            "heard {} sources on {} (the last of {} updates)",
            self.heard.len(),
            rosmap::SOURCE_POSES_TOPIC,
            self.updates
        );
        Ok(())
    }
}

/// One writer per topic of `msgs`, latched (transient local) for a map and `/tf_static`.
fn play_writers(
    dp: &DomainParticipant,
    publisher: &rustdds::Publisher,
    msgs: &[Recorded],
) -> Result<BTreeMap<String, Writer>> {
    let mut writers: BTreeMap<String, Writer> = BTreeMap::new();
    for (topic, ty, _, _) in msgs {
        if !writers.contains_key(topic) {
            let kind = Kind::of(ty).expect("kept above");
            let latched = kind == Kind::OccupancyGrid || topic.ends_with("_static");
            writers.insert(topic.clone(), writer(dp, publisher, topic, ty, latched)?);
        }
    }
    Ok(writers)
}

/// Runs `iasm ros2-play`: the bag's messages published on their topics at their pace, stamps
/// moved to now, as the robot that recorded them published them.
///
/// # Errors
/// A bag that cannot be read or is not a ROS 2 bag, or DDS that cannot start.
pub fn play(a: &Ros2PlayArgs) -> Result<Outcome> {
    let msgs = bag_messages(&a.bag)?;
    let Some(first) = msgs.first().map(|m| m.2) else {
        bail!("{}: no message of a type iasm reads", a.bag.display());
    };
    let (_ctx, _node, dp) = participant(a.domain_id, "iasm_play")?;
    let publisher = dp
        .create_publisher(&qos(true, false, 100))
        .map_err(|e| anyhow!("a DDS publisher: {e}"))?;
    let writers = play_writers(&dp, &publisher, &msgs)?;
    // The node's sources, when asked.
    let mut listener = Listener::new(&dp, a.listen.is_some())?;
    wait_for_subscribers(&dp, &writers, a.wait_s);
    let start = Instant::now();
    let shift = now_ns() - first;
    for (topic, ty, t, mut data) in msgs {
        let due = Duration::from_nanos(u64::try_from(t - first).unwrap_or(0));
        while start.elapsed() < due {
            listener.take();
            std::thread::sleep(
                due.saturating_sub(start.elapsed())
                    .min(Duration::from_millis(5)),
            );
        }
        shift_stamps(Kind::of(&ty).expect("kept"), &mut data, shift)
            .with_context(|| format!("a message of {topic}"))?;
        writers[&topic]
            .write(raw::Cdr(data), None)
            .map_err(|e| anyhow!("publishing on {topic}: {e:?}"))?;
    }
    println!(
        "played {} in {:.1} s",
        a.bag.display(),
        start.elapsed().as_secs_f64()
    );
    if let Some(path) = &a.listen {
        listener.linger_and_write(a.linger_s, path)?;
    }
    Ok(Outcome::Success)
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

    #[test]
    fn a_tf_messages_every_stamp_moves() {
        use iasm_ros::cdr::Writer as W;
        // Two transforms: header (stamp, frame), child, translation, rotation.
        let mut w = W::new();
        w.u32(2);
        for (sec, frame, child) in [(10, "map", "odom"), (11, "odom", "base_link")] {
            w.i32(sec);
            w.u32(5);
            w.string(frame);
            w.string(child);
            // Translation, then a rotation (the identity).
            for v in [1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
                w.f64(v);
            }
        }
        let mut data = w.finish();
        shift_stamps(Kind::Tf, &mut data, 2_000_000_000).unwrap();
        let t = bag::msg::transforms(bag::msg::Encoding::Cdr, &data).unwrap();
        assert_eq!(t[0].stamp_ns, Some(12_000_000_005));
        assert_eq!(t[1].stamp_ns, Some(13_000_000_005));
        assert_eq!(
            (t[1].parent.as_str(), t[1].child.as_str()),
            ("odom", "base_link")
        );
    }
}
