//! The live node (`iasm ros2`): its subscriptions, the live mapper they feed, and the
//! topics, MCAP file and JSON each map update goes to.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow};
use bag::msg::Kind;
use rustdds::DomainParticipant;
use rustdds::policy::Durability;

use crate::Outcome;
use crate::args::Ros2Args;
use crate::args::ros::RosArgs;
use crate::live::LiveMapper;
use crate::rosmap::{self, MapMessages};

use super::params::{Ask, Clock, NodeParams, Services, TriggerResponse};
use super::{Reader, Writer, participant, qos, raw, reader, ros_names, writer};

/// The node's names as its `--ros-args` resolve them: its own, and those of its topics.
pub(super) struct Names {
    pub ros: RosArgs,
    /// The node's name.
    pub node: String,
    /// Whether the node's outputs are its own (`~/sources`, a merging node's) rather than
    /// the namespace's (`iasm/sources`, a robot's).
    pub private: bool,
}

impl Names {
    /// The graph's name of the node's topic `own` (`/iasm/sources` is relative to the
    /// namespace: `/robot1/iasm/sources`), remapped.
    pub fn topic(&self, own: &str) -> String {
        if self.private {
            let last = own.rsplit('/').next().unwrap_or(own);
            self.ros.remapped(&format!("~/{last}"), &self.node)
        } else {
            self.ros.remapped(own.trim_start_matches('/'), &self.node)
        }
    }

    /// The node's fully qualified name.
    pub fn fq(&self) -> String {
        self.ros.fully_qualified(&self.node)
    }

    /// A topic of the run's options (`--audio-topic`, ...) as the mapper knows the topics:
    /// resolved in the namespace; "" (none) stays.
    fn option(&self, t: Option<String>) -> Option<String> {
        t.map(|t| {
            if t.is_empty() {
                t
            } else {
                self.ros.resolve(&t, &self.node)
            }
        })
    }
}

/// The node's publishers.
pub(super) struct Outputs {
    /// `~/stops`: each stop's pose and DoAs (`iasm_msgs/msg/Stop`), for a merging node
    /// (none on a merging node).
    stops: Option<Writer>,
    /// The stops published so far (a stop's index in the run: never reset, not even by
    /// `clear_map`, so that a merging node never takes a new stop for one it has).
    stops_sent: u32,
    sources: Writer,
    doas: Writer,
    path: Writer,
    source_poses: Writer,
    map: Writer,
    /// `/iasm/changes`, with a prior map.
    changes: Option<Writer>,
    /// The last grid sent (it is latched: sent again only when it changes).
    grid_sent: Option<iasm_ros::msg::OccupancyGrid>,
}

/// Where the node publishes its grid.
pub const NODE_MAP_TOPIC: &str = "/iasm/map";

/// The stops a node keeps for a merging node that joins late (reliable, transient local):
/// a day of stops every ten seconds.
pub const STOP_HISTORY: i32 = 10_000;

impl Outputs {
    pub fn new(dp: &DomainParticipant, names: &Names) -> Result<Self> {
        let p = dp
            .create_publisher(&qos(true, false, 10))
            .map_err(|e| anyhow!("a DDS publisher: {e}"))?;
        let ma = "visualization_msgs/msg/MarkerArray";
        let w = |own: &str, ty: &str, latched: bool| writer(dp, &p, &names.topic(own), ty, latched);
        let stops = if names.private {
            None
        } else {
            Some(super::writer_with(
                dp,
                &p,
                &names.ros.remapped("~/stops", &names.node),
                <iasm_ros::msg::Stop as iasm_ros::msg::Message>::NAME,
                qos(true, true, STOP_HISTORY),
            )?)
        };
        Ok(Self {
            stops,
            stops_sent: 0,
            sources: w(rosmap::SOURCES_TOPIC, ma, false)?,
            doas: w(rosmap::DOAS_TOPIC, ma, false)?,
            path: w(rosmap::PATH_TOPIC, "nav_msgs/msg/Path", false)?,
            source_poses: w(
                rosmap::SOURCE_POSES_TOPIC,
                "geometry_msgs/msg/PoseArray",
                false,
            )?,
            map: w(NODE_MAP_TOPIC, "nav_msgs/msg/OccupancyGrid", true)?,
            changes: None,
            grid_sent: None,
        })
    }

