//! The grid of candidate directions, and (in `grid/lags.rs`) each microphone pair's delay
//! at each of them.

use crate::array::MicArray;
use crate::error::ConfigError;
use serde::{Deserialize, Serialize};

/// The elevation range searched, in degrees.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ElevationRange {
    /// Lowest elevation (degrees, `>= -90`). Default: 0.
    pub min_deg: f64,
    /// Highest elevation (degrees, `<= 90`). Default: 0.
    pub max_deg: f64,
    /// Step (degrees, `> 0`). Default: 10.
    pub step_deg: f64,
}

impl Default for ElevationRange {
    /// The horizontal plane only.
    fn default() -> Self {
        Self {
            min_deg: 0.0,
            max_deg: 0.0,
            step_deg: 10.0,
        }
    }
}

impl ElevationRange {
    /// The horizontal plane only.
    pub const PLANE: ElevationRange = ElevationRange {
        min_deg: 0.0,
        max_deg: 0.0,
        step_deg: 10.0,
    };

    /// -60 to 60 degrees in 10-degree steps: sources seen from a robot are rarely more than
    /// 60 degrees off its horizon, and a robot array's vertical aperture (a tenth of a metre)
    /// resolves elevation no finer than tens of degrees at speech frequencies.
    pub const ROBOT: ElevationRange = ElevationRange {
        min_deg: -60.0,
        max_deg: 60.0,
        step_deg: 10.0,
    };

    /// The automatic choice for `array`: [`ElevationRange::ROBOT`] when its microphones are
    /// not all at one height (a 3-D array resolves elevation, and a horizontal-only search
    /// turns a source's elevation into an azimuth error), else [`ElevationRange::PLANE`] (a
    /// planar array's delays all scale by `cos(elevation)` alike: azimuth stays unbiased).
    /// A linear array ([`MicArray::linear_axis`]) searches the horizontal plane whatever its
    /// tilt: it hears a cone around its line, which over elevations is a ridge whose
    /// highest point is the noise's choice; in the plane it is two azimuths, mirror images
    /// ([`crate::Localizer::mirror_axis_deg`]).
    pub fn auto(array: &MicArray) -> Self {
        let z = array.positions().iter().map(|p| p[2]);
        let span = z.clone().fold(f64::NEG_INFINITY, f64::max) - z.fold(f64::INFINITY, f64::min);
        if span > 1e-3 && array.linear_axis().is_none() {
            Self::ROBOT
        } else {
            Self::PLANE
        }
    }
}

/// Candidate directions: every azimuth step around the circle at each searched elevation.
///
/// Direction `d = e * num_azimuths() + a` has azimuth `-180 + a * step` degrees and
/// elevation `elevations()[e]`; its unit vector is
/// `(cos el cos az, cos el sin az, sin el)` in the array frame.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionGrid {
    az_deg: Vec<f64>,
    el_deg: Vec<f64>,
}

impl DirectionGrid {
    /// Builds the grid. The step is rounded so that a whole number of cells fills 360 degrees.
    ///
    /// # Errors
    /// [`ConfigError::AzimuthStep`] unless `0 < az_step_deg <= 90`,
    /// [`ConfigError::Elevation`] for a malformed elevation range.
    pub fn new(az_step_deg: f64, elevation: ElevationRange) -> Result<Self, ConfigError> {
        check(az_step_deg, Some(elevation))?;
        let e = elevation;
        let n_az = (360.0 / az_step_deg).round() as usize;
        let step = 360.0 / n_az as f64;
        let az_deg = (0..n_az).map(|i| -180.0 + i as f64 * step).collect();
        let n_el = ((e.max_deg - e.min_deg) / e.step_deg + 1e-9).floor() as usize + 1;
        let el_deg = (0..n_el)
            .map(|i| e.min_deg + i as f64 * e.step_deg)
            .collect();
        Ok(Self { az_deg, el_deg })
    }

    /// Azimuths (degrees), ascending from -180.
    pub fn azimuths(&self) -> &[f64] {
        &self.az_deg
    }

    /// Elevations (degrees), ascending.
    pub fn elevations(&self) -> &[f64] {
        &self.el_deg
    }

    /// Number of azimuth cells.
    pub fn num_azimuths(&self) -> usize {
        self.az_deg.len()
    }

    /// Azimuth step (degrees).
    pub fn az_step_deg(&self) -> f64 {
        360.0 / self.az_deg.len() as f64
    }

    /// The azimuth cell nearest `azimuth_deg` (any angle; wrapped).
    pub fn azimuth_cell(&self, azimuth_deg: f64) -> usize {
        let n = self.num_azimuths();
        let from_first = crate::wrap_deg(azimuth_deg - self.az_deg[0]).rem_euclid(360.0);
        (from_first / self.az_step_deg()).round() as usize % n
    }

    /// For each direction of `other`, this grid's direction nearest it in azimuth and
    /// elevation (itself, when `other`'s steps are whole multiples of this grid's and its
    /// elevations start at one of this grid's).
    pub(crate) fn nearest_of(&self, other: &DirectionGrid) -> Vec<usize> {
        let n_az = self.num_azimuths();
        let nearest_el = |el: f64| {
            (0..self.el_deg.len())
                .min_by(|&a, &b| {
                    (self.el_deg[a] - el)
                        .abs()
                        .total_cmp(&(self.el_deg[b] - el).abs())
                })
                .unwrap_or(0)
        };
        let els: Vec<usize> = other.el_deg.iter().map(|&e| nearest_el(e)).collect();
        let azs: Vec<usize> = other.az_deg.iter().map(|&a| self.azimuth_cell(a)).collect();
        els.iter()
            .flat_map(|&e| azs.iter().map(move |&a| e * n_az + a))
            .collect()
    }

