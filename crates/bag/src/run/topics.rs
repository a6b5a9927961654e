//! Which topics a run is read from (the module's **Topics**): the audio, its format, the
//! poses, odometry and the robot's map, named or chosen by type.

use super::*;

/// The occupancy grid topic (the one named, else the bag's only one, else `/map`) and its
/// last message when it can stand beside the poses: in their frame and square to it (a
/// map file's origin has no turn that every reader heeds); a note says why not otherwise.
pub(super) fn robot_map(
    topics: &[TopicInfo],
    named: Option<&str>,
    kept: &HashMap<String, Raw>,
    encoding: &impl Fn(&str) -> Encoding,
    pose_frame: Option<&str>,
    notes: &mut Vec<String>,
) -> Result<(Option<String>, Option<Grid>)> {
    let grids: Vec<&TopicInfo> = topics
        .iter()
        .filter(|t| Kind::of(&t.msg_type) == Some(Kind::OccupancyGrid))
        .collect();
    let topic = match named {
        Some("") => return Ok((None, None)),
        Some(name) => choose(topics, Some(name), "occupancy grid", "--map-topic", |k| {
            k == Kind::OccupancyGrid
        })?,
        None => match grids.as_slice() {
            [] => return Ok((None, None)),
            [one] => (*one).clone(),
            many => match many.iter().find(|t| t.topic == "/map") {
                Some(t) => (*t).clone(),
                None => {
                    notes.push(format!(
                        "{} occupancy grid topics and none is /map: no map taken (--map-topic names one)",
                        many.len()
                    ));
                    return Ok((None, None));
                }
            },
        },
    };
    let Some((_, bytes)) = kept.get(&topic.topic).and_then(|r| r.last()) else {
        return Ok((Some(topic.topic), None));
    };
    let grid = msg::grid(encoding(&topic.topic), bytes)
        .map_err(|what| message_error(&topic, topic.messages.saturating_sub(1), what))?;
    let bare = |f: &str| f.trim_start_matches('/').to_string();
    let refused = match pose_frame {
        Some(f) if bare(f) != bare(&grid.frame_id) => Some(format!(
            "the map {} is in the frame {:?} and the poses in {:?}: the map is left out (name a \
             pose topic in {:?} with --pose-topic, a localiser's)",
            topic.topic, grid.frame_id, f, grid.frame_id
        )),
        _ if grid.origin.theta.abs() > 1e-9 => Some(format!(
            "the map {}'s origin is turned by {:.2} degrees, which a ROS map file does not \
             carry: the map is left out",
            topic.topic,
            grid.origin.theta.to_degrees()
        )),
        _ => None,
    };
    if let Some(why) = refused {
        notes.push(why);
        return Ok((Some(topic.topic), None));
    }
    Ok((Some(topic.topic), Some(grid)))
}

/// A topic's namespace: all but its last name (`/mic` of `/mic/audio`).
pub(super) fn namespace(topic: &str) -> &str {
    topic.rsplit_once('/').map_or("", |(ns, _)| ns)
}

/// When the bag's audio topics are one stream published twice, unstamped and stamped, in
/// one namespace and as many messages (`audio_capture` publishes `audio` and
/// `audio_stamped`): the stamped one.
pub(super) fn same_stream_twice(topics: &[TopicInfo]) -> Option<TopicInfo> {
    let audio: Vec<&TopicInfo> = topics
        .iter()
        .filter(|t| Kind::of(&t.msg_type).is_some_and(Kind::is_audio))
        .collect();
    let [a, b] = audio.as_slice() else {
        return None;
    };
    let (plain, stamped) = match (Kind::of(&a.msg_type), Kind::of(&b.msg_type)) {
        (Some(Kind::AudioData), Some(Kind::AudioDataStamped)) => (a, b),
        (Some(Kind::AudioDataStamped), Some(Kind::AudioData)) => (b, a),
        _ => return None,
    };
    (namespace(&plain.topic) == namespace(&stamped.topic) && plain.messages == stamped.messages)
        .then(|| (*stamped).clone())
}

