//! The paper's steps: filtering rounds over every stop (particle filter, DBSCAN, the
//! largest cluster as a source, implicit association), repeated until rounds find nothing;
//! the DoAs turned into world bearings, and the rank of each stop's DoAs in the likelihood.

use super::*;

impl Mapper {
    /// Maps the sources heard from `poses`, given each stop's DoAs (array-frame azimuths,
    /// rad, strongest first, at most `N`), with randomness from `rng`: filtering rounds
    /// ([`Mapper::round`]) until `retries + 1` fail in a row or `max_rounds` have run, then
    /// close estimates merged and, with [`IasmConfig::refine`], refined.
    ///
    /// # Errors
    /// [`Error`] if the tables differ in length, a pose is not finite, or a row holds more
    /// than `N` DoAs.
    pub fn run(
        &self,
        poses: &[Pose],
        doas_rad: &[Vec<f64>],
        rng: &mut impl Rng,
    ) -> Result<MapResult> {
        self.run_rows(poses, doas_rad, None, rng)
    }

    /// [`Mapper::run`], told which rows the SSL cut at `N`: `cut[k]` when a further peak
    /// than the row's `N` passed the SSL's thresholds at stop `k` (the `ssl` crate's
    /// `Located::cut`). A row that was not cut holds everything the SSL heard standing
    /// out, however many DoAs it has, and counts towards the vote's smaller quorum
    /// ([`IasmConfig::vote_min_thresholded_stops`]). Without it (`None`: a DoA table,
    /// whose rows do not say) a row of `N` DoAs is taken as cut.
    ///
    /// # Errors
    /// As [`Mapper::run`], and [`Error::CutMismatch`] if `cut` has not one flag per pose.
    pub fn run_rows(
        &self,
        poses: &[Pose],
        doas_rad: &[Vec<f64>],
        cut: Option<&[bool]>,
        rng: &mut impl Rng,
    ) -> Result<MapResult> {
        if let Some(cut) = cut
            && cut.len() != poses.len()
        {
            return Err(Error::CutMismatch {
                poses: poses.len(),
                cut: cut.len(),
            });
        }
        let mut bearings = self.world_bearings_cut(poses, doas_rad, cut)?;
        let complete: Vec<bool> = doas_rad
            .iter()
            .enumerate()
            .map(|(k, row)| {
                let heard = row.iter().filter(|a| a.is_finite()).count();
                self.complete(heard, cut.map(|c| c[k]))
            })
            .collect();
        let said_cut = cut.map_or_else(|| vec![false; poses.len()], <[bool]>::to_vec);
        Ok(self.run_bearings_complete(poses, &mut bearings, &complete, &said_cut, rng))
    }

    /// [`Mapper::run`] on checked world bearings ([`Mapper::world_bearings`]), which are
    /// left holding the DoAs no source explains.
    ///
    /// # Panics
    /// If `poses` and `bearings` differ in length.
    pub fn run_bearings(
        &self,
        poses: &[Pose],
        bearings: &mut [Vec<f64>],
        rng: &mut impl Rng,
    ) -> MapResult {
        let complete: Vec<bool> = poses
            .iter()
            .zip(bearings.iter())
            .map(|(p, row)| self.complete(self.doas_in(p, row), None))
            .collect();
        self.run_bearings_complete(poses, bearings, &complete, &vec![false; poses.len()], rng)
    }

    /// Which of `rows` (each stop's DoAs) hold every peak the SSL let through, when
    /// nothing else says: those with fewer than `N` DoAs (a full row may have been cut at
    /// `N`; see [`Mapper::run_rows`]).
    pub fn complete_by_length(&self, rows: &[Vec<f64>]) -> Vec<bool> {
        rows.iter().map(|r| self.complete(r.len(), None)).collect()
    }

    /// Whether a row of `len` DoAs holds every peak the SSL let through: not cut at `N`
    /// when the SSL says (`cut`), else shorter than `N`. The one rule behind
    /// [`Mapper::run_rows`], [`Mapper::complete_by_length`] and the online mapper.
    pub(crate) fn complete(&self, len: usize, cut: Option<bool>) -> bool {
        cut.map_or(len < self.config.num_doas, |cut| !cut)
    }

