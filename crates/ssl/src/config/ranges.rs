//! The ranges beyond which a setting means nothing for an array and a room, and would only
//! cost memory and time (a grid of a billion directions, a hop of one sample) or give
//! nonsense (a speed of sound of 1e-300 m/s): checked when the settings are read.

use super::SslConfig;
use crate::error::ConfigError;

/// Real-valued settings: (name, value, lowest, highest, what is accepted and why).
type Real = (&'static str, f64, f64, f64, &'static str);
/// Counts: (name, value, lowest, highest, what is accepted and why).
type Count = (&'static str, usize, usize, usize, &'static str);

fn out_of_range(name: &'static str, value: String, range: &'static str) -> ConfigError {
    ConfigError::OutOfRange { name, value, range }
}

impl SslConfig {
    /// Every numeric setting against its range ([`ConfigError::OutOfRange`] for the first
    /// outside it): the real-valued ones, the counts, the band, the grid.
    pub(crate) fn check_ranges(&self) -> Result<(), ConfigError> {
        for (name, v, lo, hi, range) in self.reals() {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                // `{:?}` writes 5e-324 as such, not as 324 digits.
                return Err(out_of_range(name, format!("{v:?}"), range));
            }
        }
        for (name, v, lo, hi, range) in self.counts() {
            if !(lo..=hi).contains(&v) {
                return Err(out_of_range(name, v.to_string(), range));
            }
        }
        if self.fmin_hz >= self.fmax_hz {
            return Err(out_of_range(
                "fmin_hz",
                format!("{:?}", self.fmin_hz),
                "below fmax_hz (the band from fmin_hz to fmax_hz must not be empty)",
            ));
        }
        self.check_grid()
    }

    /// The real-valued settings with their ranges.
    fn reals(&self) -> Vec<Real> {
        let mut reals: Vec<Real> = vec![
            (
                "az_step_deg",
                self.az_step_deg,
                0.1,
                90.0,
                "0.1 to 90 degrees (no array on a robot resolves directions finer than a tenth of a degree)",
            ),
            (
                "fmin_hz",
                self.fmin_hz,
                0.0,
                500_000.0,
                "0 to 500000 Hz, below fmax_hz",
            ),
            (
                "fmax_hz",
                self.fmax_hz,
                0.0,
                500_000.0,
                "0 to 500000 Hz, above fmin_hz (and at most half the sample rate)",
            ),
            (
                "speed_of_sound",
                self.speed_of_sound,
                100.0,
                2000.0,
                "100 to 2000 m/s (air is 330-360 m/s; water about 1480)",
            ),
            (
                "decay_window_s",
                self.decay_window_s,
                1e-3,
                60.0,
                "0.001 to 60 s",
            ),
            (
                "mvdr_loading",
                self.mvdr_loading,
                1e-12,
                1e6,
                "1e-12 to 1e6",
            ),
            ("sidelobe_ratio", self.sidelobe_ratio, 0.0, 1e6, "0 to 1e6"),
            (
                "min_significance",
                self.min_significance,
                0.0,
                1e6,
                "0 to 1e6",
            ),
            (
                "decay_gate_db",
                self.decay_gate_db,
                0.0,
                200.0,
                "0 to 200 dB",
            ),
        ];
        if let Some(e) = self.elevation {
            reals.push(("elevation.step_deg", e.step_deg, 0.1, 180.0, "0.1 to 180 degrees (no array on a robot resolves directions finer than a tenth of a degree)"));
        }
        reals
    }

    /// The counts (frames, peaks, bins) with their ranges.
    fn counts(&self) -> Vec<Count> {
        let mut counts: Vec<Count> = vec![
            (
                "num_peaks",
                self.num_peaks,
                1,
                64,
                "1 to 64 DoAs per recording (no array resolves more sources at once)",
            ),
            (
                "dominance_blocks",
                self.dominance_blocks,
                0,
                100_000,
                "0 to 100000 blocks",
            ),
            (
                "subband_votes",
                self.subband_votes,
                0,
                100_000,
                "0 to 100000 blocks",
            ),
            (
                "mvdr_freq_smoothing",
                self.mvdr_freq_smoothing,
                0,
                4096,
                "0 to 4096 bins",
            ),
            (
                "music_freq_smoothing",
                self.music_freq_smoothing.unwrap_or(0),
                0,
                4096,
                "0 to 4096 bins",
            ),
        ];
        if let Some(frame) = self.frame_len {
            counts.push(("frame_len", frame, 16, 1 << 16, "16 to 65536 samples (above, a frame spans seconds at any audio rate: talkers and the robot move within it)"));
        }
        if let Some(hop) = self.hop {
            counts.push(("hop", hop, 16, 1 << 16, "16 to 65536 samples, at most the frame (a smaller hop repeats what the frames already hold, at the cost of time)"));
        }
        if let Some(k) = self.music_sources {
            counts.push((
                "music_sources",
                k,
                1,
                64,
                "1 to 64 (at most the DoAs an array resolves)",
            ));
        }
        counts
    }

    /// The grid's size: each direction costs a column of every block's spectrum.
    fn check_grid(&self) -> Result<(), ConfigError> {
        let azimuths = (360.0 / self.az_step_deg).ceil();
        let elevations = self.elevation.map_or(1.0, |e| {
            ((e.max_deg - e.min_deg).max(0.0) / e.step_deg).floor() + 1.0
        });
        if azimuths * elevations > 200_000.0 {
            return Err(out_of_range(
                "az_step_deg",
                format!("{:?}", self.az_step_deg),
                "a grid of at most 200000 directions with the elevation steps (360 azimuths x 13 elevations is 4680; finer than a degree in both resolves nothing more)",
            ));
        }
        Ok(())
    }
}