    /// With `prior`, publishes what changed against a prior map on `/iasm/changes` too.
    pub fn with_changes(
        mut self,
        dp: &DomainParticipant,
        names: &Names,
        prior: bool,
    ) -> Result<Self> {
        if prior {
            let p = dp
                .create_publisher(&qos(true, false, 10))
                .map_err(|e| anyhow!("a DDS publisher: {e}"))?;
            self.changes = Some(writer(
                dp,
                &p,
                &names.topic(rosmap::CHANGES_TOPIC),
                "visualization_msgs/msg/MarkerArray",
                false,
            )?);
        }
        Ok(self)
    }

    /// Publishes the stop `s` of the run `run` on `~/stops`.
    fn publish_stop(&mut self, run: &str, s: &crate::live::LiveStopRow) -> Result<()> {
        use iasm_ros::msg::Message;
        let m = iasm_ros::msg::Stop {
            header: iasm_ros::msg::Header::new(rosmap::FRAME, s.arrived_ns),
            run: run.to_owned(),
            index: self.stops_sent,
            pose: [s.pose.x, s.pose.y, s.pose.theta],
            doas_deg: s.doas_deg.clone(),
            cut: s.cut,
            method: s.method.to_string(),
        };
        if let Some(w) = &self.stops {
            w.write(raw::Cdr(m.to_cdr()), None)
                .map_err(|e| anyhow!("publishing a stop: {e:?}"))?;
        }
        self.stops_sent += 1;
        Ok(())
    }

    pub fn publish(&mut self, m: &MapMessages) -> Result<()> {
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
        if let (Some(w), Some(changes)) = (&self.changes, &m.changes) {
            send(w, changes.to_cdr(), rosmap::CHANGES_TOPIC)?;
        }
        send(
            &self.source_poses,
            m.source_poses.to_cdr(),
            rosmap::SOURCE_POSES_TOPIC,
        )
    }