    /// The azimuth cells `i` whose centre lies within `deg` degrees of cell `at` (at least
    /// one cell either side, at most half the circle), circularly.
    pub(crate) fn azimuth_window(&self, at: usize, deg: f64) -> impl Iterator<Item = usize> {
        let n = self.num_azimuths();
        let reach = ((deg / self.az_step_deg()).round() as usize).clamp(1, n / 2);
        (0..=2 * reach).map(move |d| (at + n + d - reach) % n)
    }

    /// Number of directions.
    pub fn len(&self) -> usize {
        self.az_deg.len() * self.el_deg.len()
    }

    /// Always false: a grid has at least four azimuths.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Unit vector of direction `d` in the array frame.
    pub fn unit(&self, d: usize) -> [f64; 3] {
        let n = self.num_azimuths();
        unit_vector(self.az_deg[d % n], self.el_deg[d / n])
    }

    /// Half of the grid and the antipodes of its directions, in the same order, when the
    /// grid holds every direction's antipode (an even number of azimuths, elevations
    /// symmetric about 0: the default 3-D grid and the horizontal plane); else `None`. The
    /// half is every elevation below 0 at all azimuths, and at 0 the azimuths from -180 up
    /// to (not including) 0; direction `(e, a)` has its antipode at `(n_el - 1 - e, a +
    /// n_az / 2)`. The subspace methods steer the half only: `-u` has the conjugate
    /// steering phasors of `u`.
    pub(crate) fn antipodal_half(&self) -> Option<(Vec<usize>, Vec<usize>)> {
        let (n_az, els) = (self.num_azimuths(), self.elevations());
        let n_el = els.len();
        let symmetric = (0..n_el).all(|e| (els[e] + els[n_el - 1 - e]).abs() < 1e-9);
        if !n_az.is_multiple_of(2) || !symmetric {
            return None;
        }
        let half: Vec<usize> = (0..n_el / 2 * n_az)
            .chain(
                (n_el % 2 == 1)
                    .then(|| (0..n_az / 2).map(|a| n_el / 2 * n_az + a))
                    .into_iter()
                    .flatten(),
            )
            .collect();
        let anti = half
            .iter()
            .map(|&d| (n_el - 1 - d / n_az) * n_az + (d % n_az + n_az / 2) % n_az)
            .collect();
        Some((half, anti))
    }
}

/// The unit vector of azimuth `azimuth_deg` and elevation `elevation_deg` (degrees) in the
/// array frame: `(cos el cos az, cos el sin az, sin el)`.
pub fn unit_vector(azimuth_deg: f64, elevation_deg: f64) -> [f64; 3] {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]
}

/// Checks a grid's settings: `0 < az_step_deg <= 90`, and, when given, an elevation range
/// with `-90 <= min <= max <= 90` and a positive step. Shared by [`DirectionGrid::new`] and
/// [`crate::SslConfig::validate`], which checks before the elevation is resolved.
pub(crate) fn check(
    az_step_deg: f64,
    elevation: Option<ElevationRange>,
) -> Result<(), ConfigError> {
    if !(az_step_deg > 0.0 && az_step_deg <= 90.0) {
        return Err(ConfigError::AzimuthStep(az_step_deg));
    }
    if let Some(e) = elevation
        && !(e.min_deg >= -90.0 && e.min_deg <= e.max_deg && e.max_deg <= 90.0 && e.step_deg > 0.0)
    {
        return Err(ConfigError::Elevation {
            min: e.min_deg,
            max: e.max_deg,
            step: e.step_deg,
        });
    }
    Ok(())
}

mod lags;
pub(crate) use lags::*;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_covers_the_circle_once() {
        let g = DirectionGrid::new(1.0, ElevationRange::default()).unwrap();
        assert_eq!(g.len(), 360);
        assert_eq!(g.azimuths()[0], -180.0);
        assert_eq!(*g.azimuths().last().unwrap(), 179.0);
        let u = g.unit(180); // azimuth 0
        assert!((u[0] - 1.0).abs() < 1e-12 && u[1].abs() < 1e-12);
        let u = g.unit(270); // azimuth 90: +y
        assert!((u[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_nearest_azimuth_cell_is_the_one_least_far_round_the_circle() {
        for step in [1.0, 2.5, 7.0] {
            let g = DirectionGrid::new(step, ElevationRange::default()).unwrap();
            let az = g.azimuths();
            for k in 0..2000 {
                let a = -400.0 + 0.37 * k as f64;
                let far = |i: usize| crate::wrap_deg(az[i] - a).abs();
                let best = (0..az.len()).map(far).fold(f64::INFINITY, f64::min);
                assert!((far(g.azimuth_cell(a)) - best).abs() < 1e-9, "{step} {a}");
            }
            let window: Vec<usize> = g.azimuth_window(0, 2.0 * step).collect();
            let n = az.len();
            assert_eq!(window, [n - 2, n - 1, 0, 1, 2], "{step}");
        }
    }

    #[test]
    fn elevation_range_is_inclusive() {
        let e = ElevationRange {
            min_deg: -20.0,
            max_deg: 40.0,
            step_deg: 10.0,
        };
        let g = DirectionGrid::new(5.0, e).unwrap();
        assert_eq!(g.elevations(), &[-20.0, -10.0, 0.0, 10.0, 20.0, 30.0, 40.0]);
        assert_eq!(g.len(), 72 * 7);
        let bad = ElevationRange {
            min_deg: 10.0,
            max_deg: 0.0,
            step_deg: 1.0,
        };
        assert!(DirectionGrid::new(5.0, bad).is_err());
        assert!(DirectionGrid::new(0.0, ElevationRange::default()).is_err());
    }
}
