//! `iasm ros2-merge`: the building's map from several robots' stops, live.
//!
//! **In.** Every robot's node publishes its stops on `~/stops` (`iasm_msgs/msg/Stop`:
//! pose and ranked DoAs, no audio), reliable and transient local, so that a merging node
//! that starts late is sent the stops before it. The merging node subscribes to each such
//! topic that discovery finds (or to `NODE/stops` of the nodes named), as robots join;
//! and to the building's grid (`--map-topic`, `/map`: reliable, transient local).
//!
//! **Out** (its own topics, `~/sources`, `~/doas`, `~/path`, `~/source_poses`, `~/map`,
//! as a robot's node publishes `iasm/...`): an update after every stop from any robot; on
//! Ctrl-C (or `--until-idle`) the full map over every stop, which is `iasm map --dataset
//! A --dataset B` on the runs (by name) ([`crate::merge`]).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Result, anyhow};
use asm::MapResult;
use iasm_ros::msg::Message;
use rustdds::DomainParticipant;

use crate::Outcome;
use crate::args::Ros2MergeArgs;
use crate::merge::{MergeMapper, MergedStop};
use crate::rosmap;

use super::node::{Log, Names, Outputs, STOP_HISTORY};
use super::{Reader, now_ns, participant, qos, reader, ros_names};

/// The merging node's subscriptions.
struct Inputs {
    subscriber: rustdds::Subscriber,
    /// The graph's topic -> its reader: robots' stops.
    stops: BTreeMap<String, Reader>,
    /// The building's grid.
    grid: Option<Reader>,
    last_message: Option<Instant>,
}

impl Inputs {
    /// Subscribes to every robot's `~/stops` found (of the nodes `robots`, when named) and
    /// to the grid on `map_topic`.
    fn discover(
        &mut self,
        dp: &DomainParticipant,
        robots: &[String],
        map_topic: Option<&str>,
    ) -> Result<()> {
        for w in dp.discovered_writers() {
            let d = &w.publication_topic_data;
            let Some((topic, ty)) = ros_names(&d.topic_name, &d.type_name) else {
                continue;
            };
            let names = (d.topic_name.clone(), d.type_name.clone());
            if ty == iasm_ros::msg::Stop::NAME && !self.stops.contains_key(&topic) {
                if !robots.is_empty()
                    && !robots
                        .iter()
                        .any(|r| topic == format!("{}/stops", r.trim_end_matches('/')))
                {
                    continue;
                }
                let r = reader(dp, &self.subscriber, names, qos(true, true, STOP_HISTORY))?;
                eprintln!("merging the stops of {topic}");
                self.stops.insert(topic, r);
            } else if Some(topic.as_str()) == map_topic
                && ty == "nav_msgs/msg/OccupancyGrid"
                && self.grid.is_none()
            {
                self.grid = Some(reader(dp, &self.subscriber, names, qos(true, true, 1))?);
                eprintln!("the building's map from {topic}");
            }
        }
        Ok(())
    }
}

