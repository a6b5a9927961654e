//! Checking a scene and precomputing what rendering it needs ([`Scene::prepare`]): the
//! settings, the array, where every source, stop and microphone stands, the signal budget,
//! then the sources' signals and the robot's own noise heard alone.

use rand::{SeedableRng, rngs::StdRng};

use super::{
    MAX_CALIBRATION_IMAGES, MAX_CLIP_S, MAX_FS, MAX_RT60_S, MAX_SIGNAL_SAMPLES, PreparedScene,
    ROBOT_ALONE_S, ROBOT_ALONE_SEED, Scene, SourceSpec, invalid, mic_world, wav_signal,
};
use crate::error::SimError;
use crate::room::Space;
use crate::signal::generate;
use geom::Pose;

impl Scene {
    /// Checks the scene and precomputes the room, stops and signals. `preset` resolves
    /// `array.preset` to positions.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the field: a source, stop or microphone outside the
    /// room, an absorption outside [0, 1], an RT60 the room cannot have, a bad trajectory.
    pub fn prepare(
        self,
        preset: impl Fn(&str) -> Option<Vec<[f64; 3]>>,
    ) -> Result<PreparedScene, SimError> {
        self.check_settings()?;
        let room = self.space()?;
        let mics = self.array_positions(preset)?;
        let stops = self.stops()?;
        self.check_placements(&room, &mics, &stops)?;
        let (n, n_alone) = self.signal_lengths()?;
        let signals = self.source_signals(n)?;
        let alone_signals = self.robot_alone_signals(&signals, n, n_alone);
        Ok(PreparedScene {
            scene: self,
            room,
            mics,
            stops,
            signals,
            alone_signals,
            renderer: std::sync::OnceLock::new(),
        })
    }

    /// The scene-wide settings: the sample rate, the clip, the speed of sound, the SNR,
    /// and the response length and RT60 within what the image enumeration can afford.
    fn check_settings(&self) -> Result<(), SimError> {
        if !(1000..=MAX_FS).contains(&self.fs) {
            return Err(invalid(
                "fs",
                format!("{} Hz is outside [1000, {MAX_FS}] Hz", self.fs),
            ));
        }
        if !(self.clip_s.is_finite() && self.clip_s > 0.0 && self.clip_s <= MAX_CLIP_S) {
            return Err(invalid(
                "clip_s",
                format!("{} s is not a duration in (0, {MAX_CLIP_S}] s", self.clip_s),
            ));
        }
        if !(self.speed_of_sound.is_finite() && (100.0..=2000.0).contains(&self.speed_of_sound)) {
            return Err(invalid(
                "speed_of_sound",
                format!("{} m/s is outside [100, 2000] m/s", self.speed_of_sound),
            ));
        }
        if let Some(snr) = self.snr_db.filter(|v| !v.is_finite()) {
            return Err(invalid(
                "snr_db",
                format!("{snr} dB is not a signal-to-noise ratio; leave it out for no noise"),
            ));
        }
        let r = &self.room;
        // Refuses a time `t` (s) for `field` unless in (0, MAX_RT60_S] and its `travel`
        // (metres of sound per second of it) reaches at most MAX_CALIBRATION_IMAGES image
        // sources (a sphere over the room's volume). A plan's images are enumerated for
        // its first 55 ms only, whatever the times.
        let volume: f64 = r.dims.map_or(0.0, |d| d.iter().product());
        let check_time = |field: &str, what: &str, t: f64, travel: f64, hint: &str| {
            if !(t.is_finite() && t > 0.0 && t <= MAX_RT60_S) {
                return Err(invalid(
                    field,
                    format!("{t} s is not {what} in (0, {MAX_RT60_S}] s"),
                ));
            }
            let n = 4.0 / 3.0 * std::f64::consts::PI * (t * travel).powi(3) / volume;
            if volume > 0.0 && n > MAX_CALIBRATION_IMAGES {
                return Err(invalid(
                    field,
                    format!(
                        "{t} s in a room of {volume:.3} m^3 needs {n:.1e} image sources \
                         (at most {MAX_CALIBRATION_IMAGES:.0e}); {hint}"
                    ),
                ));
            }
            Ok(())
        };
        if let Some(t) = self.rir_s {
            // With a max_order, the response stops at that order whatever its length.
            let travel = if self.max_order.is_none() {
                self.speed_of_sound
            } else {
                0.0
            };
            check_time(
                "rir_s",
                "a length",
                t,
                travel,
                "give a shorter rir_s or a max_order",
            )?;
        }
        if let Some(t) = r.rt60 {
            // The calibration enumerates every image within 1.2 RT60 of travel.
            check_time(
                "room.rt60",
                "a reverberation time",
                t,
                1.2 * self.speed_of_sound,
                "the RT60 calibration enumerates them; give a shorter rt60 or `absorption`",
            )?;
        }
        Ok(())
    }

