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

    /// A room whose walls all absorb alike, chosen so that Sabine's formula
    /// `RT60 = 0.161 V / (S alpha)` gives `rt60` (s).
    ///
    /// Measured on image-source responses of a 6 x 4 x 3 m room, T30 comes out 25 to 45 %
    /// longer than this target: a shoebox's specular images decay more slowly than Sabine's
    /// diffuse field (paths along the long axis meet walls less often and dominate the late
    /// decay). Calibrating the absorption against the rendered decay is issue 4's work.
    ///
    /// # Errors
    /// [`SimError::Invalid`] if `rt60` is not positive, or is shorter than the room allows
    /// (it would need `alpha >= 1`).
    pub fn with_rt60(dims: [f64; 3], rt60: f64) -> Result<Self, SimError> {
        let room = Self::new(dims, [0.0; 6])?;
        if !(rt60.is_finite() && rt60 > 0.0) {
            return Err(SimError::Invalid {
                field: "room.rt60".into(),
                message: format!("{rt60} s is not a positive time"),
            });
        }
        let alpha = 0.161 * room.volume() / (room.surface() * rt60);
        if alpha >= 1.0 {
            return Err(SimError::Invalid {
                field: "room.rt60".into(),
                message: format!(
                    "{rt60} s is shorter than this room can have ({:.3} s by Sabine with fully absorbing walls)",
                    0.161 * room.volume() / room.surface()
                ),
            });
        }
        Self::new(dims, [alpha; 6])
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
        // ...and the inversion gives that alpha back for that time.
        let c = Room::with_rt60([6.0, 4.0, 3.0], 0.161 * 72.0 / 21.6).unwrap();
        approx::assert_relative_eq!(c.absorption()[0], 0.2, max_relative = 1e-12);
    }

    #[test]
    fn an_impossible_rt60_names_the_field() {
        let e = Room::with_rt60([6.0, 4.0, 3.0], 0.05)
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
