//! Scenes: a room (a shoebox, or any floor plan) with sources, and a robot carrying an
//! array along a trajectory.
//! One TOML file describes a scene; [`PreparedScene::render_stop`] renders what the array hears at
//! one stop.
//!
//! ```toml
//! name = "two_talkers"
//! seed = 7
//! fs = 16000            # Hz
//! clip_s = 1.0          # seconds recorded at each stop
//! snr_db = 30.0         # sensor noise against the mean signal power at the microphones
//! [room]
//! dims = [6.0, 4.0, 3.0]
//! rt60 = 0.3            # or absorption = [x0, x1, y0, y1, floor, ceiling]
//! # A room that is not a box: its floor plan instead of dims (corners in order, x, y >= 0),
//! # rendered by `crate::plan` (images checked per microphone, a diffuse tail):
//! # plan = [[0, 0], [8, 0], [8, 7], [5, 7], [5, 3], [0, 3]]   # an L
//! # height = 3.0
//! # rt60 = 0.6          # or absorption = [one per wall (corner i to i + 1)..., floor, ceiling]
//! [array]
//! preset = "iasm6"      # resolved by the application; or positions = [[x, y, z], ...]
//! height = 0.6          # height of the array frame's origin (m)
//! [[sources]]
//! pos = [1.5, 3.0, 1.2]
//! signal = "voiced"     # white_noise | pink_noise | speech_shaped | voiced
//! f0 = 140.0
//! # or: wav = "talker.wav" (relative to the scene file; first channel, at the scene's fs)
//! level_db = 65.0       # dB SPL at 1 m
//! active_s = [0.0, 0.8] # plays only then (s into each clip); the decay follows
//! at_stops = [0, 5]     # plays at stops 0 to 5 only (a talker who leaves)
//! # moves = [{ from_stop = 12, pos = [4.0, 2.5, 1.2] }]   # from stop 12 on, it is there
//! [[sources]]           # the robot's own noise (a fan): carried with the array
//! on_robot = true       # pos is then [forward, left, up] (m) in the array frame
//! pos = [-0.15, 0.05, -0.25]
//! signal = "pink_noise"
//! [trajectory]
//! waypoints = [[1.0, 1.0], [5.0, 1.0]]
//! spacing = 0.5         # or poses = [[x, y, theta_deg], ...]
//! ```

use geom::Pose;
use rand::{Rng, SeedableRng, rngs::StdRng};
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::error::SimError;
use crate::render::{RenderConfig, Renderer, RoomSource};
use crate::room::Space;
use crate::signal::{SignalKind, scale_to_unit_power};
pub use room::RoomSpec;

fn invalid(field: impl Into<String>, message: impl Into<String>) -> SimError {
    SimError::Invalid {
        field: field.into(),
        message: message.into(),
    }
}

/// The most stops a scene may have (each is rendered: a bound on work and memory).
pub const MAX_STOPS: usize = 10_000;
/// The most samples of source signal a scene may hold (all sources, one clip each: 256 MiB).
pub const MAX_SIGNAL_SAMPLES: usize = 1 << 25;
/// The highest sample rate a scene may ask for (Hz).
pub const MAX_FS: u32 = 384_000;
/// The longest clip per stop (s).
pub const MAX_CLIP_S: f64 = 60.0;
/// The longest reverberation time (s): the most reverberant spaces measured are below it.
pub const MAX_RT60_S: f64 = 20.0;
/// The most image sources the RT60 calibration or a response of `rir_s` may enumerate
/// (their cost grows with the cube of the decay's length over the room's size).
pub const MAX_CALIBRATION_IMAGES: f64 = 5e7;