/// The topic for `role`: the one named (which must exist and fit), else the only one that
/// fits.
pub(super) fn choose(
    topics: &[TopicInfo],
    named: Option<&str>,
    role: &str,
    option: &str,
    fits: impl Fn(Kind) -> bool,
) -> Result<TopicInfo> {
    let fitting: Vec<&TopicInfo> = topics
        .iter()
        .filter(|t| Kind::of(&t.msg_type).is_some_and(&fits))
        .collect();
    let list = |ts: &[&TopicInfo]| {
        ts.iter()
            .map(|t| format!("{} ({}, {} messages)", t.topic, t.msg_type, t.messages))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(name) = named {
        return match topics.iter().find(|t| t.topic == name) {
            Some(t) if Kind::of(&t.msg_type).is_some_and(&fits) => Ok(t.clone()),
            Some(t) => Err(Error::Topic(format!(
                "{option} {name}: its type {} is not a {role} message{}",
                t.msg_type,
                if fitting.is_empty() {
                    String::new()
                } else {
                    format!("; {role} topics: {}", list(&fitting))
                }
            ))),
            None => Err(Error::Topic(format!(
                "{option} {name}: no such topic in the bag{}",
                if fitting.is_empty() {
                    String::new()
                } else {
                    format!("; {role} topics: {}", list(&fitting))
                }
            ))),
        };
    }
    match fitting.as_slice() {
        [one] => Ok((*one).clone()),
        [] => Err(Error::Topic(format!(
            "no {role} topic in the bag (it reads {}); its topics: {}",
            match role {
                "audio" => "audio_common_msgs/AudioData, AudioDataStamped and AudioStamped",
                _ =>
                    "nav_msgs/Odometry, geometry_msgs/PoseStamped, PoseWithCovarianceStamped and Pose2D, or tf2_msgs/TFMessage",
            },
            if topics.is_empty() {
                "none".to_string()
            } else {
                list(&topics.iter().collect::<Vec<_>>())
            }
        ))),
        many => Err(Error::Topic(format!(
            "{} {role} topics: {}; name one with {option}",
            many.len(),
            list(many)
        ))),
    }
}

/// The audio's format from the `AudioInfo` topic beside `audio` (the one in the same
/// namespace, else the only one).
pub(super) fn format_from_info(
    topics: &[TopicInfo],
    audio: &str,
    kept: &HashMap<String, Raw>,
    encoding: &impl Fn(&str) -> Encoding,
) -> Result<AudioFormat> {
    let infos: Vec<&TopicInfo> = topics
        .iter()
        .filter(|t| Kind::of(&t.msg_type) == Some(Kind::AudioInfo))
        .collect();
    let beside: Vec<&&TopicInfo> = infos
        .iter()
        .filter(|t| namespace(&t.topic) == namespace(audio))
        .collect();
    let info_topic = match (beside.as_slice(), infos.as_slice()) {
        ([one], _) => *one,
        (_, [one]) => one,
        _ => {
            return Err(Error::Audio(format!(
                "{} says nothing of its format ({}): give the channels, the sample rate and the \
                 sample format",
                audio,
                if infos.is_empty() {
                    "no audio_common_msgs/AudioInfo in the bag".to_string()
                } else {
                    format!("{} AudioInfo topics, none beside it", infos.len())
                }
            )));
        }
    };
    let raw = kept
        .get(&info_topic.topic)
        .and_then(|r| r.last())
        .ok_or_else(|| Error::Audio(format!("{}: no AudioInfo message", info_topic.topic)))?;
    let info: AudioInfo = msg::audio_info(encoding(&info_topic.topic), &raw.1)
        .map_err(|what| message_error(info_topic, 0, what))?;
    if !info.coding_format.is_empty() && !info.coding_format.eq_ignore_ascii_case("wave") {
        return Err(Error::Audio(format!(
            "{} is coded as {} ({}): localisation needs the raw samples of every channel; \
             record with audio_capture's format:=wave",
            audio, info.coding_format, info_topic.topic
        )));
    }
    Ok(AudioFormat {
        channels: u16::from(info.channels),
        sample_rate: info.sample_rate,
        sample: info.sample_format.parse().map_err(|e| match e {
            Error::Audio(m) => Error::Audio(format!("{}: {m}", info_topic.topic)),
            e => e,
        })?,
    })
}