    /// [`Mapper::run_rows`] on checked world bearings, with the rows that hold every peak
    /// the SSL let through marked in `complete`, and those the SSL said it cut at `N` in
    /// `said_cut`.
    pub(crate) fn run_bearings_complete(
        &self,
        poses: &[Pose],
        bearings: &mut [Vec<f64>],
        complete: &[bool],
        said_cut: &[bool],
        rng: &mut impl Rng,
    ) -> MapResult {
        let c = &self.config;
        let heard = bearings.to_vec();
        let mut sources: Vec<Source> = Vec::new();
        let mut rounds = 0;
        let mut failed = 0;
        let mut clutter: Vec<Ray> = Vec::new();
        while rounds < c.max_rounds {
            rounds += 1;
            match self.round(poses, bearings, &heard, rounds, rng) {
                Round::Found(s) => {
                    failed = 0;
                    sources.push(s);
                }
                // One retry policy for every round that finds no source: each is one
                // random draw's bad luck until `retries + 1` happen in a row (see the
                // module documentation). A clutter round has at least taken its DoAs out
                // of the rounds; they are kept for the vote.
                failure => {
                    if let Round::Clutter(rays) = failure {
                        clutter.extend(rays);
                    }
                    failed += 1;
                    if failed > c.retries {
                        break;
                    }
                }
            }
        }
        let mut refused = Vec::new();
        if c.vote_min_stops > 0 {
            // The rounds' clutter was clutter where their clouds settled; the vote,
            // deterministic and with its own quorum, judges those DoAs anew (see
            // `IasmConfig::vote_min_stops`).
            for r in &clutter {
                r.give_back(bearings);
            }
            while rounds < c.max_rounds {
                let mapped: Vec<[f64; 2]> = sources.iter().map(|s| [s.x, s.y]).collect();
                let Some(s) = self.vote_noting(
                    poses,
                    bearings,
                    &heard,
                    complete,
                    &mapped,
                    rounds + 1,
                    &mut refused,
                ) else {
                    break;
                };
                rounds += 1;
                sources.push(s);
            }
        }
        let removed = self.settle(&mut sources, poses, &heard, complete, said_cut, bearings);
        let count = removed.len();
        refused.extend(removed);
        self.mark_mirrors(&mut sources);
        let refused = self.one_per_place(refused, &sources);
        MapResult {
            sources,
            rounds,
            particles: self.m,
            unexplained: self.unexplained(poses, bearings),
            unexplained_bearings: bearings.to_vec(),
            removed: count,
            refused,
        }
    }

    /// Checks the inputs and turns every DoA into a world bearing, `wrap(azimuth + theta)`,
    /// dropping non-finite DoAs (missing cells of a table).
    ///
    /// # Errors
    /// As [`Mapper::run`].
    pub fn world_bearings(&self, poses: &[Pose], doas_rad: &[Vec<f64>]) -> Result<Vec<Vec<f64>>> {
        self.world_bearings_cut(poses, doas_rad, None)
    }

    /// Whether a row of `len` DoAs is one the mapper takes: at most `N`, or, in a row the
    /// SSL says it cut at `N` (`cut`), `N` more beyond them (the extra DoAs its octaves
    /// heard: `ssl::Located::extra`).
    pub(crate) fn row_fits(&self, len: usize, cut: Option<bool>) -> bool {
        let n = self.config.num_doas;
        len <= n || (cut == Some(true) && len <= 2 * n)
    }

    /// [`Mapper::world_bearings`], with each row's cut flag when the SSL gives them
    /// ([`Mapper::row_fits`]).
    pub(super) fn world_bearings_cut(
        &self,
        poses: &[Pose],
        doas_rad: &[Vec<f64>],
        cut: Option<&[bool]>,
    ) -> Result<Vec<Vec<f64>>> {
        if poses.is_empty() {
            return Err(Error::NoPoses);
        }
        if poses.len() != doas_rad.len() {
            return Err(Error::LengthMismatch {
                poses: poses.len(),
                doas: doas_rad.len(),
            });
        }
        if let Some(index) = poses.iter().position(|p| !p.is_finite()) {
            return Err(Error::NonFinitePose { index });
        }
        let fits = |k: usize| self.row_fits(doas_rad[k].len(), cut.map(|c| c[k]));
        if let Some(index) = (0..doas_rad.len()).find(|&k| !fits(k)) {
            return Err(Error::TooManyDoas {
                index,
                got: doas_rad[index].len(),
                n: self.config.num_doas,
            });
        }
        Ok(doas_rad
            .iter()
            .zip(poses)
            .map(|(row, p)| self.stop_bearings(p, row))
            .collect())
    }