/// A scene as written in its TOML file.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name used in reports. Default: empty.
    #[serde(default)]
    pub name: String,
    /// Seed of every random signal. Default: 0.
    #[serde(default)]
    pub seed: u64,
    /// Sample rate (Hz). Default: 16000.
    #[serde(default = "default_fs")]
    pub fs: u32,
    /// Seconds recorded at each stop. Default: 1.
    #[serde(default = "default_clip")]
    pub clip_s: f64,
    /// Speed of sound (m/s). Default: 343.
    #[serde(default = "default_c")]
    pub speed_of_sound: f64,
    /// Sensor noise (dB below the mean signal power at the microphones). Default: none.
    #[serde(default)]
    pub snr_db: Option<f64>,
    /// At most this many reflections per image. Default: every image within the response.
    #[serde(default)]
    pub max_order: Option<u32>,
    /// Response length (s). Default: the room's RT60 target, at most 0.5 s.
    #[serde(default)]
    pub rir_s: Option<f64>,
    /// The room.
    pub room: RoomSpec,
    /// The array.
    pub array: ArraySpec,
    /// The sources.
    pub sources: Vec<SourceSpec>,
    /// The robot's stops.
    pub trajectory: TrajectorySpec,
    /// Box obstacles (they appear in the occupancy map; sound passes them).
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
}

fn default_fs() -> u32 {
    16_000
}
fn default_clip() -> f64 {
    1.0
}
fn default_c() -> f64 {
    343.0
}

/// The array of a scene.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ArraySpec {
    /// A preset name, resolved by the application.
    pub preset: Option<String>,
    /// Microphone positions in the array frame (m).
    pub positions: Option<Vec<[f64; 3]>>,
    /// Height of the array frame's origin above the floor (m).
    pub height: f64,
}

/// One source of a scene.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SourceSpec {
    /// Position (m).
    pub pos: [f64; 3],
    /// `white_noise`, `pink_noise`, `speech_shaped` or `voiced`. Default: `speech_shaped`
    /// (unless `wav` is given).
    #[serde(default)]
    pub signal: Option<SignalKind>,
    /// A recording to play instead of a generated signal: its first channel, at the scene's
    /// sample rate, repeated if shorter than the clip and cut if longer, scaled to
    /// `level_db` like the generated signals. A relative path is relative to the scene file
    /// once [`Scene::resolve_paths`] has run (the CLI does).
    #[serde(default)]
    pub wav: Option<std::path::PathBuf>,
    /// Fundamental (Hz) of a voiced source. Default: 140.
    #[serde(default = "default_f0")]
    pub f0: f64,
    /// Level (dB SPL at 1 m). Default: 65.
    #[serde(default = "default_level")]
    pub level_db: f64,
    /// `[start, stop]` (s from the start of each stop's clip): the source plays only
    /// then, silent before and after, so that a recording holds its onset and the room's
    /// decay after it stops. Default: the whole clip.
    #[serde(default)]
    pub active_s: Option<[f64; 2]>,
    /// `[first, last]` (stop indices from 0, inclusive): the source plays at those stops
    /// only and is silent at the others (a talker who arrives or leaves while the robot
    /// drives). Default: every stop.
    #[serde(default)]
    pub at_stops: Option<[usize; 2]>,
    /// The source is part of the robot (a fan, a computer, a motor held still): it moves
    /// with the array, and `pos` is its position in the array frame (forward, left, up
    /// from the array frame's origin, m), as the microphones' are. Its signal is the same
    /// kind at every stop, and [`PreparedScene::render_robot_alone`] renders it without the
    /// room's sources (the recording a user makes of the robot standing in a quiet room
    /// to tell the SSL what its own noise sounds like). Default: false.
    #[serde(default)]
    pub on_robot: bool,
    /// Where the source goes during the run (a talker who walks to another desk between
    /// two stops): each entry a stop (from 0) from which on it stands at `pos`, in stop
    /// order, after the first stop it plays at and no later than its last. It plays the same
    /// signal at every place, rendered with the same image model. Default: it stays at
    /// `pos`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub moves: Vec<SourceMove>,
}

/// A source's move ([`SourceSpec::moves`]).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SourceMove {
    /// The first stop (from 0) at which the source stands at `pos`.
    pub from_stop: usize,
    /// Its position from then on (m).
    pub pos: [f64; 3],
}

