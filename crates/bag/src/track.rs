//! A robot's poses in time: a pose at a time, a track's pose between its samples, and
//! two poses composed. What the stops ([`crate::stops`]) and the transform tree
//! ([`crate::tf`]) both read a run's poses with.

use geom::{Pose, wrap_rad};

/// A pose at a time (s from the run's start).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedPose {
    /// Time (s).
    pub t: f64,
    /// Pose.
    pub pose: Pose,
}

/// `track`'s pose at `t`, linear between its poses (the heading along the shorter arc),
/// held beyond its ends.
pub(crate) fn pose_at(track: &[TimedPose], t: f64) -> Pose {
    let k = track.partition_point(|p| p.t <= t);
    if k == 0 {
        return track[0].pose;
    }
    if k == track.len() {
        return track[k - 1].pose;
    }
    let (a, b) = (track[k - 1], track[k]);
    let u = if b.t > a.t {
        (t - a.t) / (b.t - a.t)
    } else {
        0.0
    };
    Pose::new(
        a.pose.x + u * (b.pose.x - a.pose.x),
        a.pose.y + u * (b.pose.y - a.pose.y),
        wrap_rad(a.pose.theta + u * wrap_rad(b.pose.theta - a.pose.theta)),
    )
}

/// `a ⊕ b`: `b`, given in `a`'s frame, in the frame `a` is given in.
pub(crate) fn compose(a: Pose, b: Pose) -> Pose {
    let (s, c) = a.theta.sin_cos();
    Pose::new(
        a.x + c * b.x - s * b.y,
        a.y + s * b.x + c * b.y,
        wrap_rad(a.theta + b.theta),
    )
}
