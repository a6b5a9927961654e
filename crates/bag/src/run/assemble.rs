//! A robot run from the messages a bag kept ([`assemble`]): which topics hold the audio,
//! the poses and the map, their messages decoded, and one clock for all.

use std::collections::HashMap;

use geom::Pose;

use super::*;
use crate::msg::Embedded;

/// A pose series: each message's receipt time and stamp (ns) and its pose.
type Series = Vec<(i64, Option<i64>, Pose)>;

/// A topic's messages' receipt times and stamps (ns).
type Times = Vec<(i64, Option<i64>)>;

/// Where the poses came from: the named series and the frame it gives, and the odometry
/// that finds the stops (empty without one).
struct PoseSources {
    name: String,
    poses: Series,
    frame: Option<String>,
    odom_name: Option<String>,
    odometry: Series,
}

/// The kept messages of each topic, and how each topic is encoded.
struct Messages<'a> {
    raw: &'a HashMap<String, Raw>,
    encodings: &'a HashMap<String, Encoding>,
}

impl Messages<'_> {
    fn encoding(&self, topic: &str) -> Encoding {
        self.encodings.get(topic).copied().unwrap_or(Encoding::Ros1)
    }

    fn of(&self, topic: &str) -> &[(i64, Vec<u8>)] {
        self.raw.get(topic).map_or(&[][..], Vec::as_slice)
    }

    /// A pose topic's poses, and the frame its first message gives.
    fn poses(&self, topic: &TopicInfo) -> Result<(Series, Option<String>)> {
        let k = Kind::of(&topic.msg_type).expect("a pose topic");
        let raw = self.of(&topic.topic);
        let mut out = Vec::with_capacity(raw.len());
        let mut frame = None;
        for (i, (t, bytes)) in raw.iter().enumerate() {
            let p = msg::pose(k, self.encoding(&topic.topic), bytes)
                .map_err(|what| message_error(topic, i, what))?;
            if i == 0 {
                frame = p.frame_id;
            }
            out.push((*t, p.stamp_ns, p.pose));
        }
        Ok((out, frame))
    }
}

pub(crate) fn assemble(summary: &Summary, kept: Kept, options: &ReadOptions) -> Result<Run> {
    let Kept {
        raw,
        audio: mut audio_raw,
        encodings,
        lag_ns: kept_lag,
        ..
    } = kept;
    let msgs = Messages {
        raw: &raw,
        encodings: &encodings,
    };
    let encoding = |topic: &str| msgs.encoding(topic);
    let start_ns = summary.spans.values().map(|s| s.0).min().unwrap_or(0);
    let rel = |ns: i64| (ns - start_ns) as f64 * 1e-9;
    let topics = topic_infos(summary, &rel);
    let mut notes = Vec::new();
    let audio = audio_topic(&topics, options, &mut notes)?;
    let poses = pose_sources(&topics, &msgs, options, &mut notes)?;
    let AudioRaw {
        msgs: audio_msgs,
        bytes: audio_bytes,
        embedded,
    } = audio_raw.remove(&audio.topic).unwrap_or_default();
    drop(audio_raw);
    let format = audio_format(options.format, embedded, &topics, &audio.topic, &msgs)?;
    let (map_topic, map) = robot_map(
        &topics,
        options.map_topic.as_deref(),
        &raw,
        &encoding,
        poses.frame.as_deref(),
        &mut notes,
    )?;
    let (mut audio_msgs, mut poses) = (audio_msgs, poses);
    // Stamps that lie are judged against the clock the run began on: the usual lag of its
    // first messages, over every topic (a live run keeps the one it found first, since it
    // forgets its first messages). A topic whose own lag differs from it by more than
    // CLOCK_MISMATCH_S keeps another clock (below), and is judged against its own.
    let pose_msgs = poses.poses.iter().chain(&poses.odometry);
    let as_times = |m: &(i64, Option<i64>, Pose)| (m.0, m.1, ());
    let mut all: Vec<(i64, Option<i64>, ())> = audio_msgs
        .iter()
        .map(|m| (m.0, m.1, ()))
        .chain(pose_msgs.map(as_times))
        .filter(|m| m.1.is_some())
        .collect();
    all.sort_by_key(|m| m.0);
    let mut stamp_jumps = Vec::new();
    let clock_lag_ns = kept_lag.or_else(|| median_lag(&all[..all.len().min(FIRST_MESSAGES)]));
    if let Some(run_lag) = clock_lag_ns {
        let lag_for = |own: Option<i64>| match own {
            Some(own) if ((own - run_lag) as f64 * 1e-9).abs() > CLOCK_MISMATCH_S => own,
            _ => run_lag,
        };
        let lag = lag_for(median_lag(&audio_msgs));
        stamp_jumps.extend(rectify_stamps(&audio.topic, &mut audio_msgs, lag));
        let lag = lag_for(median_lag(&poses.poses));
        stamp_jumps.extend(rectify_stamps(&poses.name, &mut poses.poses, lag));
        if let Some(odom) = &poses.odom_name {
            let lag = lag_for(median_lag(&poses.odometry));
            stamp_jumps.extend(rectify_stamps(odom, &mut poses.odometry, lag));
        }
    }
    notes.extend(stamp_jumps.iter().map(|j| j.describe(start_ns)));
    let times = |m: &[(i64, Option<i64>, Pose)]| m.iter().map(|m| (m.0, m.1)).collect();
    let use_stamps = one_clock(
        &[
            (
                audio.topic.as_str(),
                audio_msgs.iter().map(|m| (m.0, m.1)).collect(),
            ),
            (poses.name.as_str(), times(&poses.poses)),
            (
                poses.odom_name.as_deref().unwrap_or(""),
                times(&poses.odometry),
            ),
        ],
        &mut notes,
    );
    let time = |t: i64, s: Option<i64>| rel(if use_stamps { s.unwrap_or(t) } else { t });
    let segments = segments(&audio_msgs, format, &time)
        .map_err(|what| Error::Audio(format!("topic {}: {what}", audio.topic)))?;
    let timed = |m: &[(i64, Option<i64>, Pose)]| {
        let mut v: Vec<TimedPose> = m
            .iter()
            .map(|&(t, s, pose)| TimedPose {
                t: time(t, s),
                pose,
            })
            .collect();
        v.sort_by(|a, b| a.t.total_cmp(&b.t));
        v
    };
    Ok(Run {
        start_ns,
        audio_topic: audio.topic.clone(),
        format,
        segments,
        audio: audio_bytes,
        pose_topic: poses.name,
        poses: timed(&poses.poses),
        odom_topic: poses.odom_name,
        odometry: timed(&poses.odometry),
        pose_frame: poses.frame,
        map_topic,
        map,
        truncated: summary.truncated,
        notes,
        topics,
        clock_lag_ns,
        stamp_jumps,
    })
}

