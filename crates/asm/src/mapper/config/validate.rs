//! Checking the mapper's settings: each against its sign and its range, so that a
//! hand-written file is refused with the setting named, before it costs memory and time
//! or gives nonsense.

use super::*;

impl IasmConfig {
    /// Checks every parameter.
    ///
    /// # Errors
    /// The first [`ConfigError`] found.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.check_ranges()?;
        for (name, value) in [
            ("density_d", self.density_d),
            ("sigma_p_m", self.sigma_p_m),
            ("sigma_deg", self.sigma_deg),
            ("beta_m", self.beta_m),
            ("lambda_thresh_m2", self.lambda_thresh_m2),
            ("dbscan_eps_m", self.dbscan_eps_m),
            ("gamma_sigmas", self.gamma_sigmas),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ConfigError::NotPositive { name, value });
            }
        }
        for (name, value) in [
            ("merge_dist_m", self.merge_dist_m),
            ("absence_ratio", self.absence_ratio),
            ("min_range_m", self.min_range_m),
            ("beyond_map_m", self.beyond_map_m),
            ("wall_clearance_m", self.wall_clearance_m),
            ("room_margin_m", self.room_margin_m),
            ("share_gate_sigmas", self.share_gate_sigmas),
            ("trim_mads", self.trim_mads),
            ("trim_floor_deg", self.trim_floor_deg),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ConfigError::NotPositive { name, value });
            }
        }
        if let Some(value) = self.mirror_axis_deg.filter(|a| !a.is_finite()) {
            return Err(ConfigError::NotFinite {
                name: "mirror_axis_deg",
                value,
            });
        }
        for (name, value) in [
            ("min_pts_frac", self.min_pts_frac),
            ("resample_frac", self.resample_frac),
            ("rank_gain", self.rank_gain),
        ] {
            if !(value > 0.0 && value <= 1.0) {
                return Err(ConfigError::Fraction { name, value });
            }
        }
        for (name, v) in [
            ("passes", self.passes),
            ("max_rounds", self.max_rounds),
            ("num_doas", self.num_doas),
            ("min_observations", self.min_observations),
        ] {
            if v == 0 {
                return Err(ConfigError::Zero(name));
            }
        }
        Ok(())
    }
}

impl IasmConfig {
    /// The ranges beyond which a parameter means nothing for a robot in a room, and would
    /// only cost memory and time (a particle per hundredth of a cell, a million passes) or
    /// give nonsense (a random walk of 1e300 m).
    fn check_ranges(&self) -> Result<(), ConfigError> {
        // Each setting, the range it is held to, and that range in words: a table, one
        // setting a row.
        #[rustfmt::skip]
        let reals: [(&'static str, f64, f64, f64, &'static str); 16] = [
            ("density_d", self.density_d, 1.0, 1e6, "1 to 1e6 known cells per particle (a particle is drawn from a cell; fewer than one cell each leaves particles without a place)"),
            ("sigma_p_m", self.sigma_p_m, 1e-6, 1.0, "1e-6 to 1 m per step (a random walk of more than a metre never settles)"),
            ("sigma_deg", self.sigma_deg, 0.01, 90.0, "0.01 to 90 degrees"),
            ("beta_m", self.beta_m, 1e-3, 1e4, "0.001 to 10000 m"),
            ("lambda_thresh_m2", self.lambda_thresh_m2, 1e-9, 1e4, "1e-9 to 10000 m^2"),
            ("dbscan_eps_m", self.dbscan_eps_m, 1e-3, 100.0, "0.001 to 100 m"),
            ("gamma_sigmas", self.gamma_sigmas, 0.01, 100.0, "0.01 to 100 sigma"),
            ("merge_dist_m", self.merge_dist_m, 0.0, 1e4, "0 to 10000 m"),
            ("min_range_m", self.min_range_m, 0.0, 1e4, "0 to 10000 m"),
            ("beyond_map_m", self.beyond_map_m, 0.0, 1e4, "0 to 10000 m"),
            ("wall_clearance_m", self.wall_clearance_m, 0.0, 1e4, "0 to 10000 m"),
            ("room_margin_m", self.room_margin_m, 0.0, 100.0, "0 to 100 m"),
            ("absence_ratio", self.absence_ratio, 0.0, 1e4, "0 to 10000"),
            ("share_gate_sigmas", self.share_gate_sigmas, 0.0, 100.0, "0 to 100 sigma"),
            ("trim_mads", self.trim_mads, 0.0, 1e4, "0 to 10000"),
            ("trim_floor_deg", self.trim_floor_deg, 0.0, 180.0, "0 to 180 degrees"),
        ];
        #[rustfmt::skip]
        let counts: [(&'static str, usize, usize, usize, &'static str); 7] = [
            ("passes", self.passes, 1, 100, "1 to 100 passes over the stops (the paper makes two)"),
            ("max_rounds", self.max_rounds, 1, 10_000, "1 to 10000 rounds"),
            ("retries", self.retries, 0, 100, "0 to 100 failed rounds in a row"),
            ("num_doas", self.num_doas, 1, 64, "1 to 64 DoAs per stop (no array resolves more sources at once)"),
            ("min_observations", self.min_observations, 1, 100_000, "1 to 100000 stops"),
            ("vote_min_stops", self.vote_min_stops, 0, 100_000, "0 to 100000 stops"),
            ("vote_min_thresholded_stops", self.vote_min_thresholded_stops, 0, 100_000, "0 to 100000 stops"),
        ];
        let out = |name, value: String, range| ConfigError::OutOfRange { name, value, range };
        for (name, v, lo, hi, range) in reals {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(out(name, format!("{v:?}"), range));
            }
        }
        for (name, v, lo, hi, range) in counts {
            if !(lo..=hi).contains(&v) {
                return Err(out(name, v.to_string(), range));
            }
        }
        Ok(())
    }
}
