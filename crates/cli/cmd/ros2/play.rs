//! `iasm ros2-play`: a recorded ROS 2 bag published on its topics at its pace, its stamps
//! moved to now, as the robot published it; and, when asked, the node's sources heard
//! back.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use bag::msg::Kind;
use rustdds::DomainParticipant;

use crate::Outcome;
use crate::args::Ros2PlayArgs;
use crate::rosmap;

use super::{Reader, Writer, dds_names, now_ns, participant, qos, raw, reader, writer};

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

/// The longest pause the player keeps between two messages (s): a robot's topics publish
/// many times a second, so a longer one is a recorder paused, or a log time that is wrong
/// (one message 31 years late would hold the run for ever).
pub const MAX_PLAY_GAP_S: f64 = 5.0;

/// When a message is played, from the first's: its log time, with every pause between two
/// messages cut to [`MAX_PLAY_GAP_S`]; `cut_s` is the pause cut there.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Due {
    at: Duration,
    cut_s: Option<f64>,
}

/// The play times of messages whose log times (ns) are `times`, in order.
fn play_times(times: impl IntoIterator<Item = i64>) -> Vec<Due> {
    let mut out = Vec::new();
    let (mut last, mut at) = (None::<i64>, Duration::ZERO);
    for t in times {
        let gap_s = last.map_or(0.0, |l| (t - l).max(0) as f64 * 1e-9);
        let cut_s = (gap_s > MAX_PLAY_GAP_S).then_some(gap_s);
        at += Duration::from_secs_f64(gap_s.min(MAX_PLAY_GAP_S));
        out.push(Due { at, cut_s });
        last = Some(t);
    }
    out
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
    /// A listener to the node's sources on `topic` ([`rosmap::SOURCE_POSES_TOPIC`] in the
    /// namespace) when `listen`, else one that hears nothing.
    fn new(dp: &DomainParticipant, listen: bool, topic: &str) -> Result<Self> {
        let reader = if listen {
            let sub = dp
                .create_subscriber(&qos(true, false, 10))
                .map_err(|e| anyhow!("a DDS subscriber: {e}"))?;
            let names = dds_names(topic, "geometry_msgs/msg/PoseArray");
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
    fn linger_and_write(
        mut self,
        linger_s: f64,
        path: &std::path::Path,
        topic: &str,
    ) -> Result<()> {
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
            "heard {} sources on {topic} (the last of {} updates)",
            self.heard.len(),
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
/// moved to now, as the robot that recorded them published them (with `--clock`: stamps
/// kept, and `/clock` at the bag's time before each message, as `ros2 bag play --clock`
/// publishes it). Under `--ros-args -r __ns:=/robot1` the bag's topics are taken as
/// relative to the namespace (`/audio` is played on `/robot1/audio`), and remaps rename
/// them.
///
/// # Errors
/// A bag that cannot be read or is not a ROS 2 bag, or DDS that cannot start.
pub fn play(a: &Ros2PlayArgs) -> Result<Outcome> {
    let node = crate::args::play_node_name();
    let topic = |t: &str| a.ros.remapped(t.trim_start_matches('/'), node);
    let mut msgs = bag_messages(&a.bag)?;
    for m in &mut msgs {
        m.0 = topic(&m.0);
    }
    let Some(first) = msgs.first().map(|m| m.2) else {
        bail!("{}: no message of a type iasm reads", a.bag.display());
    };
    let (_ctx, _node, dp) = participant(
        a.domain_id,
        a.ros.namespace(),
        a.ros.node_name.as_deref().unwrap_or(node),
        ros2_client::NodeOptions::new(),
    )?;
    let publisher = dp
        .create_publisher(&qos(true, false, 100))
        .map_err(|e| anyhow!("a DDS publisher: {e}"))?;
    let writers = play_writers(&dp, &publisher, &msgs)?;
    let clock = if a.clock {
        Some(writer(
            &dp,
            &publisher,
            "/clock",
            "rosgraph_msgs/msg/Clock",
            false,
        )?)
    } else {
        None
    };
    // The node's sources, when asked.
    let listen_on = topic(rosmap::SOURCE_POSES_TOPIC);
    let mut listener = Listener::new(&dp, a.listen.is_some(), &listen_on)?;
    wait_for_subscribers(&dp, &writers, a.wait_s);
    let start = Instant::now();
    let shift = if a.clock { 0 } else { now_ns() - first };
    let due = play_times(msgs.iter().map(|m| m.2));
    let mut skipped: BTreeMap<String, usize> = BTreeMap::new();
    for ((topic, ty, t, mut data), due) in msgs.into_iter().zip(due) {
        if let Some(gap) = due.cut_s {
            eprintln!(
                "warning: the bag's times jump by {gap:.1} s after {:.1} s (to a message of \
                 {topic}): played as a gap of {MAX_PLAY_GAP_S} s",
                (t - first) as f64 * 1e-9 - gap
            );
        }
        while start.elapsed() < due.at {
            listener.take();
            std::thread::sleep(
                due.at
                    .saturating_sub(start.elapsed())
                    .min(Duration::from_millis(5)),
            );
        }
        if let Some(c) = &clock {
            c.write(super::params::clock_message(t), None)
                .map_err(|e| anyhow!("publishing on /clock: {e:?}"))?;
        }
        // A message that is not little-endian CDR of its type (as a node refuses it) is
        // skipped and counted; the run goes on.
        if data.get(..4) != Some(&iasm_ros::cdr::CDR_LE[..])
            || shift_stamps(Kind::of(&ty).expect("kept"), &mut data, shift).is_err()
        {
            *skipped.entry(topic).or_default() += 1;
            continue;
        }
        writers[&topic]
            .write(raw::Cdr(data), None)
            .map_err(|e| anyhow!("publishing on {topic}: {e:?}"))?;
    }
    for (topic, n) in &skipped {
        eprintln!(
            "warning: {n} message{} of {topic} skipped: not little-endian CDR of its type",
            if *n == 1 { "" } else { "s" }
        );
    }
    println!(
        "played {} in {:.1} s",
        a.bag.display(),
        start.elapsed().as_secs_f64()
    );
    if let Some(path) = &a.listen {
        listener.linger_and_write(a.linger_s, path, &listen_on)?;
    }
    Ok(Outcome::Success)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// See: issue 71 (`logtime_far_future.mcap`). Log times a second apart play a second
    /// apart; a message 31 years late plays MAX_PLAY_GAP_S after the one before, and says
    /// how far its time jumped; the messages after it keep their own spacing.
    #[test]
    fn r71_a_jump_in_log_times_plays_as_a_bounded_gap() {
        let far = 1_000_000_000_000_000_000i64;
        let due = play_times([0, 1_000_000_000, far, far + 500_000_000]);
        let at: Vec<f64> = due.iter().map(|d| d.at.as_secs_f64()).collect();
        assert_eq!(at, [0.0, 1.0, 1.0 + MAX_PLAY_GAP_S, 1.5 + MAX_PLAY_GAP_S]);
        assert_eq!(due[1].cut_s, None);
        let cut = due[2].cut_s.unwrap();
        assert!((cut - (far as f64 * 1e-9 - 1.0)).abs() < 1.0, "{cut}");
        assert_eq!(due[3].cut_s, None);
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