/// Where a source of the room stands over a stretch of the run: what a map of the room at
/// a stop of `stops` should hold ([`PreparedScene::places`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Place {
    /// The source (its index among the scene's sources in the room, not on the robot).
    pub source: usize,
    /// Where it stands (m).
    pub pos: [f64; 3],
    /// The stops (from 0, inclusive) at which it plays there.
    pub stops: [usize; 2],
}

impl Place {
    /// Whether the source plays here at stop `k`.
    pub fn plays_at(&self, k: usize) -> bool {
        (self.stops[0]..=self.stops[1]).contains(&k)
    }
}

impl SourceSpec {
    /// The first and last stop (inclusive) at which the source plays over a run of
    /// `n_stops` stops: `at_stops`, or every stop.
    pub fn stop_range(&self, n_stops: usize) -> [usize; 2] {
        self.at_stops.unwrap_or([0, n_stops.saturating_sub(1)])
    }

    /// The places this source stands at over a run of `n_stops` stops: its `pos` from the
    /// first stop it plays at ([`SourceSpec::stop_range`]), then each of its `moves`, up to
    /// the last stop it plays at. `source` is recorded in each. Expects a checked scene.
    pub fn places(&self, source: usize, n_stops: usize) -> Vec<Place> {
        let [first, last] = self.stop_range(n_stops);
        let mut starts: Vec<(usize, [f64; 3])> = vec![(first, self.pos)];
        starts.extend(self.moves.iter().map(|m| (m.from_stop, m.pos)));
        starts
            .iter()
            .enumerate()
            .map(|(i, &(from, pos))| Place {
                source,
                pos,
                stops: [from, starts.get(i + 1).map_or(last, |&(next, _)| next - 1)],
            })
            .collect()
    }
}

fn default_f0() -> f64 {
    140.0
}
fn default_level() -> f64 {
    65.0
}

/// The robot's stops: explicit poses, or waypoints walked at a spacing.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySpec {
    /// `[x, y, theta_deg]` per stop.
    pub poses: Option<Vec<[f64; 3]>>,
    /// Corners of a polyline.
    pub waypoints: Option<Vec<[f64; 2]>>,
    /// Distance between stops along the polyline (m).
    pub spacing: Option<f64>,
}

/// An axis-aligned box obstacle (m).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// Lower corner (x, y).
    pub min: [f64; 2],
    /// Upper corner (x, y).
    pub max: [f64; 2],
}

/// A checked scene, ready to render.
#[derive(Clone, Debug)]
pub struct PreparedScene {
    /// The scene as written.
    pub scene: Scene,
    /// The room.
    pub room: Space,
    /// Microphone positions in the array frame (m).
    pub mics: Vec<[f64; 3]>,
    /// The robot's stops.
    pub stops: Vec<Pose>,
    /// Each source's signal (pressure at 1 m, Pa).
    pub signals: Vec<Vec<f64>>,
    /// Each source's signal in the recording of the robot alone
    /// ([`PreparedScene::render_robot_alone`]): another stretch of the same kind of signal
    /// for the sources on the robot (a noise recorded at another time is another
    /// realisation of it), empty for the others.
    pub alone_signals: Vec<Vec<f64>>,
    /// Built on the first stop rendered, shared by the others.
    renderer: std::sync::OnceLock<Renderer>,
}

impl Scene {
    /// Parses a scene.
    ///
    /// # Errors
    /// [`SimError::Parse`] with the TOML parser's message (unknown keys are refused, and
    /// named).
    pub fn from_toml(text: &str) -> Result<Self, SimError> {
        toml::from_str(text).map_err(|e| SimError::Parse(e.message().to_owned()))
    }

    /// Makes every relative `wav` path relative to `base` (the scene file's folder).
    pub fn resolve_paths(&mut self, base: &std::path::Path) {
        for s in &mut self.sources {
            if let Some(p) = &mut s.wav
                && p.is_relative()
            {
                *p = base.join(&*p);
            }
        }
    }

