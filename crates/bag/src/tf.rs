//! The robot's poses out of `/tf`, for bags that record no pose topic (Cartographer, for
//! one, publishes its map-frame pose only as a transform).
//!
//! `tf2_msgs/TFMessage` carries transforms between frames, each a parent, a child and the
//! child's pose in the parent; `/tf_static` those that never change. The robot's pose in
//! the map is the chain from the tree's root down to the robot's base frame
//! (`base_footprint`, else `base_link`, or the one named): `map → odom → base_link`, each
//! link taken at the same time (linear between its samples, held beyond its ends). The
//! chain is sampled where its most often published link was: the odometry's rate.
//! When the chain passes through `odom`, the part below it is the odometry the stops are
//! found by ([`crate::stops`]), and the part above it (a localiser's correction) carries
//! each stop's pose into the map's frame.

use std::collections::HashMap;

use geom::Pose;

use crate::msg::Transform;
use crate::track::{TimedPose, compose, pose_at};

/// The base frames tried, in order, when none is named.
pub const BASE_FRAMES: [&str; 2] = ["base_footprint", "base_link"];

/// One link of the tree: its parent and its samples (ns, pose); one sample for a static one.
struct Link {
    parent: String,
    samples: Vec<(i64, Option<i64>, Pose)>,
}

/// The robot's track out of the transforms.
#[derive(Debug)]
pub struct Track {
    /// The root frame the poses are given in (`map`, or `odom` without a localiser).
    pub frame: String,
    /// The base frame whose poses they are.
    pub base: String,
    /// The chain root → base at each sample of its most often published link: (receipt ns,
    /// stamp, pose).
    pub poses: Vec<(i64, Option<i64>, Pose)>,
    /// The chain `odom` → base at the same times, when `odom` lies strictly between.
    pub odometry: Vec<(i64, Option<i64>, Pose)>,
}

fn bare(frame: &str) -> String {
    frame.trim_start_matches('/').to_string()
}

/// The track of `base` (or the first of [`BASE_FRAMES`] that the tree has) from the
/// transforms `messages` (receipt ns, transforms), their times being the stamps.
///
/// # Errors
/// No base frame in the tree, or a loop in it.
pub fn track(messages: &[(i64, Vec<Transform>)], base: Option<&str>) -> Result<Track, String> {
    let mut links: HashMap<String, Link> = HashMap::new();
    for (t, transforms) in messages {
        for tr in transforms {
            let link = links.entry(bare(&tr.child)).or_insert_with(|| Link {
                parent: bare(&tr.parent),
                samples: Vec::new(),
            });
            // A frame has one parent; a transform that gives it another is not ours to mix in.
            if link.parent == bare(&tr.parent) {
                link.samples.push((*t, tr.stamp_ns, tr.pose));
            }
        }
    }
    for link in links.values_mut() {
        link.samples.sort_by_key(|s| s.1.unwrap_or(s.0));
    }
    let base = match base {
        Some(b) => bare(b),
        None => BASE_FRAMES
            .iter()
            .find(|b| links.contains_key(**b))
            .map(|b| (*b).to_string())
            .ok_or_else(|| {
                format!(
                    "no {} frame in the transforms (frames: {}): name the robot's with --base-frame",
                    BASE_FRAMES.join(" or "),
                    {
                        let mut f: Vec<&String> = links.keys().collect();
                        f.sort();
                        f.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
                    }
                )
            })?,
    };
    // The chain from the base up to the root.
    let mut chain: Vec<&str> = vec![base.as_str()];
    while let Some(link) = links.get(*chain.last().expect("a frame")) {
        if chain.contains(&link.parent.as_str()) {
            return Err(format!("the transforms loop through {}", link.parent));
        }
        chain.push(link.parent.as_str());
    }
    if chain.len() < 2 {
        return Err(format!("no transform has {base} as its child"));
    }
    let root = chain.last().expect("a root").to_string();
    // The chain is sampled where its most often published link was (the odometry's, below
    // a static link to a sensor's frame or beside a localiser's slower correction).
    let densest = chain[..chain.len() - 1]
        .iter()
        .map(|child| &links[*child])
        .max_by_key(|l| l.samples.len())
        .expect("a link");
    // Each link of the chain as a track in seconds, for interpolation.
    let tracks: Vec<Vec<TimedPose>> = chain[..chain.len() - 1]
        .iter()
        .map(|child| {
            links[*child]
                .samples
                .iter()
                .map(|s| TimedPose {
                    t: s.1.unwrap_or(s.0) as f64 * 1e-9,
                    pose: s.2,
                })
                .collect()
        })
        .collect();
    // The pose of the base in the frame `chain[above]`: the links below it composed.
    let series = |time: f64, above: usize| -> Pose {
        tracks[..above]
            .iter()
            .rev()
            .fold(Pose::new(0.0, 0.0, 0.0), |p, link| {
                compose(p, pose_at(link, time))
            })
    };
    let odom_at = chain
        .iter()
        .position(|f| *f == "odom")
        .filter(|&k| k + 1 < chain.len());
    let mut poses = Vec::with_capacity(densest.samples.len());
    let mut odometry = Vec::new();
    for &(t, stamp, _) in &densest.samples {
        let time = stamp.unwrap_or(t) as f64 * 1e-9;
        poses.push((t, stamp, series(time, chain.len() - 1)));
        if let Some(k) = odom_at {
            odometry.push((t, stamp, series(time, k)));
        }
    }
    Ok(Track {
        frame: root,
        base,
        poses,
        odometry,
    })
}