    /// One round of the paper's loop: [filter](Mapper::filter) a fresh cloud over the
    /// remaining `bearings`, take the [largest cluster](largest_cluster) as a source and
    /// [associate](crate::assoc::associate) it, removing the DoAs it explains; then, in the
    /// robust profile, refine it and require [`IasmConfig::min_observations`] stops.
    /// `heard` holds each stop's DoAs as the SSL gave them, which rank the remaining ones
    /// ([`Mapper::filter`]); `round` is the round's number, recorded in the source.
    ///
    /// # Panics
    /// If `poses`, `bearings` and `heard` differ in length (use
    /// [`Mapper::world_bearings`]).
    pub fn round(
        &self,
        poses: &[Pose],
        bearings: &mut [Vec<f64>],
        heard: &[Vec<f64>],
        round: usize,
        rng: &mut impl Rng,
    ) -> Round {
        let (mut pf, resampled) = self.filter(poses, bearings, heard, rng);
        // DBSCAN counts particles, not weights: if the adaptive resampling never ran (few
        // stops), the cloud is still the uniform initial draw and all the evidence is in
        // its weights, so it is resampled once to turn them into density. Otherwise the
        // cloud is clustered as the paper does.
        let weighted_mean = pf.weighted_mean();
        if !resampled {
            pf.resample(rng);
        }
        let mut fallback = false;
        let cluster = match largest_cluster(&self.dbscan, pf.particles()) {
            Some(c) => c,
            // A diffuse cloud (broad DoAs: a small array, many sources) has no cluster of
            // MinPts within eps, yet its densest part may be a source: take it, and let
            // the association, the refinement and the stop count judge it.
            None if self.config.densest_fallback => {
                match densest_cell(pf.particles(), 2.0 * self.config.dbscan_eps_m) {
                    Some(c) => {
                        fallback = true;
                        c
                    }
                    None => return Round::NoCluster,
                }
            }
            None => return Round::NoCluster,
        };
        let est = match self.config.variant {
            Variant::Ws => weighted_mean,
            Variant::Ca | Variant::Wdp => mean(&cluster),
        };
        let mut rays = self.associate(est, poses, bearings);
        if rays.is_empty() {
            return Round::NothingExplained;
        }
        let mut est = est;
        let mut refined = false;
        if self.config.refine
            && let Some(p) = refit(est, &mut rays, self.sigma, self.trim, bearings)
        {
            (est, refined) = (p, true);
        }
        let needed = if fallback {
            FALLBACK_OBSERVATIONS.max(self.config.min_observations)
        } else {
            self.config.min_observations
        };
        if rays.len() < needed {
            return Round::Clutter(rays);
        }
        Round::Found(Source {
            x: est[0],
            y: est[1],
            observations: rays.len(),
            particles: cluster.len(),
            covariance: covariance(&cluster),
            round,
            cluster,
            rays,
            refined,
            mirror: None,
        })
    }