    fn clip_samples(&self) -> usize {
        (self.clip_s * f64::from(self.fs)).round() as usize
    }

    pub(crate) fn stops(&self) -> Result<Vec<Pose>, SimError> {
        let t = &self.trajectory;
        match (&t.poses, &t.waypoints) {
            (Some(p), None) if p.len() > MAX_STOPS => Err(invalid(
                "trajectory.poses",
                format!("{} poses are more than {MAX_STOPS}", p.len()),
            )),
            (Some(p), None) if !p.is_empty() => Ok(p
                .iter()
                .map(|q| Pose::from_degrees(q[0], q[1], q[2]))
                .collect()),
            (None, Some(w)) if w.len() >= 2 => {
                let spacing = t
                    .spacing
                    .ok_or_else(|| invalid("trajectory.spacing", "waypoints need a spacing"))?;
                if !(spacing.is_finite() && spacing > 0.0) {
                    return Err(invalid(
                        "trajectory.spacing",
                        format!("{spacing} m is not positive"),
                    ));
                }
                // Check the path before walking it: its length bounds the stop count.
                let [lx, ly] = self.room_extent();
                for (i, p) in w.iter().enumerate() {
                    if !((0.0..=lx).contains(&p[0]) && (0.0..=ly).contains(&p[1])) {
                        return Err(invalid(
                            format!("trajectory.waypoints[{i}]"),
                            format!("{p:?} is outside the room (0..{lx}, 0..{ly})"),
                        ));
                    }
                }
                let length: f64 = w
                    .windows(2)
                    .map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]))
                    .sum();
                if length / spacing > MAX_STOPS as f64 {
                    return Err(invalid(
                        "trajectory.spacing",
                        format!(
                            "{spacing} m along a {length:.1} m path is more than {MAX_STOPS} stops"
                        ),
                    ));
                }
                let mut out = Vec::new();
                let mut carry = 0.0; // distance along the current segment to the next stop
                for seg in w.windows(2) {
                    let (a, b) = (seg[0], seg[1]);
                    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
                    let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
                    let mut s = carry;
                    while s <= len + 1e-9 {
                        let f = if len > 0.0 { s / len } else { 0.0 };
                        let (x, y) = (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
                        out.push(Pose::new(x, y, heading));
                        s += spacing;
                    }
                    carry = s - len;
                }
                Ok(out)
            }
            _ => Err(invalid(
                "trajectory",
                "give poses, or at least two waypoints and a spacing",
            )),
        }
    }
}

/// The recording of the robot alone lasts this long (s), or a stop's clip if longer: a
/// user records a few seconds of it, and its covariance is a mean over them.
pub const ROBOT_ALONE_S: f64 = 4.0;

/// Seeds the signals of the recording of the robot alone (with the scene's seed).
const ROBOT_ALONE_SEED: u64 = 0x0A11_0E5E_ED00_0001;

/// World position of array-frame point `p` with the robot at `stop` and the array frame's
/// origin `height` above the floor.
pub fn mic_world(stop: Pose, height: f64, p: [f64; 3]) -> [f64; 3] {
    let (s, c) = stop.theta.sin_cos();
    [
        stop.x + c * p[0] - s * p[1],
        stop.y + s * p[0] + c * p[1],
        height + p[2],
    ]
}

