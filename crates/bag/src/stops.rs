//! Where the robot stood still and listened, and its pose there.
//!
//! I-ASM maps from recordings made at stops (the array must not move while it listens: a
//! DoA is a direction from one place). A run recorded in a bag is continuous, so the stops
//! are found in its motion: a **stop** is a stretch of time over which every pose lies
//! within [`StopOptions::radius_m`] and [`StopOptions::turn_deg`] of the stretch's first
//! (1 cm and 1 degree by default: the array then moves less than a DoA's resolution, while
//! a robot that creeps at a few millimetres a second leaves the ball within seconds). Its
//! listening window leaves out the first [`StopOptions::settle_s`] (a robot rocks and its
//! motors ring down as it stops; and an audio message's time is known to within its
//! length) and the last [`StopOptions::end_margin_s`] (the motors start before the pose
//! moves), and must hold at least [`StopOptions::min_listen_s`] of continuous audio.
//!
//! The stops are found by the odometry topic when the run has one beside its pose topic
//! (wheel odometry is smooth and published at a steady rate; a localiser such as AMCL
//! publishes only when the robot has moved, and jumps when it corrects itself). The pose of
//! a stop is then the pose topic's message nearest the stop (the last one before its
//! window ends, else the first after), carried to the stop by the odometry's motion between
//! that message's time and the stop: `P(t) ⊕ O(t)⁻¹ ⊕ O(stop)`, what ROS's `tf` composes
//! from a localiser's `map → odom` and the odometry's `odom → base_link`. Without
//! odometry, it is the mean of the pose topic's poses over the stop.

use geom::{Pose, wrap_rad};

use crate::error::{Error, Result};
use crate::run::{AudioSegment, Run};
use crate::track::{TimedPose, compose, pose_at};

/// How stops are found (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopOptions {
    /// How far the robot may move within a stop (m). Default 0.01.
    pub radius_m: f64,
    /// How far it may turn within a stop (degrees). Default 1.
    pub turn_deg: f64,
    /// Left out at the start of a stop (s). Default 0.3.
    pub settle_s: f64,
    /// Left out at its end (s). Default 0.2.
    pub end_margin_s: f64,
    /// The shortest listening window kept (s of continuous audio). Default 0.5.
    pub min_listen_s: f64,
}

impl Default for StopOptions {
    fn default() -> Self {
        Self {
            radius_m: 0.01,
            turn_deg: 1.0,
            settle_s: 0.3,
            end_margin_s: 0.2,
            min_listen_s: 0.5,
        }
    }
}

impl StopOptions {
    /// Checks every field.
    ///
    /// # Errors
    /// A negative or non-finite field, or a `min_listen_s` that is not positive.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("radius_m", self.radius_m),
            ("turn_deg", self.turn_deg),
            ("settle_s", self.settle_s),
            ("end_margin_s", self.end_margin_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::Config(format!(
                    "{name} must be finite and not negative (got {v})"
                )));
            }
        }
        if !(self.min_listen_s.is_finite() && self.min_listen_s > 0.0) {
            return Err(Error::Config(format!(
                "min_listen_s must be positive (got {})",
                self.min_listen_s
            )));
        }
        Ok(())
    }
}

/// One stop of the run.
#[derive(Clone, Debug, PartialEq)]
pub struct Stop {
    /// When the robot stood still: the first and last pose of the stretch (s).
    pub still_s: (f64, f64),
    /// The listening window (s): within `still_s` and within one audio segment.
    pub listen_s: (f64, f64),
    /// The robot's pose there, in the pose topic's frame.
    pub pose: Pose,
    /// The audio segment the window lies in ([`Run::segments`]).
    pub segment: usize,
    /// The window's frames in that segment ([`Run::stop_audio`] decodes them).
    pub frames: std::ops::Range<usize>,
}

