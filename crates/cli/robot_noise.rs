//! The robot's own noise: the recording of the robot alone that the SSL subtracts
//! ([`ssl::noise`]), and a note for a user who has none but whose DoAs show the robot's
//! noise.
//!
//! A fan on the robot is heard from one azimuth in the array frame at every stop, wherever
//! the robot stands and however it is turned. No source of the room can do that once the
//! robot has turned: its azimuth in the array frame turns the other way. So a direction
//! that most stops hear within a few degrees, at stops whose headings differ by 30 degrees
//! or more, and whose rays in the room meet at no point in front of them, is the robot's
//! own ([`fixed_direction`]). On a straight path it cannot be told from a source far ahead
//! or behind on the path's line, and no note is given.

use std::path::PathBuf;

use anyhow::{Context, Result};
use asm::Pose;
use ssl::{Audio, wrap_deg};

use crate::dataset::Table;
use crate::dataset::read_recording;
use crate::settings::Settings;

/// A recording of the robot alone ([`Settings::noise`]), its channels picked as the
/// recordings' are: the robot's own noise, which the localizers subtract ([`ssl::noise`]).
#[derive(Clone, Debug)]
pub struct RobotNoise {
    /// The file.
    pub path: PathBuf,
    /// Its microphones' channels.
    pub audio: Audio,
}

impl RobotNoise {
    /// The recording `settings` name, if any.
    ///
    /// # Errors
    /// A file that cannot be read or has too few channels, named.
    pub fn of(settings: &Settings) -> Result<Option<Self>> {
        let Some(path) = &settings.noise else {
            return Ok(None);
        };
        let audio = read_recording(path, settings.channels.as_deref())
            .context("the recording of the robot alone")?;
        Ok(Some(Self {
            path: path.clone(),
            audio,
        }))
    }
}

/// DoAs within this many degrees of a direction count as heard from it.
const SAME_DEG: f64 = 5.0;
/// The share of the stops that must hear the direction.
const MIN_SHARE: f64 = 0.7;
/// And at least this many stops.
const MIN_STOPS: usize = 4;
/// The headings of those stops must span at least this many degrees.
const MIN_TURN_DEG: f64 = 30.0;
/// A point that every ray passes within this angle of (degrees), in front of every stop
/// and within [`MAX_RANGE_M`], is a source of the room.
const RAY_TOL_DEG: f64 = 6.0;
/// Farther than this from the stops (m), a point is no source a robot in a room hears.
const MAX_RANGE_M: f64 = 15.0;

/// A direction of the array frame that the robot's noise fills: its azimuth (degrees) and
/// the stops that hear it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedDirection {
    /// Azimuth in the array frame (degrees): the circular mean of the DoAs heard from it.
    pub azimuth_deg: f64,
    /// Stops with a DoA there.
    pub stops: usize,
}

/// The direction of the array frame that most stops hear (`doas`, degrees, one row per
/// pose of `poses`) when it is the robot's own (see the module docs), or `None`.
pub fn fixed_direction(poses: &[Pose], doas: &Table) -> Option<FixedDirection> {
    let n = poses.len().min(doas.len());
    let need = MIN_STOPS.max((MIN_SHARE * n as f64).ceil() as usize);
    if n < need {
        return None;
    }
    // The candidate heard by the most stops: each DoA tried as a centre.
    let near = |a: f64, b: f64| wrap_deg(a - b).abs() <= SAME_DEG;
    let hearing = |centre: f64| -> Vec<(usize, f64)> {
        (0..n)
            .filter_map(|k| {
                doas[k]
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|&a| near(a, centre))
                    .min_by(|a, b| {
                        wrap_deg(a - centre)
                            .abs()
                            .total_cmp(&wrap_deg(b - centre).abs())
                    })
                    .map(|a| (k, a))
            })
            .collect()
    };
    let best = doas[..n]
        .iter()
        .flatten()
        .flatten()
        .map(|&a| hearing(a))
        .max_by_key(Vec::len)?;
    if best.len() < need {
        return None;
    }
    let (s, c) = best.iter().fold((0.0, 0.0), |(s, c), (_, a)| {
        (s + a.to_radians().sin(), c + a.to_radians().cos())
    });
    let azimuth_deg = s.atan2(c).to_degrees();
    let stops: Vec<Pose> = best.iter().map(|&(k, _)| poses[k]).collect();
    let headings: Vec<f64> = stops.iter().map(Pose::theta_deg).collect();
    let turned = headings
        .iter()
        .flat_map(|a| headings.iter().map(move |b| wrap_deg(a - b).abs()))
        .fold(0.0, f64::max);
    if turned < MIN_TURN_DEG {
        return None;
    }
    let rays: Vec<(Pose, f64)> = best
        .iter()
        .map(|&(k, a)| (poses[k], poses[k].theta + a.to_radians()))
        .collect();
    if meet_in_front(&rays) {
        return None;
    }
    Some(FixedDirection {
        azimuth_deg,
        stops: best.len(),
    })
}

