//! Microphone arrays: positions in metres in the array frame, channel `i` = microphone `i`.
//!
//! The array frame is right-handed: `x` is the robot's heading, `z` points up, azimuth is
//! counter-clockwise from `x`. Built-in presets cover the paper's array and a few arrays
//! that robots commonly carry; any other array loads from a small TOML or JSON file:
//!
//! ```toml
//! name = "my-array"            # optional
//! positions = [[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.05, 0.0]]
//! ```

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::ArrayError;

/// Names of the built-in arrays, in the order [`MicArray::preset`] documents them.
pub const PRESETS: [&str; 4] = ["iasm6", "respeaker4", "respeaker6", "uma8"];

/// Two microphones closer than this (m) are taken to be the same one: a copy-paste slip in
/// an array file, which would make a pair with no delay information.
const DUPLICATE_TOL_M: f64 = 1e-4;

/// An array whose microphones all lie within this fraction of its aperture of one line is
/// linear ([`MicArray::linear_axis`]). Why 1 %: the two mirror directions of a line differ
/// in delay by at most `2 d / c` for microphones `d` off it; at 1 % of a 0.1-0.2 m line,
/// 1-2 mm, that is 6-12 us, under a tenth of a period at 1 kHz and a quarter at 8 kHz:
/// the peaks of a source and of its mirror image stand within a few percent of each
/// other, and which is higher is the noise's choice.
const LINEAR_TOL: f64 = 0.01;

/// An array whose microphones, seen from above, span less than this fraction of its
/// aperture hears no azimuth (a vertical line, or a stack): refused.
const MIN_HORIZONTAL_SPAN: f64 = 0.1;

/// An array wider than this (m) is refused. Why: the localizer models each source as one
/// plane wave across the array, which holds for sources beyond the far-field distance
/// `2 D² f / c` (2.6 m for the paper's 0.235-m array at 8 kHz); a 2-m array's is 190 m,
/// beyond any room. The arrays robots carry are a few centimetres to a few decimetres
/// across, and a file of positions in millimetres or centimetres read as metres (a
/// 6.4-cm ReSpeaker 64 or 6.4 m wide) gave DoAs of nothing, silently.
pub const MAX_APERTURE_M: f64 = 2.0;

/// A microphone array: its name and the microphone positions (m) in the array frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MicArray {
    name: String,
    positions: Vec<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ArrayFile {
    name: Option<String>,
    positions: Vec<[f64; 3]>,
}