    /// Waits until every reliable reader of every topic has acknowledged what was
    /// published, or until `max` has passed for a topic (a reader that vanished).
    pub fn wait_for_acknowledgments(&self, max: Duration) {
        for w in self.stops.iter().chain(self.changes.iter()).chain([
            &self.source_poses,
            &self.sources,
            &self.doas,
            &self.path,
            &self.map,
        ]) {
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
pub(super) struct Log {
    seen: HashMap<String, u64>,
}

impl Log {
    pub fn warn(&mut self, what: &str) {
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

/// The node's subscriptions, and when each kind of message last came.
struct Inputs {
    subscriber: rustdds::Subscriber,
    /// The graph's topic -> (the node's name of it, type, reader).
    readers: BTreeMap<String, (String, String, Reader)>,
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
    /// reader knows, that is the node's to read (in its namespace, or named by a remap;
    /// not its own outputs): best effort, or reliable and transient local where the
    /// publisher offers that.
    fn discover(&mut self, dp: &DomainParticipant, names: &Names) -> Result<()> {
        let ours = names.ros.resolve("iasm/", &names.node);
        for w in dp.discovered_writers() {
            let d = &w.publication_topic_data;
            let Some((topic, ty)) = ros_names(&d.topic_name, &d.type_name) else {
                continue;
            };
            if self.readers.contains_key(&topic) || Kind::of(&ty).is_none() {
                continue;
            }
            let Some(own) = names.ros.own_name(&topic, &names.node) else {
                continue;
            };
            if own.starts_with(&ours) || topic.starts_with("/iasm/") {
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
                "subscribed to {topic}{} ({ty}{})",
                if own == topic {
                    String::new()
                } else {
                    format!(" as {own}")
                },
                if latched { ", transient local" } else { "" }
            );
            self.readers.insert(topic, (own, ty, r));
        }
        Ok(())
    }

    /// Hands every message waiting to `live`; how many there were.
    fn take(&mut self, live: &mut LiveMapper, log: &mut Log, now_ns: i64) -> usize {
        let mut got = 0usize;
        for (own, ty, r) in self.readers.values_mut() {
            let topic = own.as_str();
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
                        if let Some(w) = live.push(topic, ty, now_ns, &s.value().0) {
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
    let names = Names {
        ros: a.ros.clone(),
        node: a.node_name.clone(),
        private: false,
    };
    let mut read = a.run.read_options()?;
    read.audio_topic = names.option(read.audio_topic);
    read.pose_topic = names.option(read.pose_topic);
    read.odom_topic = names.option(read.odom_topic);
    read.map_topic = names.option(read.map_topic);
    let mut live = LiveMapper::new(settings, read, a.run.stop_options()?, a.seed)?
        .with_pending_audio(a.pending_audio)?;
    if let Some(path) = &a.prior {
        let prior = crate::mapfile::MapFile::read(path).context("--prior")?;
        if let Some(frame) = prior.frame_id.as_deref().filter(|&f| f != rosmap::FRAME) {
            anyhow::bail!(
                "--prior {}: its frame is {frame:?}; the node maps in {:?}",
                path.display(),
                rosmap::FRAME
            );
        }
        live = live.with_prior(prior);
    }
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }
    let params = NodeParams::new(&a.command_line)?;
    let node_name = a.ros.node_name.as_deref().unwrap_or(&a.node_name);
    let (_ctx, mut node, dp) = participant(
        a.domain_id,
        a.ros.namespace(),
        node_name,
        params.node_options(),
    )?;
    // ros2-client's spinner answers the parameter services; it runs until the node goes.
    let spinner = node
        .spinner()
        .map_err(|e| anyhow!("the node's parameter services: {e:?}"))?;
    std::thread::spawn(move || futures::executor::block_on(spinner.spin()));
    let mut services = Services::new(&mut node, &names.fq())?;
    let mut inputs = Inputs::new(&dp)?;
    let mut clock = Clock::new(&dp, &inputs.subscriber)?;
    let sim_time = || {
        matches!(
            node.get_parameter("use_sim_time"),
            Some(ros2_client::ParameterValue::Boolean(true))
        )
    };
    let mut sink = Sink {
        out: Outputs::new(&dp, &names)?.with_changes(&dp, &names, a.prior.is_some())?,
        run: names.fq(),
        mcap: a.mcap.as_deref().map(rosmap::McapFile::new).transpose()?,
        json: a.out.clone(),
        current: None,
        now_ns: 0,
    };
    let mut save_to = a.save_to.clone();
    let mut log = Log::default();
    let mut last_discovery = Instant::now() - Duration::from_secs(10);
    let mut last_step = Instant::now();
    // --until-idle counts from the last message, or from the node's start when none came.
    let started = Instant::now();
    eprintln!(
        "iasm ros2: node {} on DDS domain {}; listening for audio, poses and the map (Ctrl-C ends the run with its final map)",
        names.fq(),
        a.domain_id
    );
    while !stop.load(Ordering::SeqCst) {
        sink.now_ns = clock.now_ns(sim_time());
        if last_discovery.elapsed() >= Duration::from_millis(250) {
            last_discovery = Instant::now();
            inputs.discover(&dp, &names)?;
        }
        let got = inputs.take(&mut live, &mut log, sink.now_ns);
        inputs.check_poses(&mut log);
        if let Some(changed) = params.take_changed() {
            match changed.and_then(|c| {
                live.set_settings(c.settings.settings()?, c.seed)?;
                Ok(c)
            }) {
                Ok(c) => {
                    save_to = c.save_to;
                    eprintln!(
                        "parameters changed: the settings take effect at the next stop (method {})",
                        live.settings().ssl.method
                    );
                }
                Err(e) => log.warn(&format!("parameters: not applied: {e:#}")),
            }
        }
        services.serve(|ask| answer(ask, &mut live, &mut sink, &save_to));
        if last_step.elapsed() >= Duration::from_millis(200) {
            last_step = Instant::now();
            step(&mut live, &mut sink, &mut log, false)?;
        }
        if let Some(idle) = idle_for(a.until_idle, inputs.last_message, started) {
            match inputs.last_message {
                Some(_) => eprintln!("no message for {idle} s: the run is over"),
                None => eprintln!(
                    "no message at all in {idle} s since the node started: the run is over"
                ),
            }
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

/// `--until-idle S` when it has run out: S seconds since the last message, or since
/// `started` when none came.
pub(super) fn idle_for(
    until_idle: Option<f64>,
    last_message: Option<Instant>,
    started: Instant,
) -> Option<f64> {
    until_idle.filter(|&idle| last_message.unwrap_or(started).elapsed().as_secs_f64() > idle)
}

/// What a service call did.
fn answer(
    ask: Ask,
    live: &mut LiveMapper,
    sink: &mut Sink,
    save_to: &std::path::Path,
) -> TriggerResponse {
    let json = |map: &asm::MapResult| serde_json::to_string_pretty(&live.report(map, false));
    let (success, message) = match (ask, &sink.current) {
        (Ask::Clear, _) => {
            let n = live.clear();
            sink.current = None;
            (true, format!("cleared: {n} stops forgotten"))
        }
        (_, None) => (false, "no stop mapped yet".to_owned()),
        (Ask::Get, Some(map)) => match json(map) {
            Ok(j) => (true, j),
            Err(e) => (false, e.to_string()),
        },
        (Ask::Save, Some(map)) => match json(map)
            .map_err(anyhow::Error::from)
            .and_then(|j| crate::output::write_atomic(save_to, j.as_bytes()))
        {
            Ok(()) => (
                true,
                format!(
                    "{} sources over {} stops written to {}",
                    map.sources.len(),
                    live.stops().len(),
                    save_to.display()
                ),
            ),
            Err(e) => (false, format!("{}: {e:#}", save_to.display())),
        },
    };
    eprintln!(
        "service {ask:?}: {}",
        if success && ask == Ask::Get {
            "the map sent"
        } else {
            &message
        }
    );
    TriggerResponse { success, message }
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
            say_sources(&fin);
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

/// The final map's sources, a line each.
pub(super) fn say_sources(map: &asm::MapResult) {
    for (k, s) in map.sources.iter().enumerate() {
        println!(
            "  s{} ({:.3}, {:.3}) m, {} DoAs",
            k + 1,
            s.x,
            s.y,
            s.observations
        );
    }
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

/// Where each map update goes: the topics, the MCAP file, the JSON; and the map now.
struct Sink {
    out: Outputs,
    /// The run's name on `~/stops`: the node's fully qualified name.
    run: String,
    mcap: Option<rosmap::McapFile>,
    json: Option<std::path::PathBuf>,
    /// The last map published (the services' "current map").
    current: Option<asm::MapResult>,
    /// The node's time now (ns since the epoch): the system's, or /clock's.
    now_ns: i64,
}

impl Sink {
    fn publish(&mut self, live: &LiveMapper, map: &asm::MapResult, final_map: bool) -> Result<()> {
        self.current = Some(map.clone());
        let t = self.now_ns;
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
        if let Some(s) = live.stops().last() {
            sink.out.publish_stop(&sink.run, s)?;
        }
        sink.publish(live, &u.map, false)?;
    }
    Ok(())
}