/// `n` samples of the first channel of the WAV file at `path`, which must be sampled at
/// `fs`, repeated as needed, scaled to unit mean power.
fn wav_signal(path: &std::path::Path, n: usize, fs: u32) -> Result<Vec<f64>, String> {
    let mut r = hound::WavReader::open(path).map_err(|e| e.to_string())?;
    let spec = r.spec();
    if spec.sample_rate != fs {
        return Err(format!(
            "sampled at {} Hz, the scene at {fs} Hz (resample the file)",
            spec.sample_rate
        ));
    }
    let ch = usize::from(spec.channels.max(1));
    let first: Vec<f64> = match spec.sample_format {
        hound::SampleFormat::Float => r
            .samples::<f32>()
            .step_by(ch)
            .map(|v| v.map(f64::from))
            .collect::<Result<_, _>>(),
        hound::SampleFormat::Int => {
            let scale = 2f64.powi(i32::from(spec.bits_per_sample) - 1);
            r.samples::<i32>()
                .step_by(ch)
                .map(|v| v.map(|v| f64::from(v) / scale))
                .collect::<Result<_, _>>()
        }
    }
    .map_err(|e| e.to_string())?;
    if first.is_empty() {
        return Err("has no samples".into());
    }
    let mut x: Vec<f64> = first.iter().copied().cycle().take(n).collect();
    let p = scale_to_unit_power(&mut x);
    if !(p > 0.0 && p.is_finite()) {
        return Err("is silent (or not finite) over the clip".into());
    }
    Ok(x)
}

impl PreparedScene {
    /// Samples per stop.
    pub fn clip_samples(&self) -> usize {
        self.scene.clip_samples()
    }

    /// The scene's sources ready to render (built once, on first use).
    pub fn renderer(&self) -> &Renderer {
        self.renderer.get_or_init(|| {
            let room_signals: Vec<&Vec<f64>> = (self.scene.sources.iter().zip(&self.signals))
                .filter(|(s, _)| !s.on_robot)
                .map(|(_, x)| x)
                .collect();
            let sources: Vec<RoomSource> = self
                .places()
                .iter()
                .map(|p| RoomSource {
                    pos: p.pos,
                    signal: room_signals[p.source].clone(),
                })
                .collect();
            Renderer::new_in(
                &self.room,
                &sources,
                self.clip_samples(),
                &self.render_config(),
            )
        })
    }

    fn render_config(&self) -> RenderConfig {
        let sc = &self.scene;
        let rir_s = sc
            .rir_s
            .unwrap_or_else(|| sc.room.rt60.unwrap_or(0.3).min(0.5));
        RenderConfig {
            fs: f64::from(sc.fs),
            speed_of_sound: sc.speed_of_sound,
            rir_len: (rir_s * f64::from(sc.fs)) as usize,
            max_order: sc.max_order,
        }
    }

    /// The sources in the room (every one not `on_robot`): what a map should find.
    pub fn room_sources(&self) -> impl Iterator<Item = &SourceSpec> {
        self.scene.sources.iter().filter(|s| !s.on_robot)
    }

    /// Every place a source of the room stands at during the run, source by source
    /// ([`SourceSpec::places`]): one per source that does not move. The renderer renders
    /// each as a source of its own, playing at its stops.
    pub fn places(&self) -> Vec<Place> {
        self.room_sources()
            .enumerate()
            .flat_map(|(i, s)| s.places(i, self.stops.len()))
            .collect()
    }

    /// The places a map made after stop `k` should hold as sounding then.
    pub fn places_at(&self, k: usize) -> Vec<Place> {
        self.places()
            .into_iter()
            .filter(|p| p.plays_at(k))
            .collect()
    }

    /// Whether any source is carried by the robot (`on_robot`).
    pub fn has_robot_sources(&self) -> bool {
        self.scene.sources.iter().any(|s| s.on_robot)
    }

    /// The sources on the robot at stop `k`, each with `signals` (one per scene source),
    /// rendered at `mics`: their images depend on where the robot stands, so each stop
    /// builds its own.
    fn render_on_robot(
        &self,
        k: usize,
        signals: &[Vec<f64>],
        mics: &[[f64; 3]],
    ) -> Option<Vec<Vec<f64>>> {
        let sc = &self.scene;
        let sources: Vec<RoomSource> = sc
            .sources
            .iter()
            .zip(signals)
            .filter(|(s, _)| s.on_robot)
            .map(|(s, x)| RoomSource {
                pos: mic_world(self.stops[k], sc.array.height, s.pos),
                signal: x.clone(),
            })
            .collect();
        let n = signals.iter().map(Vec::len).max().unwrap_or(0);
        (!sources.is_empty())
            .then(|| Renderer::new_in(&self.room, &sources, n, &self.render_config()).render(mics))
    }