/// Whether the rays (from each pose's position, at each world bearing in radians) pass
/// within [`RAY_TOL_DEG`] of one point in front of them all, within [`MAX_RANGE_M`]: the
/// point nearest all of them in least squares.
fn meet_in_front(rays: &[(Pose, f64)]) -> bool {
    // Sum over rays of (I - d d^T) (p - s) = 0.
    let (mut a, mut b) = ([[0.0f64; 2]; 2], [0.0f64; 2]);
    for (s, bearing) in rays {
        let d = [bearing.cos(), bearing.sin()];
        let m = [
            [1.0 - d[0] * d[0], -d[0] * d[1]],
            [-d[0] * d[1], 1.0 - d[1] * d[1]],
        ];
        for i in 0..2 {
            for j in 0..2 {
                a[i][j] += m[i][j];
            }
            b[i] += m[i][0] * s.x + m[i][1] * s.y;
        }
    }
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    let trace = a[0][0] + a[1][1];
    if det <= 1e-6 * trace * trace {
        return false;
    }
    let p = [
        (a[1][1] * b[0] - a[0][1] * b[1]) / det,
        (a[0][0] * b[1] - a[1][0] * b[0]) / det,
    ];
    rays.iter().all(|(s, bearing)| {
        let (dx, dy) = (p[0] - s.x, p[1] - s.y);
        let range = dx.hypot(dy);
        let off = wrap_deg((dy.atan2(dx) - bearing).to_degrees()).abs();
        range <= MAX_RANGE_M && off <= RAY_TOL_DEG
    })
}

/// What a user with no recording of the robot alone should know when their DoAs show the
/// robot's own noise ([`fixed_direction`]), or `None`.
pub fn note(poses: &[Pose], doas: &Table) -> Option<String> {
    let f = fixed_direction(poses, doas)?;
    Some(format!(
        "note: {} of {} stops hear a DoA at azimuth {:.0} deg of the array wherever the robot stands and however it is turned: no source of the room does that, the robot's own noise does (a fan); record the robot alone for a few seconds (its fans running, the room quiet) and give it with --noise WAV, or put it in the data set's noise/ folder (see ssl::noise)",
        f.stops,
        poses.len(),
        f.azimuth_deg
    ))
}