/// Runs `iasm ros2-merge`: the merging node, until Ctrl-C (or `--until-idle`); then the
/// final map.
///
/// # Errors
/// Settings refused, DDS that cannot start, or outputs that cannot be written.
pub fn merge(a: &Ros2MergeArgs) -> Result<Outcome> {
    let mut mapper = MergeMapper::new(a.settings.settings()?, a.seed)?;
    let names = Names {
        ros: a.ros.clone(),
        node: a.node_name.clone(),
        private: true,
    };
    let map_topic = (a.map_topic != "none").then(|| names.ros.resolve(&a.map_topic, &names.node));
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }
    let node_name = a.ros.node_name.as_deref().unwrap_or(&a.node_name);
    let (_ctx, _node, dp) = participant(
        a.domain_id,
        a.ros.namespace(),
        node_name,
        ros2_client::NodeOptions::new().start_parameter_services(false),
    )?;
    let mut inputs = Inputs {
        subscriber: dp
            .create_subscriber(&qos(true, false, 100))
            .map_err(|e| anyhow!("a DDS subscriber: {e}"))?,
        stops: BTreeMap::new(),
        grid: None,
        last_message: None,
    };
    let mut out = Outputs::new(&dp, &names)?;
    let mut mcap = a.mcap.as_deref().map(rosmap::McapFile::new).transpose()?;
    let mut log = Log::default();
    let mut last_discovery = Instant::now() - Duration::from_secs(10);
    let started = Instant::now();
    eprintln!(
        "iasm ros2-merge: node {} on DDS domain {}; merging {} (Ctrl-C ends the run with its final map)",
        names.fq(),
        a.domain_id,
        if a.robots.is_empty() {
            "every robot's stops".to_owned()
        } else {
            a.robots.join(", ")
        }
    );
    let mut publish = |mapper: &MergeMapper, map: &MapResult, final_map: bool| -> Result<()> {
        let t = now_ns();
        if let Some(m) = mapper.messages(map, t) {
            out.publish(&m)?;
            if let Some(f) = mcap.as_mut() {
                f.add(&m, t)?;
            }
        }
        if let Some(path) = &a.out {
            let json = serde_json::to_string_pretty(&mapper.report(map, final_map))?;
            crate::output::write_atomic(path, json.as_bytes())?;
        }
        Ok(())
    };
    while !stop.load(Ordering::SeqCst) {
        if last_discovery.elapsed() >= Duration::from_millis(250) {
            last_discovery = Instant::now();
            inputs.discover(&dp, &a.robots, map_topic.as_deref())?;
        }
        let mut got = 0;
        if let Some(r) = &mut inputs.grid {
            while let Ok(Some(s)) = r.take_next_sample() {
                got += 1;
                match bag::msg::grid(bag::msg::Encoding::Cdr, &s.value().0)
                    .map_err(|e| anyhow!(e))
                    .and_then(|g| crate::bagset::grid_map(&g))
                {
                    Ok(g) => mapper.set_grid(g),
                    Err(e) => log.warn(&format!("the building's map unreadable: {e:#}")),
                }
            }
        }
        for (topic, r) in &mut inputs.stops {
            while let Ok(Some(s)) = r.take_next_sample() {
                got += 1;
                let stop = match iasm_ros::msg::Stop::from_cdr(&s.value().0) {
                    Ok(s) => s,
                    Err(e) => {
                        log.warn(&format!("{topic}: a stop unreadable: {e}"));
                        continue;
                    }
                };
                let (run, index) = (stop.run.clone(), stop.index);
                let merged = MergedStop {
                    run: stop.run,
                    index: stop.index,
                    arrived_ns: stop.header.stamp.ns(),
                    pose: asm::Pose {
                        x: stop.pose[0],
                        y: stop.pose[1],
                        theta: stop.pose[2],
                    },
                    doas_deg: stop.doas_deg,
                    cut: stop.cut,
                    method: stop.method,
                };
                match mapper.add(merged) {
                    Ok(Some(u)) => {
                        println!(
                            "{run} stop {:>3}  {:>3} stops  {:>2} sources  map {:.0} ms",
                            index + 1,
                            u.stops,
                            u.map.sources.len(),
                            u.map_ms
                        );
                        publish(&mapper, &u.map, false)?;
                    }
                    Ok(None) => {}
                    Err(e) => log.warn(&format!("{topic}: stop {} skipped: {e:#}", index + 1)),
                }
            }
        }
        if got > 0 {
            inputs.last_message = Some(Instant::now());
        }
        if let Some(idle) = super::node::idle_for(a.until_idle, inputs.last_message, started) {
            eprintln!("no stop for {idle} s: the run is over");
            break;
        }
        if got == 0 {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    match mapper.finish()? {
        Some(fin) => {
            publish(&mapper, &fin, true)?;
            println!(
                "{} stops of {} runs; final map (full, seed {}): {} sources",
                mapper.len(),
                inputs.stops.len(),
                a.seed,
                fin.sources.len()
            );
            super::node::say_sources(&fin);
        }
        None => println!("no stop was merged"),
    }
    if let Some(f) = mcap {
        f.finish()?;
    }
    std::thread::sleep(Duration::from_millis(200));
    out.wait_for_acknowledgments(Duration::from_secs(5));
    Ok(Outcome::Success)
}
