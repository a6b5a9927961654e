//! Shoebox rooms: dimensions and the absorption of their six walls; and [`Space`], a room
//! of either kind.

use crate::error::SimError;
use crate::plan::PlanRoom;

/// A room of either kind: a shoebox (the image lattice, every image sounds) or a floor
/// plan ([`PlanRoom`]: images checked per microphone, a diffuse tail).
#[derive(Clone, Debug, PartialEq)]
pub enum Space {
    /// `[0, Lx] x [0, Ly] x [0, Lz]`.
    Shoebox(Room),
    /// A polygon extruded from the floor.
    Plan(PlanRoom),
}

impl Space {
    /// Whether `a` sees `b` on the floor (m): a line of sight within a floor plan, always
    /// in a box.
    pub fn sees(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        match self {
            Space::Shoebox(_) => true,
            Space::Plan(r) => r.sees(a, b),
        }
    }

    /// Whether `p` lies strictly inside the room.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        match self {
            Space::Shoebox(r) => r.contains(p),
            Space::Plan(r) => r.contains(p),
        }
    }

    /// The far corner of the room's bounding box from the origin (m): a shoebox's
    /// dimensions, a plan's largest x and y and its height.
    pub fn dims(&self) -> [f64; 3] {
        match self {
            Space::Shoebox(r) => r.dims(),
            Space::Plan(r) => {
                let (_, hi) = r.bounds();
                [hi[0], hi[1], r.height()]
            }
        }
    }

    /// Volume (m^3).
    pub fn volume(&self) -> f64 {
        match self {
            Space::Shoebox(r) => r.volume(),
            Space::Plan(r) => r.volume(),
        }
    }
}

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
