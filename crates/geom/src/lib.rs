//! The one pose type of the workspace, and angle wrapping.
//!
//! # Overview
//!
//! `sim` renders what an array hears at a robot's stops, `asm` maps sources from the DoAs
//! heard there, and the app reads stops from pose tables; all three speak of the same
//! thing, a [`Pose`]. It lives in this crate of its own because `sim` and `asm` must not
//! depend on each other (each is usable alone), and a pose is all they share.
//!
//! # Example
//!
//! ```
//! use iasm_geom::Pose;
//! // A robot at (1, 2) facing +y hears a source dead ahead (azimuth 0 in its array frame).
//! let p = Pose::from_degrees(1.0, 2.0, 90.0);
//! let world = p.world_bearing(0.0);
//! assert!((world - p.bearing_to([1.0, 5.0])).abs() < 1e-12);
//! assert!((p.theta_deg() - 90.0).abs() < 1e-12);
//! ```
//!
//! # Conventions
//!
//! SI units: metres and radians (degrees only through the `_deg` helpers, for tables and
//! people). The world frame is right-handed with `z` up (REP-103); a heading and every
//! bearing is counter-clockwise from the world `x` axis. A DoA in the array frame is an
//! azimuth from the robot's heading.

use serde::{Deserialize, Serialize};

/// A robot pose: position (m) and heading (rad), world frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// Heading (rad, counter-clockwise from the world x axis).
    pub theta: f64,
}

impl Pose {
    /// A pose from a position (m) and a heading in radians.
    pub const fn new(x: f64, y: f64, theta: f64) -> Self {
        Self { x, y, theta }
    }

    /// A pose from a position (m) and a heading in degrees (as pose tables give it).
    pub fn from_degrees(x: f64, y: f64, theta_deg: f64) -> Self {
        Self::new(x, y, theta_deg.to_radians())
    }

    /// The heading in degrees.
    pub fn theta_deg(&self) -> f64 {
        self.theta.to_degrees()
    }

    /// The position (m).
    pub fn position(&self) -> [f64; 2] {
        [self.x, self.y]
    }

    /// Whether every field is finite.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.theta.is_finite()
    }

    /// The world bearing (rad, wrapped to `(-pi, pi]`) of an array-frame azimuth (rad).
    pub fn world_bearing(&self, azimuth_rad: f64) -> f64 {
        wrap_rad(azimuth_rad + self.theta)
    }

    /// The world bearing (rad, in `(-pi, pi]`) from this pose's position to `point` (m).
    pub fn bearing_to(&self, point: [f64; 2]) -> f64 {
        (point[1] - self.y).atan2(point[0] - self.x)
    }

    /// The array-frame azimuth (rad, wrapped to `(-pi, pi]`) of `point` (m) seen from this
    /// pose: [`Pose::world_bearing`]'s inverse.
    pub fn azimuth_to(&self, point: [f64; 2]) -> f64 {
        wrap_rad(self.bearing_to(point) - self.theta)
    }
}

/// Wraps an angle (rad) to `(-pi, pi]`.
pub fn wrap_rad(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let w = a - two_pi * ((a + std::f64::consts::PI) / two_pi).floor();
    if w <= -std::f64::consts::PI {
        w + two_pi
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn wrap_rad_stays_in_range() {
        for (a, w) in [
            (0.0, 0.0),
            (PI, PI),
            (-PI, PI),
            (3.0 * PI / 2.0, -PI / 2.0),
            (-7.0, -7.0 + 2.0 * PI),
        ] {
            assert!(
                (wrap_rad(a) - w).abs() < 1e-12,
                "{a} -> {} (want {w})",
                wrap_rad(a)
            );
        }
    }

    #[test]
    fn an_array_frame_doa_turns_with_the_robot() {
        // Facing -x (180 deg), a DoA at +90 (the robot's left) points to world -y.
        let p = Pose::from_degrees(0.0, 0.0, 180.0);
        assert!((p.world_bearing(PI / 2.0) - (-PI / 2.0)).abs() < 1e-12);
        assert!((p.bearing_to([0.0, -3.0]) - (-PI / 2.0)).abs() < 1e-12);
    }

    #[test]
    fn degrees_round_trip() {
        let p = Pose::from_degrees(1.0, -2.0, -135.0);
        assert!((p.theta_deg() + 135.0).abs() < 1e-12);
        assert!(p.is_finite());
        assert!(!Pose::new(f64::NAN, 0.0, 0.0).is_finite());
    }
}