    /// The microphones' positions in the array frame: the preset's or those given.
    fn array_positions(
        &self,
        preset: impl Fn(&str) -> Option<Vec<[f64; 3]>>,
    ) -> Result<Vec<[f64; 3]>, SimError> {
        match (&self.array.preset, &self.array.positions) {
            (Some(p), None) => {
                preset(p).ok_or_else(|| invalid("array.preset", format!("unknown array {p:?}")))
            }
            (None, Some(v)) if v.len() >= 2 => Ok(v.clone()),
            (None, Some(_)) => Err(invalid(
                "array.positions",
                "an array needs at least two microphones",
            )),
            _ => Err(invalid("array", "give preset or positions, not both")),
        }
    }

    /// Every source in the room (and one at least not on the robot), every source's
    /// `at_stops` a range of the stops, and at every stop every microphone and every source
    /// the robot carries in the room.
    fn check_placements(
        &self,
        room: &Space,
        mics: &[[f64; 3]],
        stops: &[Pose],
    ) -> Result<(), SimError> {
        for (i, s) in self.sources.iter().enumerate().filter(|(_, s)| !s.on_robot) {
            if !room.contains(s.pos) {
                return Err(invalid(
                    format!("sources[{i}].pos"),
                    format!("{:?} is outside the room", s.pos),
                ));
            }
        }
        if self.sources.iter().all(|s| s.on_robot) {
            return Err(invalid(
                "sources",
                "a scene needs at least one source in the room (not on_robot)",
            ));
        }
        for (i, src) in self.sources.iter().enumerate() {
            if let Some([first, last]) = src.at_stops
                && !(first <= last && last < stops.len())
            {
                return Err(invalid(
                    format!("sources[{i}].at_stops"),
                    format!(
                        "[{first}, {last}] is not a range of the {} stops (0..={})",
                        stops.len(),
                        stops.len().saturating_sub(1)
                    ),
                ));
            }
        }
        for (i, src) in self.sources.iter().enumerate() {
            src.check_moves(i, room, stops.len())?;
        }
        for (k, st) in stops.iter().enumerate() {
            for (m, p) in mics.iter().enumerate() {
                let w = mic_world(*st, self.array.height, *p);
                if !room.contains(w) {
                    return Err(invalid(
                        format!("trajectory stop {k}"),
                        format!("microphone {m} at {w:?} is outside the room"),
                    ));
                }
            }
            for (i, src) in self.sources.iter().enumerate().filter(|(_, s)| s.on_robot) {
                let w = mic_world(*st, self.array.height, src.pos);
                if !room.contains(w) {
                    return Err(invalid(
                        format!("sources[{i}].pos"),
                        format!("on the robot at stop {k}, {w:?} is outside the room"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Samples per clip and per recording of the robot alone, within the simulator's
    /// budget of source signal.
    fn signal_lengths(&self) -> Result<(usize, usize), SimError> {
        let n = self.clip_samples();
        let on_robot = self.sources.iter().filter(|s| s.on_robot).count();
        let n_alone = n.max((ROBOT_ALONE_S * f64::from(self.fs)).round() as usize);
        let samples = n
            .saturating_mul(self.sources.len())
            .saturating_add(n_alone.saturating_mul(on_robot));
        if samples > MAX_SIGNAL_SAMPLES {
            return Err(invalid(
                "clip_s",
                format!(
                    "{} sources of {n} samples each ({} s at {} Hz) exceed the simulator's \
                     {MAX_SIGNAL_SAMPLES} samples of source signal",
                    self.sources.len(),
                    self.clip_s,
                    self.fs
                ),
            ));
        }
        Ok((n, n_alone))
    }

    /// Each source's signal for one clip of `n` samples, at its level, silent outside its
    /// `active_s`.
    fn source_signals(&self, n: usize) -> Result<Vec<Vec<f64>>, SimError> {
        let mut rng = StdRng::seed_from_u64(self.seed);
        self.sources
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let unit = match (&s.wav, s.signal) {
                    (Some(_), Some(_)) => {
                        let field = format!("sources[{i}]");
                        return Err(invalid(field, "give signal or wav, not both"));
                    }
                    (Some(path), None) => {
                        wav_signal(path, n, self.fs).map_err(|message| SimError::Wav {
                            field: format!("sources[{i}].wav"),
                            path: path.clone(),
                            message,
                        })?
                    }
                    (None, kind) => {
                        let signal = kind.unwrap_or_default().signal(s.f0);
                        generate(signal, n, self.fs, &mut rng)
                    }
                };
                let rms = s.rms_pa();
                let mut x: Vec<f64> = unit.into_iter().map(|v| v * rms).collect();
                if let Some([start, stop]) = s.active_s {
                    if !(0.0 <= start && start < stop && start < self.clip_s) {
                        return Err(invalid(
                            format!("sources[{i}].active_s"),
                            format!(
                                "[{start}, {stop}] is not a span within the {} s clip",
                                self.clip_s
                            ),
                        ));
                    }
                    let fs = f64::from(self.fs);
                    let (a, b) = ((start * fs) as usize, ((stop * fs) as usize).min(n));
                    x[..a].fill(0.0);
                    x[b..].fill(0.0);
                }
                Ok(x)
            })
            .collect()
    }

    /// The robot alone: the same kinds of signal from a generator of their own, so that
    /// the scene's other signals do not change with whether a robot source is there
    /// (empty for the sources not on the robot).
    fn robot_alone_signals(&self, signals: &[Vec<f64>], n: usize, n_alone: usize) -> Vec<Vec<f64>> {
        let mut rng = StdRng::seed_from_u64(self.seed ^ ROBOT_ALONE_SEED);
        self.sources
            .iter()
            .zip(signals)
            .map(|(s, x)| {
                if !s.on_robot {
                    return Vec::new();
                }
                let unit = match &s.wav {
                    // Another stretch of the same recording: from its middle on, repeated.
                    Some(_) => {
                        return x
                            .iter()
                            .cycle()
                            .skip(n / 2)
                            .take(n_alone)
                            .copied()
                            .collect();
                    }
                    None => generate(
                        s.signal.unwrap_or_default().signal(s.f0),
                        n_alone,
                        self.fs,
                        &mut rng,
                    ),
                };
                let rms = s.rms_pa();
                unit.into_iter().map(|v| v * rms).collect()
            })
            .collect()
    }
}

impl SourceSpec {
    /// Source `i`'s moves, each to a place in the room, at stops in order after the first
    /// it plays at and no later than its last; none for a source on the robot.
    fn check_moves(&self, i: usize, room: &Space, n_stops: usize) -> Result<(), SimError> {
        if self.moves.is_empty() {
            return Ok(());
        }
        if self.on_robot {
            return Err(invalid(
                format!("sources[{i}].moves"),
                "a source on the robot moves with it; it has no moves of its own",
            ));
        }
        let [first, last] = self.stop_range(n_stops);
        let mut after = first;
        for (j, m) in self.moves.iter().enumerate() {
            let field = format!("sources[{i}].moves[{j}]");
            if !(m.from_stop > after && m.from_stop <= last) {
                return Err(invalid(
                    field,
                    format!(
                        "from_stop {} must lie after stop {after} and no later than the \
                         source's last stop, {last}",
                        m.from_stop
                    ),
                ));
            }
            if !room.contains(m.pos) {
                return Err(invalid(field, format!("{:?} is outside the room", m.pos)));
            }
            after = m.from_stop;
        }
        Ok(())
    }

    /// The source's RMS pressure (Pa) at its `level_db`: 94 dB SPL is 1 Pa RMS.
    fn rms_pa(&self) -> f64 {
        10f64.powf((self.level_db - 94.0) / 20.0)
    }
}