    /// The filtering step: `M` particles drawn from the map's known cells, then the stops
    /// visited `passes` times, each time predicting (random walk), weighting with the
    /// stop's remaining bearings, resampling when `N_eff < ceil(M / C)`, and stopping early
    /// once the cloud's largest covariance eigenvalue is below `lambda_thresh`. Returns the
    /// cloud and whether it was ever resampled. `heard` holds each stop's DoAs as the SSL
    /// gave them (world bearings, strongest first: `Mapper::stop_bearings`), which
    /// ranks the remaining ones for [`IasmConfig::rank_gain`].
    ///
    /// # Panics
    /// If `poses`, `bearings` and `heard` differ in length.
    pub fn filter(
        &self,
        poses: &[Pose],
        bearings: &[Vec<f64>],
        heard: &[Vec<f64>],
        rng: &mut impl Rng,
    ) -> (ParticleFilter, bool) {
        assert_eq!(poses.len(), bearings.len(), "one row of bearings per pose");
        let c = &self.config;
        let k_stops = poses.len();
        let gains = (c.rank_gain < 1.0).then(|| self.rank_gains(bearings, heard));
        let mut pf = ParticleFilter::from_cells(&self.cells, self.m, rng);
        let mut resampled = false;
        for step in 0..c.passes * k_stops {
            let k = step % k_stops;
            pf.predict(c.sigma_p_m, rng);
            let neff = match &gains {
                Some(g) => pf.update_gained(poses[k].position(), &bearings[k], &g[k], &self.lik),
                None => pf.update(poses[k].position(), &bearings[k], &self.lik),
            };
            if neff < self.resample_below {
                pf.resample(rng);
                resampled = true;
            }
            if pf.max_cov_eigenvalue() < c.lambda_thresh_m2 {
                break;
            }
        }
        (pf, resampled)
    }

    /// Each remaining DoA's gain in the particles' likelihood, `rank_gain^r`, where `r`
    /// is its rank among its stop's remaining DoAs in the order `heard` gives them
    /// (strongest first; a linear array's mirror pair counts as one DoA). A DoA not in
    /// `heard` ranks last.
    ///
    /// # Panics
    /// If `bearings` and `heard` differ in length.
    pub(crate) fn rank_gains(&self, bearings: &[Vec<f64>], heard: &[Vec<f64>]) -> Vec<Vec<f64>> {
        assert_eq!(
            bearings.len(),
            heard.len(),
            "one row heard per row of bearings"
        );
        let per = if self.mirror.is_some() { 2 } else { 1 };
        bearings
            .iter()
            .zip(heard)
            .map(|(row, said)| {
                let order: Vec<usize> = row
                    .iter()
                    .map(|b| said.iter().position(|h| h == b).unwrap_or(said.len()))
                    .collect();
                order
                    .iter()
                    .map(|&o| {
                        let ahead = order.iter().filter(|&&p| p < o).count() / per;
                        self.config.rank_gain.powi(ahead as i32)
                    })
                    .collect()
            })
            .collect()
    }
}

/// Stops a source found by the densest-cell fallback must explain.
pub(super) const FALLBACK_OBSERVATIONS: usize = 5;

/// The particles in the square of side `side` (m) that holds the most of them, and in
/// its eight neighbours; `None` for no particles.
pub fn densest_cell(particles: &[[f64; 2]], side: f64) -> Option<Vec<[f64; 2]>> {
    let key = |p: &[f64; 2]| ((p[0] / side).floor() as i64, (p[1] / side).floor() as i64);
    let mut counts: std::collections::HashMap<(i64, i64), usize> = Default::default();
    for p in particles {
        *counts.entry(key(p)).or_default() += 1;
    }
    // The most particles; among equals, the smallest cell (a deterministic choice).
    let (&(i, j), _) = counts
        .iter()
        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))?;
    Some(
        particles
            .iter()
            .filter(|p| {
                let (a, b) = key(p);
                (a - i).abs() <= 1 && (b - j).abs() <= 1
            })
            .copied()
            .collect(),
    )
}

/// The particles of the largest DBSCAN cluster of `particles` (the first found among equals),
/// or `None` when every particle is noise.
pub fn largest_cluster(dbscan: &Dbscan, particles: &[[f64; 2]]) -> Option<Vec<[f64; 2]>> {
    let labels = dbscan.cluster(particles);
    let mut sizes: Vec<usize> = Vec::new();
    for l in &labels {
        if let Label::Cluster(k) = *l {
            let k = k as usize;
            if sizes.len() <= k {
                sizes.resize(k + 1, 0);
            }
            sizes[k] += 1;
        }
    }
    let (largest, _) = sizes
        .iter()
        .enumerate()
        .max_by_key(|&(i, &s)| (s, std::cmp::Reverse(i)))?;
    Some(
        particles
            .iter()
            .zip(&labels)
            .filter(|(_, l)| **l == Label::Cluster(largest as u32))
            .map(|(p, _)| *p)
            .collect(),
    )
}