/// The stretches of `track` (in time order) over which it stays within `radius_m` and
/// `turn_rad` of the stretch's first pose, as index ranges of at least two poses.
fn still_stretches(track: &[TimedPose], radius_m: f64, turn_rad: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < track.len() {
        let p = track[i].pose;
        let mut j = i;
        while j + 1 < track.len() {
            let q = track[j + 1].pose;
            if (q.x - p.x).hypot(q.y - p.y) > radius_m
                || wrap_rad(q.theta - p.theta).abs() > turn_rad
            {
                break;
            }
            j += 1;
        }
        if j > i {
            out.push((i, j));
        }
        i = j + 1;
    }
    out
}

/// The mean of poses: positions averaged, headings by the circular mean.
fn mean_pose(poses: &[TimedPose]) -> Pose {
    let n = poses.len() as f64;
    let (x, y, s, c) = poses.iter().fold((0.0, 0.0, 0.0, 0.0), |a, p| {
        (
            a.0 + p.pose.x,
            a.1 + p.pose.y,
            a.2 + p.pose.theta.sin(),
            a.3 + p.pose.theta.cos(),
        )
    });
    Pose::new(x / n, y / n, s.atan2(c))
}

/// `a⁻¹ ⊕ b`: `b` in `a`'s frame.
fn relative(a: Pose, b: Pose) -> Pose {
    let (s, c) = a.theta.sin_cos();
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    Pose::new(
        c * dx + s * dy,
        -s * dx + c * dy,
        wrap_rad(b.theta - a.theta),
    )
}

/// The frames of `segment` within `(from, to)` (s); a bound that falls on a frame (to within
/// a thousandth of one: times in seconds carry rounding) takes it.
fn frames_within(segment: &AudioSegment, (from, to): (f64, f64), fs: f64) -> (usize, usize) {
    let first =
        (((from - segment.start_s) * fs - 1e-3).ceil().max(0.0) as usize).min(segment.frames);
    let last = (((to - segment.start_s) * fs + 1e-3).floor() as usize).min(segment.frames);
    (first, last.max(first))
}

impl Run {
    /// The audio of `stop`'s listening window, one vector per channel, full scale at 1.
    pub fn stop_audio(&self, stop: &Stop) -> Vec<Vec<f32>> {
        self.samples(stop.segment, stop.frames.clone())
    }

    /// The segment and its frames that hold the audio from `from` to `to` (s from the
    /// run's start), or `None` when no one continuous segment holds all of it (the audio
    /// starts later, ends sooner, or has a gap there).
    pub fn window(&self, (from, to): (f64, f64)) -> Option<(usize, std::ops::Range<usize>)> {
        let fs = f64::from(self.format.sample_rate);
        // Half a frame of slack at either end: times in seconds carry rounding.
        let slack = 0.5 / fs;
        let k = self.segments.iter().position(|s| {
            s.start_s - slack <= from && to <= s.start_s + s.frames as f64 / fs + slack
        })?;
        let (first, last) = frames_within(&self.segments[k], (from, to), fs);
        (first < last).then_some((k, first..last))
    }