impl MicArray {
    /// Builds an array from positions (m).
    ///
    /// # Errors
    /// [`ArrayError`] if there are fewer than two microphones, a coordinate is not finite,
    /// two microphones are within 0.1 mm of each other, the array is wider than
    /// [`MAX_APERTURE_M`] (positions in millimetres or centimetres read as metres), or the
    /// microphones, seen from above, span less than a tenth of the aperture (a vertical
    /// line hears no azimuth).
    pub fn new(name: impl Into<String>, positions: Vec<[f64; 3]>) -> Result<Self, ArrayError> {
        if positions.len() < 2 {
            return Err(ArrayError::TooFewMics(positions.len()));
        }
        if let Some(index) = positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(ArrayError::NonFinite { index });
        }
        for a in 0..positions.len() {
            for b in a + 1..positions.len() {
                if dist(positions[a], positions[b]) < DUPLICATE_TOL_M {
                    return Err(ArrayError::Duplicate { a, b });
                }
            }
        }
        let array = Self {
            name: name.into(),
            positions,
        };
        let aperture = array.aperture();
        if aperture > MAX_APERTURE_M {
            return Err(ArrayError::TooLarge {
                aperture_m: aperture,
            });
        }
        let flat: Vec<[f64; 3]> = array.positions.iter().map(|p| [p[0], p[1], 0.0]).collect();
        let horizontal = span(&flat);
        if horizontal < MIN_HORIZONTAL_SPAN * aperture {
            return Err(ArrayError::NoAzimuth {
                horizontal_m: horizontal,
                aperture_m: aperture,
            });
        }
        Ok(array)
    }

    /// A built-in array by name:
    ///
    /// - `iasm6`: the I-ASM paper's 6-microphone array (a 0.235 m body; two staggered
    ///   triangles at 0.104 m and 0.208 m height), from the authors' published data.
    /// - `respeaker4`: Seeed ReSpeaker USB Mic Array v2.0, 4 microphones on a circle of
    ///   radius 32 mm (ODAS configuration), channel order as its 4-channel raw firmware.
    /// - `respeaker6`: Seeed ReSpeaker 6-Mic Circular Array for Raspberry Pi, radius 46.3 mm,
    ///   microphones every 60 degrees starting on the x axis.
    /// - `uma8`: miniDSP UMA-8, 6 microphones on a circle of radius 43 mm plus one at the
    ///   centre (channel 0).
    ///
    /// Check the channel order of circular arrays against your driver: it varies with firmware.
    ///
    /// # Errors
    /// [`ArrayError::UnknownPreset`] for any other name.
    pub fn preset(name: &str) -> Result<Self, ArrayError> {
        let positions = match name {
            "iasm6" => vec![
                [0.1200, 0.0, 0.1040],
                [-0.0600, 0.1039, 0.1040],
                [-0.0600, -0.1039, 0.1040],
                [-0.0606, -0.0350, 0.2080],
                [0.0606, -0.0350, 0.2080],
                [0.0000, 0.0700, 0.2080],
            ],
            "respeaker4" => vec![
                [-0.032, 0.0, 0.0],
                [0.0, -0.032, 0.0],
                [0.032, 0.0, 0.0],
                [0.0, 0.032, 0.0],
            ],
            "respeaker6" => circle(0.0463, 6),
            "uma8" => {
                let mut p = vec![[0.0, 0.0, 0.0]];
                p.extend(circle(0.043, 6));
                p
            }
            _ => {
                return Err(ArrayError::UnknownPreset {
                    name: name.to_owned(),
                    presets: &PRESETS,
                });
            }
        };
        Self::new(name, positions)
    }

    /// Reads an array from a TOML (`.toml`) or JSON (any other extension) file with a
    /// `positions` list of `[x, y, z]` (m) and an optional `name` (default: the file stem).
    ///
    /// # Errors
    /// [`ArrayError::Io`] if the file cannot be read, [`ArrayError::Parse`] if it is not
    /// valid, [`ArrayError::Invalid`] if the geometry is refused by [`MicArray::new`].
    pub fn from_file(path: &Path) -> Result<Self, ArrayError> {
        let text = std::fs::read_to_string(path).map_err(|source| ArrayError::Io {
            path: path.to_owned(),
            source,
        })?;
        let is_toml = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        let parsed: ArrayFile = if is_toml {
            toml::from_str(&text).map_err(|e| e.message().to_owned())
        } else {
            serde_json::from_str(&text).map_err(|e| e.to_string())
        }
        .map_err(|message| ArrayError::Parse {
            path: path.to_owned(),
            message,
        })?;
        let name = parsed.name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        Self::new(name, parsed.positions).map_err(|e| ArrayError::Invalid {
            path: path.to_owned(),
            reason: Box::new(e),
        })
    }

    /// A preset name, or else a path to an array file.
    ///
    /// # Errors
    /// As [`MicArray::preset`] when `spec` names no existing file, else as
    /// [`MicArray::from_file`].
    pub fn from_spec(spec: &str) -> Result<Self, ArrayError> {
        let path = Path::new(spec);
        if PRESETS.contains(&spec) || !path.exists() {
            Self::preset(spec)
        } else {
            Self::from_file(path)
        }
    }

    /// The array's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Microphone positions (m), channel order.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Number of microphones.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Always false: an array has at least two microphones.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// All microphone pairs `(i, j)` with `i < j`.
    pub fn pairs(&self) -> Vec<(usize, usize)> {
        let n = self.len();
        (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .collect()
    }

    /// The largest distance between two microphones (m), the array's aperture.
    pub fn aperture(&self) -> f64 {
        span(&self.positions)
    }

    /// The unit vector of the line the microphones lie on, when they do (within 1 % of
    /// the aperture), pointing from the first microphone to the one furthest from it;
    /// `None` for an array that spans a plane or a volume.
    ///
    /// A linear array (a Kinect's four microphones, a two-microphone head) hears only the
    /// angle between a source and its line: every direction on a cone around the line
    /// gives the same delays. In the horizontal plane that leaves two azimuths, mirror
    /// images in the line ([`MicArray::mirror_axis_deg`]), and no recording can tell them
    /// apart; only a robot that turns can (see `asm::IasmConfig::mirror_axis_deg`).
    pub fn linear_axis(&self) -> Option<[f64; 3]> {
        let p = &self.positions;
        let far = (1..p.len())
            .max_by(|&a, &b| dist(p[0], p[a]).total_cmp(&dist(p[0], p[b])))
            .expect("an array has two microphones");
        let len = dist(p[0], p[far]);
        let u = [0, 1, 2].map(|i| (p[far][i] - p[0][i]) / len);
        let off_line = p
            .iter()
            .map(|q| {
                let v = [0, 1, 2].map(|i| q[i] - p[0][i]);
                let along = v[0] * u[0] + v[1] * u[1] + v[2] * u[2];
                dist(v, u.map(|c| c * along))
            })
            .fold(0.0, f64::max);
        (off_line <= LINEAR_TOL * self.aperture()).then_some(u)
    }

    /// For a linear array ([`MicArray::linear_axis`]), the azimuth of its line in the
    /// array frame, in `[0, 180)` degrees: a source at azimuth `a` (in the horizontal
    /// plane) and one at `2 * axis - a` give every pair the same delay. `None` for an
    /// array that is not linear.
    pub fn mirror_axis_deg(&self) -> Option<f64> {
        self.linear_axis()
            .map(|u| u[1].atan2(u[0]).to_degrees().rem_euclid(180.0))
    }
}

