//! Shoebox rooms: dimensions and the absorption of their six walls.

use crate::error::SimError;

/// Wall order used everywhere: `x = 0`, `x = Lx`, `y = 0`, `y = Ly`, `z = 0` (floor),
/// `z = Lz` (ceiling).
pub const WALLS: [&str; 6] = ["x0", "x1", "y0", "y1", "floor", "ceiling"];

/// A shoebox room `[0, Lx] x [0, Ly] x [0, Lz]` (m) with an energy absorption coefficient
/// per wall.
#[derive(Clone, Debug, PartialEq)]
pub struct Room {
    dims: [f64; 3],
    absorption: [f64; 6],
}

impl Room {
    /// A room with the given per-wall absorption (order [`WALLS`]).
    ///
    /// # Errors
    /// [`SimError::Invalid`] if a dimension is not positive and finite or an absorption is
    /// outside `[0, 1]`.
    pub fn new(dims: [f64; 3], absorption: [f64; 6]) -> Result<Self, SimError> {
        if let Some(d) = dims.iter().find(|d| !(d.is_finite() && **d > 0.0)) {
            return Err(SimError::Invalid {
                field: "room.dims".into(),
                message: format!("{d} m is not a positive length"),
            });
        }
        if let Some((i, a)) = absorption
            .iter()
            .enumerate()
            .find(|(_, a)| !(0.0..=1.0).contains(*a))
        {
            return Err(SimError::Invalid {
                field: format!("room.absorption[{i}] ({})", WALLS[i]),
                message: format!("{a} is outside [0, 1]"),
            });
        }
        Ok(Self { dims, absorption })
    }

    /// A room whose walls all absorb alike, with reverberation time `rt60` (s) as the
    /// image-source method renders it at speed of sound `c`.
    ///
    /// Sabine's inversion `alpha = 0.161 V / (S RT60)` is the start. A shoebox's specular
    /// images decay more slowly than Sabine's diffuse field, though (paths along the long
    /// axis meet walls less often and dominate the late decay: +4 % at 0.3 s, +23 % at
    /// 0.8 s in a 6 x 4 x 3 m room), so the absorption is then raised by bisection until the
    /// rendered decay ([`crate::ism::ism_t30`]) lasts `rt60`.
    ///
    /// # Errors
    /// [`SimError::Invalid`] if `rt60` is not positive, or is shorter than the room can
    /// have even with fully absorbing walls.
    pub fn with_rt60(dims: [f64; 3], rt60: f64, c: f64) -> Result<Self, SimError> {
        let room = Self::new(dims, [0.0; 6])?;
        if !(rt60.is_finite() && rt60 > 0.0) {
            return Err(SimError::Invalid {
                field: "room.rt60".into(),
                message: format!("{rt60} s is not a positive time"),
            });
        }
        let too_short = || SimError::Invalid {
            field: "room.rt60".into(),
            message: format!(
                "{rt60} s is shorter than this room can have ({:.3} s by Sabine with fully absorbing walls)",
                0.161 * room.volume() / room.surface()
            ),
        };
        let sabine = 0.161 * room.volume() / (room.surface() * rt60);
        if sabine >= 1.0 {
            return Err(too_short());
        }
        let t30 = |a: f64| {
            crate::ism::ism_t30(
                &Self {
                    dims,
                    absorption: [a; 6],
                },
                c,
                1.2 * rt60,
            )
        };
        let (mut lo, mut hi) = (sabine, 0.99);
        if t30(lo).is_none_or(|t| t <= rt60) {
            return Self::new(dims, [sabine; 6]);
        }
        if t30(hi).is_some_and(|t| t > rt60) {
            return Err(too_short());
        }
        // T30 falls as absorption rises: keep lo too live, hi too dead.
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            if t30(mid).is_some_and(|t| t > rt60) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Self::new(dims, [0.5 * (lo + hi); 6])
    }

    /// Dimensions (m).
    pub fn dims(&self) -> [f64; 3] {
        self.dims
    }

    /// Energy absorption per wall.
    pub fn absorption(&self) -> [f64; 6] {
        self.absorption
    }

    /// Pressure reflection coefficient per wall, `sqrt(1 - alpha)`.
    pub fn reflection(&self) -> [f64; 6] {
        self.absorption.map(|a| (1.0 - a).sqrt())
    }

    /// Volume (m^3).
    pub fn volume(&self) -> f64 {
        self.dims.iter().product()
    }

    /// Wall surface (m^2).
    pub fn surface(&self) -> f64 {
        let [x, y, z] = self.dims;
        2.0 * (x * y + x * z + y * z)
    }

    /// Sabine's reverberation time (s) of the room as it is.
    pub fn sabine_rt60(&self) -> f64 {
        let [x, y, z] = self.dims;
        let areas = [y * z, y * z, x * z, x * z, x * y, x * y];
        let absorbing: f64 = areas.iter().zip(&self.absorption).map(|(s, a)| s * a).sum();
        0.161 * self.volume() / absorbing
    }

    /// Whether `p` lies strictly inside the room.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        p.iter().zip(&self.dims).all(|(v, d)| *v > 0.0 && v < d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sabine_reverberation_time_by_hand() {
        // 6 x 4 x 3 m: V = 72, S = 108; alpha = 0.2 everywhere: 0.161 * 72 / 21.6 = 0.5367 s.
        let r = Room::new([6.0, 4.0, 3.0], [0.2; 6]).unwrap();
        approx::assert_relative_eq!(r.sabine_rt60(), 0.161 * 72.0 / 21.6, max_relative = 1e-12);
        // A room tuned to a time absorbs at least what Sabine's inversion asks.
        let c = Room::with_rt60([6.0, 4.0, 3.0], 0.5, 343.0).unwrap();
        assert!(c.absorption()[0] >= 0.161 * 72.0 / 54.0);
    }

    #[test]
    fn an_impossible_rt60_names_the_field() {
        let e = Room::with_rt60([6.0, 4.0, 3.0], 0.05, 343.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("room.rt60") && e.contains("shorter than"), "{e}");
        let e = Room::new([6.0, 4.0, 3.0], [0.2, 0.2, 1.2, 0.2, 0.2, 0.2])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("absorption[2]") && e.contains("outside [0, 1]"),
            "{e}"
        );
    }
}