/// Each topic once (its connections merged): type, messages, and the span of their times
/// (s, by `rel` from the bag's time in ns).
fn topic_infos(summary: &Summary, rel: &dyn Fn(i64) -> f64) -> Vec<TopicInfo> {
    summary
        .connections
        .iter()
        .fold(Vec::<TopicInfo>::new(), |mut acc, c| {
            let n = summary.counts.get(&c.id).copied().unwrap_or(0);
            let span = summary
                .spans
                .get(&c.id)
                .map_or((0.0, 0.0), |s| (rel(s.0), rel(s.1)));
            match acc.iter_mut().find(|t| t.topic == c.topic) {
                Some(t) => {
                    t.messages += n;
                    t.span_s = (t.span_s.0.min(span.0), t.span_s.1.max(span.1));
                }
                None => acc.push(TopicInfo {
                    topic: c.topic.clone(),
                    msg_type: c.msg_type.clone(),
                    messages: n,
                    span_s: span,
                }),
            }
            acc
        })
}

/// The audio topic: the one named, or the only one, or of a stream recorded twice the
/// stamped copy.
fn audio_topic(
    topics: &[TopicInfo],
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<TopicInfo> {
    match (options.audio_topic.as_deref(), same_stream_twice(topics)) {
        (None, Some(stamped)) => {
            notes.push(format!(
                "audio from {}, the stamped copy of the stream beside it",
                stamped.topic
            ));
            Ok(stamped)
        }
        (named, _) => choose(topics, named, "audio", "--audio-topic", |k| k.is_audio()),
    }
}

/// The poses and the odometry for the stops: from /tf when a transform topic is named, or
/// when there is no pose topic; else from the pose topics.
fn pose_sources(
    topics: &[TopicInfo],
    msgs: &Messages<'_>,
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<PoseSources> {
    let kind = |t: &TopicInfo| Kind::of(&t.msg_type);
    let pose_candidates: Vec<&TopicInfo> = topics
        .iter()
        .filter(|t| kind(t).is_some_and(Kind::is_pose))
        .collect();
    let tf_topics: Vec<&TopicInfo> = topics
        .iter()
        .filter(|t| kind(t) == Some(Kind::Tf))
        .collect();
    let from_tf = match options.pose_topic.as_deref() {
        Some(named) => tf_topics.iter().any(|t| t.topic == named),
        None => pose_candidates.is_empty() && !tf_topics.is_empty(),
    };
    if from_tf {
        return poses_from_tf(&tf_topics, msgs, options, notes);
    }
    let pose = match &options.pose_topic {
        Some(_) => choose(
            topics,
            options.pose_topic.as_deref(),
            "pose",
            "--pose-topic",
            Kind::is_pose,
        )?,
        None => {
            let others: Vec<&&TopicInfo> = pose_candidates
                .iter()
                .filter(|t| kind(t) != Some(Kind::Odometry))
                .collect();
            if pose_candidates.len() > 1 && others.len() == 1 {
                notes.push(format!(
                    "poses from {} ({}), stops found by odometry",
                    others[0].topic, others[0].msg_type
                ));
                (*others[0]).clone()
            } else {
                choose(topics, None, "pose", "--pose-topic", Kind::is_pose)?
            }
        }
    };
    let odom = match options.odom_topic.as_deref() {
        Some("") => None,
        Some(name) => {
            let t = choose(
                topics,
                Some(name),
                "odometry",
                "--odom-topic",
                Kind::is_pose,
            )?;
            (t.topic != pose.topic).then_some(t)
        }
        None if kind(&pose) != Some(Kind::Odometry) => {
            let odoms: Vec<&&TopicInfo> = pose_candidates
                .iter()
                .filter(|t| kind(t) == Some(Kind::Odometry))
                .collect();
            (odoms.len() == 1).then(|| (*odoms[0]).clone())
        }
        None => None,
    };
    let (poses, frame) = msgs.poses(&pose)?;
    let odometry = match &odom {
        Some(o) => msgs.poses(o)?.0,
        None => Vec::new(),
    };
    Ok(PoseSources {
        name: pose.topic,
        poses,
        frame,
        odom_name: odom.map(|o| o.topic),
        odometry,
    })
}

/// The base's track through the transform tree of `tf_topics`, and its odometry.
fn poses_from_tf(
    tf_topics: &[&TopicInfo],
    msgs: &Messages<'_>,
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<PoseSources> {
    let mut messages = Vec::new();
    for t in tf_topics {
        for (i, (rt, bytes)) in msgs.of(&t.topic).iter().enumerate() {
            let trs = msg::transforms(msgs.encoding(&t.topic), bytes)
                .map_err(|what| message_error(t, i, what))?;
            messages.push((*rt, trs));
        }
    }
    let track = crate::tf::track(&messages, options.base_frame.as_deref())
        .map_err(|e| Error::Topic(format!("poses from /tf: {e}")))?;
    notes.push(format!("poses from /tf: {} in {}", track.base, track.frame));
    let odom_name = (!track.odometry.is_empty()).then(|| format!("/tf (odom -> {})", track.base));
    Ok(PoseSources {
        name: format!("/tf ({} -> {})", track.frame, track.base),
        poses: track.poses,
        frame: Some(track.frame),
        odom_name,
        odometry: track.odometry,
    })
}

/// The audio's format: as given, or as the messages say (AudioStamped), or from the
/// audio-info topic beside it; refused without channels or a rate.
fn audio_format(
    given: Option<AudioFormat>,
    embedded: Option<Embedded>,
    topics: &[TopicInfo],
    audio: &str,
    msgs: &Messages<'_>,
) -> Result<AudioFormat> {
    let format = match (given, embedded) {
        (Some(f), _) => f,
        (None, Some(e)) => AudioFormat {
            channels: u16::try_from(e.channels).unwrap_or(0),
            sample_rate: u32::try_from(e.rate).unwrap_or(0),
            sample: e.sample.parse()?,
        },
        (None, None) => format_from_info(topics, audio, msgs.raw, &|t: &str| msgs.encoding(t))?,
    };
    if format.channels == 0 || format.sample_rate == 0 {
        return Err(Error::Audio(format!(
            "{audio}: audio of {} channels at {} Hz",
            format.channels, format.sample_rate
        )));
    }
    Ok(format)
}

/// Whether the stamps can time every topic (one clock for all): not when some topic's
/// stamps lie more than [`CLOCK_MISMATCH_S`] from their receipt times (median), and then
/// a note says so. `offsets`: per topic, each message's receipt time and stamp.
fn one_clock(offsets: &[(&str, Times)], notes: &mut Vec<String>) -> bool {
    let mismatch = offsets.iter().find_map(|(topic, times)| {
        let mut d: Vec<f64> = times
            .iter()
            .filter_map(|(t, s)| s.map(|s| (t - s) as f64 * 1e-9))
            .collect();
        if d.is_empty() {
            return None;
        }
        d.sort_by(f64::total_cmp);
        let median = d[d.len() / 2];
        (median.abs() > CLOCK_MISMATCH_S).then(|| (topic.to_string(), median))
    });
    if let Some((topic, median)) = &mismatch {
        notes.push(format!(
            "the stamps of {topic} lie {median:.1} s from the times they were recorded (another \
             clock): every topic is timed by when it was recorded"
        ));
    }
    mismatch.is_none()
}