    /// The stops of the run, in time order, each with its pose and audio (module docs).
    ///
    /// # Errors
    /// Options that [`StopOptions::validate`] refuses, or a run without poses.
    pub fn stops(&self, options: &StopOptions) -> Result<Vec<Stop>> {
        options.validate()?;
        if self.poses.is_empty() {
            return Err(Error::Topic(format!(
                "the pose topic {} has no messages",
                self.pose_topic
            )));
        }
        let track = if self.odometry.is_empty() {
            &self.poses
        } else {
            &self.odometry
        };
        let fs = f64::from(self.format.sample_rate);
        let mut out = Vec::new();
        for (i, j) in still_stretches(track, options.radius_m, options.turn_deg.to_radians()) {
            let still = (track[i].t, track[j].t);
            let (a, b) = (still.0 + options.settle_s, still.1 - options.end_margin_s);
            // The segment that holds most of the window, and the window within it.
            let best = self
                .segments
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    let end = s.start_s + s.frames as f64 / fs;
                    (k, a.max(s.start_s), b.min(end))
                })
                .max_by(|x, y| (x.2 - x.1).total_cmp(&(y.2 - y.1)));
            let Some((k, from, to)) = best else {
                continue;
            };
            if to - from < options.min_listen_s {
                continue;
            }
            let segment = &self.segments[k];
            let (first, last) = frames_within(segment, (from, to), fs);
            let pose = if self.odometry.is_empty() {
                mean_pose(&track[i..=j])
            } else {
                let here = mean_pose(&track[i..=j]);
                let k = self.poses.partition_point(|p| p.t <= to);
                let p = if k > 0 {
                    self.poses[k - 1]
                } else {
                    self.poses[0]
                };
                compose(p.pose, relative(pose_at(track, p.t), here))
            };
            out.push(Stop {
                still_s: still,
                listen_s: (
                    segment.start_s + first as f64 / fs,
                    segment.start_s + last as f64 / fs,
                ),
                pose,
                segment: k,
                frames: first..last,
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    fn tp(t: f64, x: f64, y: f64, deg: f64) -> TimedPose {
        TimedPose {
            t,
            pose: Pose::from_degrees(x, y, deg),
        }
    }

    #[test]
    fn a_track_that_stands_drives_and_stands_has_two_stretches() {
        let mut track: Vec<TimedPose> = (0..=10)
            .map(|k| tp(f64::from(k) * 0.1, 1.0, 2.0, 0.0))
            .collect();
        // Drives at 0.5 m/s for 1 s, then stands.
        track.extend((1..=10).map(|k| {
            tp(
                1.0 + f64::from(k) * 0.1,
                1.0 + 0.05 * f64::from(k),
                2.0,
                0.0,
            )
        }));
        track.extend((1..=10).map(|k| tp(2.0 + f64::from(k) * 0.1, 1.5, 2.0, 0.0)));
        let s = still_stretches(&track, 0.01, 1f64.to_radians());
        assert_eq!(s, vec![(0, 10), (20, 30)]);
    }

    #[test]
    fn a_robot_that_creeps_or_turns_in_place_is_not_still() {
        // 5 mm/s: leaves the 1-cm ball within 2 s.
        let creep: Vec<TimedPose> = (0..=40)
            .map(|k| tp(f64::from(k) * 0.1, 0.0005 * f64::from(k), 0.0, 0.0))
            .collect();
        assert!(
            still_stretches(&creep, 0.01, 1f64.to_radians())
                .iter()
                .all(|(i, j)| creep[*j].t - creep[*i].t <= 2.0)
        );
        let turn: Vec<TimedPose> = (0..=40)
            .map(|k| tp(f64::from(k) * 0.1, 0.0, 0.0, 10.0 * f64::from(k)))
            .collect();
        assert!(still_stretches(&turn, 0.01, 1f64.to_radians()).is_empty());
    }

    #[test]
    fn poses_compose_as_frames_do() {
        let a = Pose::from_degrees(1.0, 2.0, 90.0);
        let b = Pose::from_degrees(1.0, 0.0, 0.0);
        let c = compose(a, b);
        assert_abs_diff_eq!(c.x, 1.0, epsilon = 1e-12);
        assert_abs_diff_eq!(c.y, 3.0, epsilon = 1e-12);
        let back = relative(a, c);
        assert_abs_diff_eq!(back.x, b.x, epsilon = 1e-12);
        assert_abs_diff_eq!(back.y, b.y, epsilon = 1e-12);
        assert_abs_diff_eq!(back.theta, b.theta, epsilon = 1e-12);
    }

    #[test]
    fn the_mean_heading_is_circular() {
        let p = mean_pose(&[tp(0.0, 0.0, 0.0, 179.0), tp(0.1, 0.0, 0.0, -179.0)]);
        assert_abs_diff_eq!(p.theta.abs(), std::f64::consts::PI, epsilon = 1e-9);
    }
}