    /// What the array hears of the robot alone at stop `k`: its own sources (`on_robot`,
    /// another stretch of their signals than at the stops) and the sensor noise of stop
    /// `k` (another draw of it), without the room's sources: the recording a user makes of
    /// the robot's own noise. `None` when no source is on the robot.
    ///
    /// # Panics
    /// If `k` is not a stop.
    pub fn render_robot_alone(&self, k: usize) -> Option<Vec<Vec<f64>>> {
        let mics = self.mics_at(k);
        let mut out = self.render_on_robot(k, &self.alone_signals, &mics)?;
        self.add_sensor_noise(k, &mics, &mut out, ROBOT_ALONE_SEED);
        Some(out)
    }

    fn mics_at(&self, k: usize) -> Vec<[f64; 3]> {
        self.mics
            .iter()
            .map(|&p| mic_world(self.stops[k], self.scene.array.height, p))
            .collect()
    }

    /// What the array hears at stop `k` (channel-major, Pa), with sensor noise seeded by the
    /// scene's seed and `k` (so stops can be rendered in any order, in parallel).
    ///
    /// # Panics
    /// If `k` is not a stop.
    pub fn render_stop(&self, k: usize) -> Vec<Vec<f64>> {
        let mics = self.mics_at(k);
        let places = self.places();
        let playing: Vec<bool> = places.iter().map(|p| p.plays_at(k)).collect();
        let mut out = self.renderer().render_playing(&mics, &playing);
        self.add_sensor_noise_of(k, &mics, &mut out, &playing, 0);
        if let Some(robot) = self.render_on_robot(k, &self.signals, &mics) {
            for (o, r) in out.iter_mut().zip(&robot) {
                for (o, r) in o.iter_mut().zip(r) {
                    *o += r;
                }
            }
        }
        out
    }

    /// Adds stop `k`'s sensor noise to `out` (heard at `mics`), its generator's seed mixed
    /// with `salt`.
    fn add_sensor_noise(&self, k: usize, mics: &[[f64; 3]], out: &mut [Vec<f64>], salt: u64) {
        let n_places = self.places().len();
        self.add_sensor_noise_of(k, mics, out, &vec![false; n_places], salt);
    }

    /// Adds sensor noise at the scene's SNR against what the room's sources give at `mics`
    /// with every one playing, each at its first place (`out` already holds it when every
    /// flag of `playing`, one per [`Place`], is set and no source moves): a stop where one
    /// is silent hears the same noise, and the robot's own sources do not change it.
    fn add_sensor_noise_of(
        &self,
        k: usize,
        mics: &[[f64; 3]],
        out: &mut [Vec<f64>],
        playing: &[bool],
        salt: u64,
    ) {
        let sc = &self.scene;
        let Some(snr) = sc.snr_db else {
            return;
        };
        let places = self.places();
        // Each source at its first place: the level the noise is set against does not
        // change as a source moves.
        let reference: Vec<bool> = (0..places.len())
            .map(|i| i == 0 || places[i - 1].source != places[i].source)
            .collect();
        let everyone = if playing == reference.as_slice() {
            None
        } else {
            Some(self.renderer().render_playing(mics, &reference))
        };
        let full = everyone.as_deref().unwrap_or(out);
        let p =
            full.iter().flatten().map(|v| v * v).sum::<f64>() / (full.len() * full[0].len()) as f64;
        let sd = p.sqrt() * 10f64.powf(-snr / 20.0);
        let mut rng = StdRng::seed_from_u64(
            sc.seed ^ salt ^ (0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k as u64 + 1)),
        );
        for ch in out.iter_mut() {
            for v in ch.iter_mut() {
                *v += sd * rng.sample::<f64, _>(StandardNormal);
            }
        }
    }
}

mod prepare;
mod room;
#[cfg(test)]
mod tests;
