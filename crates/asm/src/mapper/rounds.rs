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
        Ok(self.run_stops(&self.stops(poses, doas_rad, cut)?, rng))
    }

    /// [`Mapper::run_rows`] with the map's own generator ([`crate::MapRng`]) seeded from
    /// `seed`, as every map of the `iasm` application is drawn.
    ///
    /// Why a method of its own: the generic methods are compiled in the crate that names
    /// the generator, with that crate's optimisation; this one compiles the particle filter
    /// here, so that an application built with less optimisation for its own code (the
    /// `iasm` package, to build faster) still runs the filter at full speed.
    ///
    /// # Errors
    /// As [`Mapper::run_rows`].
    pub fn run_seeded(
        &self,
        poses: &[Pose],
        doas_rad: &[Vec<f64>],
        cut: Option<&[bool]>,
        seed: u64,
    ) -> Result<MapResult> {
        use rand::SeedableRng;
        self.run_rows(
            poses,
            doas_rad,
            cut,
            &mut crate::MapRng::seed_from_u64(seed),
        )
    }

    /// [`Mapper::run`] on [`Stops`] already built: the search (the rounds, then the
    /// vote), the rules ([`Mapper::drop_implausible`]) and the reassociation
    /// ([`Mapper::reassociate`]), the mirrors marked and the refusals one per place. The map's
    /// [`MapResult::unexplained_bearings`] is the pool the search leaves.
    pub fn run_stops(&self, stops: &Stops, rng: &mut impl Rng) -> MapResult {
        let mut pool = stops.pool();
        let mut sources: Vec<Source> = Vec::new();
        let mut refused = Vec::new();
        let plan = Search {
            first_round: 1,
            retries: self.config.retries,
            new_stop: None,
        };
        let rounds = self.search(stops, &mut pool, &mut sources, &mut refused, plan, rng);
        let removed = self.settle(&mut sources, stops, &mut pool);
        let count = removed.len();
        refused.extend(removed);
        self.mark_mirrors(&mut sources);
        self.date(&mut sources, stops);
        let refused = self.one_per_place(refused, &sources);
        MapResult {
            sources,
            rounds,
            particles: self.m,
            unexplained: self.unexplained(stops.poses(), &pool),
            unexplained_bearings: pool,
            removed: count,
            refused,
        }
    }

    /// The search for new sources among the DoAs of `pool` that none explains, the one
    /// stage the batch map ([`Mapper::run_stops`]) and the online mapper's stops share:
    /// filtering rounds ([`Mapper::round`]) until `plan.retries + 1` fail in a row, then
    /// (with [`IasmConfig::vote_min_stops`]) the vote ([`Mapper::vote`]) until it proposes
    /// nothing, at most [`IasmConfig::max_rounds`] in all. What they find is added to
    /// `sources` (which the vote checks its proposals against), what the vote refuses to
    /// `refused`. Rounds are numbered from `plan.first_round`; returns how many ran.
    ///
    /// A round's clutter ([`Round::Clutter`]) was clutter where its cloud settled: its DoAs
    /// stay out of the rounds and go back for the vote, which is deterministic and has its
    /// own quorum. With `plan.new_stop`, a source must explain a DoA of that stop (whatever
    /// the earlier stops alone showed was searched at those stops); one that does not is a
    /// draw landing on old clutter, and its round failed.
    pub(crate) fn search(
        &self,
        stops: &Stops,
        pool: &mut [Vec<f64>],
        sources: &mut Vec<Source>,
        refused: &mut Vec<Refused>,
        plan: Search,
        rng: &mut impl Rng,
    ) -> usize {
        let c = &self.config;
        let mut rounds = 0;
        let mut failed = 0;
        let mut clutter: Vec<Ray> = Vec::new();
        while rounds < c.max_rounds {
            rounds += 1;
            match self.round(stops, pool, plan.first_round + rounds - 1, rng) {
                Round::Found(s)
                    if plan
                        .new_stop
                        .is_none_or(|k| s.rays.iter().any(|r| r.stop == k)) =>
                {
                    failed = 0;
                    sources.push(*s);
                }
                // One retry policy for every round that finds no source: each is one
                // random draw's bad luck until `retries + 1` happen in a row (see the
                // module documentation).
                failure => {
                    match failure {
                        Round::Found(s) => {
                            for r in s.rays {
                                r.give_back(pool);
                            }
                        }
                        Round::Clutter(rays) => clutter.extend(rays),
                        Round::NoCluster | Round::NothingExplained => {}
                    }
                    failed += 1;
                    if failed > plan.retries {
                        break;
                    }
                }
            }
        }
        if c.vote_min_stops > 0 {
            for r in &clutter {
                r.give_back(pool);
            }
            while rounds < c.max_rounds {
                let mapped: Vec<[f64; 2]> = sources.iter().map(|s| [s.x, s.y]).collect();
                let round = plan.first_round + rounds;
                let Some(s) = self.vote_noting(stops, pool, &mapped, round, refused) else {
                    break;
                };
                rounds += 1;
                sources.push(s);
            }
        }
        rounds
    }

    /// One round of the paper's loop: [filter](Mapper::filter) a fresh cloud over the
    /// DoAs of `pool` (one row per stop) that no source explains yet, take the
    /// [largest cluster](largest_cluster) as a source and
    /// [associate](crate::assoc::associate) it, removing the DoAs it explains from `pool`;
    /// then, in the robust profile, refine it and require
    /// [`IasmConfig::min_observations`] stops. `round` is the round's number, recorded in
    /// the source.
    ///
    /// # Panics
    /// If `pool` has not one row per stop.
    pub fn round(
        &self,
        stops: &Stops,
        pool: &mut [Vec<f64>],
        round: usize,
        rng: &mut impl Rng,
    ) -> Round {
        let poses = stops.poses();
        let (mut pf, resampled) = self.filter(stops, pool, rng);
        // DBSCAN counts particles, not weights: if the adaptive resampling never ran (few
        // stops), the cloud is still the uniform initial draw and all the evidence is in
        // its weights, so it is resampled once to turn them into density. Otherwise the
        // cloud is clustered as the paper does.
        let weighted_mean = pf.weighted_mean();
        if !resampled {
            pf.resample(rng);
        }
        let Some(cluster) = largest_cluster(&self.dbscan, pf.particles()) else {
            return Round::NoCluster;
        };
        let est = match self.config.variant {
            Variant::Ws => weighted_mean,
            Variant::Ca | Variant::Wdp => mean(&cluster),
        };
        let mut rays = self.associate(est, poses, pool);
        if rays.is_empty() {
            return Round::NothingExplained;
        }
        let mut est = est;
        let mut refined = false;
        if self.config.refine
            && let Some(p) = refit(est, &mut rays, self.sigma, self.trim, pool)
        {
            (est, refined) = (p, true);
        }
        if rays.len() < self.config.min_observations {
            return Round::Clutter(rays);
        }
        Round::Found(Box::new(Source {
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
            blends: Vec::new(),
            images: Vec::new(),
            history: History::default(),
        }))
    }

    /// The filtering step: `M` particles drawn from the map's known cells, then the stops
    /// visited `passes` times, each time predicting (random walk), weighting with the
    /// stop's remaining DoAs (its row of `pool`), resampling when `N_eff < ceil(M / C)`,
    /// and stopping early once the cloud's largest covariance eigenvalue is below
    /// `lambda_thresh`. Returns the cloud and whether it was ever resampled. The DoAs as
    /// the SSL gave them ([`Stops::heard`], strongest first) rank the remaining ones for
    /// [`IasmConfig::rank_gain`].
    ///
    /// # Panics
    /// If `pool` has not one row per stop.
    pub fn filter(
        &self,
        stops: &Stops,
        pool: &[Vec<f64>],
        rng: &mut impl Rng,
    ) -> (ParticleFilter, bool) {
        assert_eq!(stops.len(), pool.len(), "one row of the pool per stop");
        let (c, poses) = (&self.config, stops.poses());
        let k_stops = poses.len();
        let gains = (c.rank_gain < 1.0).then(|| self.rank_gains(pool, stops.heard()));
        let mut pf = ParticleFilter::from_cells(&self.cells, self.m, rng);
        let mut resampled = false;
        for step in 0..c.passes * k_stops {
            let k = step % k_stops;
            pf.predict(c.sigma_p_m, rng);
            let neff = match &gains {
                Some(g) => pf.update_gained(poses[k].position(), &pool[k], &g[k], &self.lik),
                None => pf.update(poses[k].position(), &pool[k], &self.lik),
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
    fn rank_gains(&self, bearings: &[Vec<f64>], heard: &[Vec<f64>]) -> Vec<Vec<f64>> {
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

/// How a search ([`Mapper::search`]) runs: the batch map's from round 1 with the
/// configured retries; an online stop's from the rounds run so far, no retry (the next full
/// map retries), its sources required to explain a DoA of the new stop.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Search {
    /// The number of the search's first round.
    pub first_round: usize,
    /// Failed rounds in a row that end the rounds, less one.
    pub retries: usize,
    /// The stop whose DoAs a new source must explain.
    pub new_stop: Option<usize>,
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