/// Says on stderr which recording of the robot alone the SSL subtracted, or, with none,
/// what [`note`] says of a survey's DoAs (`doas_deg` at `poses`, from `doa_source`: `ssl:`
/// and the method, or a table).
pub fn tell(settings: &Settings, doa_source: &str, poses: &[Pose], doas_deg: &Table) {
    if !doa_source.starts_with("ssl:") {
        // A DoA table: the SSL did not run here.
        if let Some(n) = note(poses, doas_deg) {
            eprintln!("{n}");
        }
        return;
    }
    match &settings.noise {
        Some(p) => eprintln!(
            "the robot's own noise, as {} holds it, subtracted from every statistic of the SSL (ssl::noise)",
            p.display()
        ),
        None => {
            if let Some(n) = note(poses, doas_deg) {
                eprintln!("{n}");
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L-shaped path: 6 stops along +x, then 6 along +y (heading 90 degrees).
    fn l_path() -> Vec<Pose> {
        (0..6)
            .map(|i| Pose::new(1.0 + 0.5 * f64::from(i), 1.0, 0.0))
            .chain((0..6).map(|i| Pose::new(4.0, 1.5 + 0.5 * f64::from(i), 90f64.to_radians())))
            .collect()
    }

    fn bearing_deg(p: &Pose, s: [f64; 2]) -> f64 {
        wrap_deg((p.bearing_to(s) - p.theta).to_degrees())
    }

    #[test]
    fn a_fan_on_the_robot_is_told_from_a_source_of_the_room() {
        let poses = l_path();
        let talker = [2.0, 4.0];
        // Every stop hears the talker and, behind it at 180 degrees (1-2 degrees off),
        // the fan.
        let with_fan: Table = poses
            .iter()
            .enumerate()
            .map(|(k, p)| vec![Some(bearing_deg(p, talker)), Some(179.0 + (k % 3) as f64)])
            .collect();
        let f = fixed_direction(&poses, &with_fan).expect("the fan");
        assert_eq!(f.stops, 12);
        assert!(wrap_deg(f.azimuth_deg - 180.0).abs() < 1.5, "{f:?}");
        assert!(note(&poses, &with_fan).unwrap().contains("--noise"));
        // The talker alone: its azimuth changes along the path, no note.
        let talker_only: Table = poses
            .iter()
            .map(|p| vec![Some(bearing_deg(p, talker))])
            .collect();
        assert_eq!(fixed_direction(&poses, &talker_only), None);
        // A source the turn keeps ahead: from (4, 8), the second leg hears it at 0
        // degrees, the first leg elsewhere; a point in front of every ray, no note.
        let ahead = [4.0, 8.0];
        let rows: Table = poses
            .iter()
            .map(|p| vec![Some(bearing_deg(p, ahead))])
            .collect();
        assert_eq!(fixed_direction(&poses, &rows), None);
        // Driving a circle around a source with it always on the left: one azimuth of the
        // array (90 degrees) at stops of every heading, but the rays meet at the centre.
        let centre = [3.0, 3.0];
        let circle: Vec<Pose> = (0..12)
            .map(|i| {
                let a = f64::from(i) * 30f64.to_radians();
                Pose::new(
                    3.0 + 2.0 * a.cos(),
                    3.0 + 2.0 * a.sin(),
                    a + 90f64.to_radians(),
                )
            })
            .collect();
        let rows: Table = circle
            .iter()
            .map(|p| vec![Some(bearing_deg(p, centre))])
            .collect();
        assert!(rows.iter().all(|r| (r[0].unwrap() - 90.0).abs() < 1e-9));
        assert_eq!(fixed_direction(&circle, &rows), None);
        // The same azimuths heard at the circle's stops from a fan: rays that meet nowhere
        // (each stop hears it straight back).
        let rows: Table = circle.iter().map(|_| vec![Some(180.0)]).collect();
        assert!(fixed_direction(&circle, &rows).is_some());
        // On a straight path a fan behind is a source behind on the path's line: no note.
        let straight: Vec<Pose> = poses[..6].to_vec();
        let rows: Table = straight.iter().map(|_| vec![Some(180.0)]).collect();
        assert_eq!(fixed_direction(&straight, &rows), None);
        // Heard at too few stops (6 of 12 < 70 %).
        let half: Table = with_fan
            .iter()
            .enumerate()
            .map(|(k, r)| if k % 2 == 0 { r.clone() } else { vec![r[0]] })
            .collect();
        assert_eq!(fixed_direction(&poses, &half), None);
    }
}