/// `azimuth_deg` on the counter-clockwise side of a linear array's line at `axis_deg`
/// ([`MicArray::mirror_axis_deg`]): of a direction and its mirror image in the line, the
/// one in `[axis, axis + 180]`; `azimuth_deg` itself when `axis_deg` is `None`. The
/// localizer reports a linear array's DoAs so ([`crate::Localizer::mirror_axis_deg`]); fold a true
/// bearing the same way to compare it with them.
pub fn fold_azimuth(azimuth_deg: f64, axis_deg: Option<f64>) -> f64 {
    match axis_deg {
        Some(axis) => crate::wrap_deg(axis + crate::wrap_deg(azimuth_deg - axis).abs()),
        None => azimuth_deg,
    }
}

/// The largest distance between two of `points`.
fn span(points: &[[f64; 3]]) -> f64 {
    let mut widest = 0.0f64;
    for (i, &a) in points.iter().enumerate() {
        for &b in &points[i + 1..] {
            widest = widest.max(dist(a, b));
        }
    }
    widest
}

impl Default for MicArray {
    /// The paper's array, `iasm6`.
    fn default() -> Self {
        Self::preset("iasm6").expect("the iasm6 preset is valid")
    }
}

pub(crate) fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn circle(radius: f64, n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [radius * a.cos(), radius * a.sin(), 0.0]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_is_valid() {
        for name in PRESETS {
            let a = MicArray::preset(name).unwrap();
            assert_eq!(a.name(), name);
        }
    }

    #[test]
    fn iasm6_aperture_is_mic1_to_mic4() {
        // The paper's 0.235 m is the diameter of the array's body; the microphones span
        // less. The widest pair, by hand: mic 1 (0.12, 0, 0.104) to mic 4
        // (-0.0606, -0.035, 0.208) = sqrt(0.1806^2 + 0.035^2 + 0.104^2) = 0.2113 m.
        let a = MicArray::default();
        assert_eq!(a.len(), 6);
        assert_eq!(a.pairs().len(), 15);
        assert!((a.aperture() - 0.2113).abs() < 1e-3, "{}", a.aperture());
    }

    #[test]
    fn an_array_in_millimetres_read_as_metres_is_refused() {
        // The ReSpeaker 4-mic's positions in millimetres: 64 m across.
        let mm = vec![
            [-32.0, 0.0, 0.0],
            [0.0, -32.0, 0.0],
            [32.0, 0.0, 0.0],
            [0.0, 32.0, 0.0],
        ];
        let e = MicArray::new("mm", mm).unwrap_err();
        assert!(
            matches!(e, ArrayError::TooLarge { aperture_m } if (aperture_m - 64.0).abs() < 1e-9)
        );
        assert!(e.to_string().contains("millimetres"), "{e}");
        // A large robot's array, 1.9 m across, is taken.
        assert!(
            MicArray::new(
                "wide",
                vec![[0.0, 0.0, 0.0], [1.9, 0.0, 0.0], [0.0, 0.5, 0.0]]
            )
            .is_ok()
        );
    }

    #[test]
    fn a_line_of_microphones_is_linear_and_mirrors_about_its_azimuth() {
        // Four microphones on a line at 30 degrees to the heading, 4 cm apart, 0.5 mm off
        // it (under 1 % of the 12 cm aperture).
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let line: Vec<[f64; 3]> = [-0.06, -0.02, 0.02, 0.06]
            .iter()
            .enumerate()
            .map(|(i, &t)| [t * c, t * s + if i == 1 { 0.0005 } else { 0.0 }, 0.0])
            .collect();
        let a = MicArray::new("line", line).unwrap();
        let u = a.linear_axis().unwrap();
        assert!((u[0] - c).abs() < 1e-2 && (u[1] - s).abs() < 1e-2, "{u:?}");
        assert!((a.mirror_axis_deg().unwrap() - 30.0).abs() < 0.5);
        // Pointing the other way, the line is the same line.
        let back = MicArray::new("back", a.positions().iter().rev().copied().collect()).unwrap();
        assert!((back.mirror_axis_deg().unwrap() - 30.0).abs() < 0.5);
        // Two microphones are always a line; the presets span a plane or a volume.
        let pair = MicArray::new("pair", vec![[0.0, 0.1, 0.0], [0.0, -0.1, 0.0]]).unwrap();
        assert!((pair.mirror_axis_deg().unwrap() - 90.0).abs() < 1e-9);
        for name in PRESETS {
            assert_eq!(
                MicArray::preset(name).unwrap().linear_axis(),
                None,
                "{name}"
            );
        }
        // 2 mm off a 12 cm line is beyond 1 %: a (thin) plane.
        let bent = MicArray::new(
            "bent",
            vec![[-0.06, 0.0, 0.0], [0.0, 0.002, 0.0], [0.06, 0.0, 0.0]],
        )
        .unwrap();
        assert_eq!(bent.linear_axis(), None);
    }

    #[test]
    fn a_vertical_line_hears_no_azimuth_and_is_refused() {
        let e = MicArray::new(
            "mast",
            vec![[0.0, 0.0, 0.0], [0.005, 0.0, 0.1], [0.0, 0.0, 0.2]],
        )
        .unwrap_err();
        assert!(matches!(e, ArrayError::NoAzimuth { .. }), "{e}");
        assert!(e.to_string().contains("azimuth"), "{e}");
    }

    #[test]
    fn one_microphone_is_refused() {
        assert!(matches!(
            MicArray::new("x", vec![[0.0; 3]]),
            Err(ArrayError::TooFewMics(1))
        ));
    }

    #[test]
    fn duplicate_positions_are_refused() {
        let e = MicArray::new("x", vec![[0.0; 3], [0.1, 0.0, 0.0], [0.1, 0.0, 0.0]]).unwrap_err();
        assert!(matches!(e, ArrayError::Duplicate { a: 1, b: 2 }), "{e}");
    }

    #[test]
    fn non_finite_positions_are_refused() {
        let e = MicArray::new("x", vec![[0.0; 3], [f64::NAN, 0.0, 0.0]]).unwrap_err();
        assert!(matches!(e, ArrayError::NonFinite { index: 1 }));
    }

    #[test]
    fn unknown_preset_lists_the_presets() {
        let e = MicArray::preset("nope").unwrap_err().to_string();
        assert!(e.contains("iasm6") && e.contains("nope"), "{e}");
    }

    #[test]
    fn toml_and_json_files_load() {
        let dir = tempfile::tempdir().unwrap();
        let t = dir.path().join("tri.toml");
        std::fs::write(
            &t,
            "positions = [[0.0,0.0,0.0],[0.1,0.0,0.0],[0.0,0.1,0.0]]\n",
        )
        .unwrap();
        let a = MicArray::from_file(&t).unwrap();
        assert_eq!((a.name(), a.len()), ("tri", 3));
        let j = dir.path().join("pair.json");
        std::fs::write(&j, r#"{"name":"p","positions":[[0,0,0],[0.2,0,0]]}"#).unwrap();
        let a = MicArray::from_file(&j).unwrap();
        assert_eq!((a.name(), a.len()), ("p", 2));
    }

    #[test]
    fn a_file_with_one_microphone_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let t = dir.path().join("one.toml");
        std::fs::write(&t, "positions = [[0.0,0.0,0.0]]\n").unwrap();
        let e = MicArray::from_file(&t).unwrap_err().to_string();
        assert!(e.contains("one.toml") && e.contains("at least two"), "{e}");
    }
}
