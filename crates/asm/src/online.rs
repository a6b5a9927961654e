//! Mapping while the robot drives: [`OnlineMapper`] takes one stop (pose + DoAs) at a time
//! and answers the current map after each.
//!
//! The authors' online program re-runs the whole mapper over every stop so far at each new
//! one: stop `k` costs a full map of `k` stops, and a run of `K` stops the sum of `K`
//! growing maps (about `K / 2` full maps). This one keeps what earlier stops established
//! and works on what the new stop adds, with a full map now and then to correct itself:
//!
//! - **Sources, their particles and their associations are kept.** A new stop's DoAs are
//!   offered to the known sources with the batch mapper's rule ([`crate::assoc`]: the
//!   nearest DoA within `gamma` of the source's bearing, one per stop), best supported
//!   source first; every earlier DoA is re-associated the same way (one angle comparison
//!   per source, stop and DoA; no particle touched), so that a source found early from few
//!   stops gives up DoAs a better supported one explains. A source that takes a DoA of the
//!   new stop steps its own particle cloud with it (weight, resample, random walk: a few
//!   hundred particles, not the map's thousands); in the CA variant the source is its
//!   cloud's mean, with [`IasmConfig::refine`] the least-squares fit of its rays.
//! - **Only the new stop's unexplained DoAs are searched.** Filtering rounds
//!   ([`Mapper::round`], the batch mapper's own) over the pool of unexplained DoAs run
//!   until one fails, and a source they find must explain a DoA of the new stop (whatever
//!   the earlier stops alone showed was searched at those stops). A stop whose DoAs all
//!   went to known sources runs no round. After the rounds, the batch mapper's vote
//!   ([`Mapper::vote`]) runs over the pool, as it does after the batch rounds: in a sparse
//!   scene the rounds' clouds split between sources seen by few DoAs, and without it the
//!   live map held half the sources between full maps (`sparse_ten`, GCC-PHAT, 3 seeds:
//!   the last live map 5 sources at 0.55-0.59 m -> 9 at 0.18-0.24 m; the ReSpeaker rows
//!   0.216 -> 0.126 m; arrangement II and the one- and two-talker scenes unchanged).
//! - **A full map at stops 4, 8, 16, 32, ...** (doubling) replaces the incremental one:
//!   the batch mapper over every stop so far, seeded with the mapper's seed. Incremental
//!   updates are greedy, and a clutter constellation that one stop's search took for a
//!   source would otherwise stay; the full maps remove it. Their cost over a run is at most
//!   twice one full map of all the stops, so the total stays linear in `K` where the
//!   recompute's is quadratic. [`OnlineMapper::consolidate`] runs one on demand (at the
//!   last stop of a run, it gives exactly the batch map of the same seed).
//! - **The full map runs beside the robot, not in its stop.** It is the one step whose cost
//!   grows with the run (arrangement II's at 32 stops takes 80-180 ms on one core, where a
//!   stop's own update takes 7), so a stop that would run it answers with its incremental
//!   update and starts the full map over every stop so far on a thread of its own; the next
//!   stop takes it in before its own update, from the state the full map would have left at
//!   the stop that started it (the draws and the round count as they were). So every map
//!   from that next stop on is the one the full map in the stop would have given, to the
//!   bit, whether the thread finished early, late or could not be started (the full map
//!   then runs where it is taken in); only the starting stop's own map is its incremental
//!   one. A robot records for seconds at a stop, so the full map is done before the next
//!   stop arrives, and a stop's latency is its incremental update.
//!
//! [`IasmConfig::refine`]: crate::IasmConfig::refine

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use rand::SeedableRng;

use crate::error::Result;
use crate::mapper::{MapResult, Mapper, Search, Source, Stops, Variant, refit};
use crate::pf::{ParticleFilter, covariance, mean};
use crate::{MapRng, Pose};

/// What one stop changed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StopUpdate {
    /// The stop's index (from 0).
    pub stop: usize,
    /// The stop's DoAs taken by sources already on the map.
    pub associated: usize,
    /// Sources found by this stop's search.
    pub found: usize,
    /// Filtering rounds the stop ran (0 when every DoA went to a known source).
    pub rounds: usize,
    /// Sources on the map after the stop.
    pub sources: usize,
    /// Whether the stop started a full map over every stop so far (see the module docs:
    /// it runs beside the next stops and the next stop takes it in).
    pub full: bool,
    /// Where the stop took in the full map the stop before it started: how long that map
    /// took on its own thread (ms; its rounds are counted in [`StopUpdate::rounds`]).
    /// `None` at every other stop.
    pub full_ms: Option<f64>,
}

/// The incremental I-ASM mapper (see the module docs): feed it stops with
/// [`OnlineMapper::add_stop`], read the map with [`OnlineMapper::map`].
#[derive(Debug)]
pub struct OnlineMapper {
    mapper: Arc<Mapper>,
    seed: u64,
    /// Every stop so far.
    stops: Stops,
    /// Every stop's unexplained DoAs.
    pool: Vec<Vec<f64>>,
    sources: Vec<Source>,
    rounds: usize,
    /// Sources removed by [`Mapper::drop_implausible`] in the last full map and since.
    removed: usize,
    /// What was found and refused, and why, in the last full map and since, one per place
    /// against the sources as each stop left them (see [`MapResult::refused`]).
    refused: Vec<crate::Refused>,
    /// Stops at which the next full map runs.
    next_full: usize,
    /// The stop count of the last full map (0: none yet).
    last_full: usize,
    rng: MapRng,
    /// The full map running beside the stops, if one does.
    pending: Option<Pending>,
    /// Whether full maps run on a thread of their own (the tests run them in place too).
    threaded: bool,
}

/// A full map started at a stop and not yet taken in (see the module docs).
#[derive(Debug)]
struct Pending {
    /// The stops it maps: the first `stops`.
    stops: usize,
    /// The draws and the round count as the full map would have left them in the stop
    /// that started it.
    rng: MapRng,
    rounds: usize,
    work: Work,
}

/// A full map's result with the time it took (ms), or the thread computing it.
#[derive(Debug)]
enum Work {
    Running(JoinHandle<(MapResult, f64)>),
    Done(MapResult, f64),
}

impl Work {
    /// The full map of `stops`, on a thread of its own where one can be started, here
    /// otherwise.
    fn start(mapper: &Arc<Mapper>, stops: &Stops, seed: u64, threaded: bool) -> Self {
        // The job is kept to run here if no thread can be started: what it holds is shared,
        // not copied twice.
        let job = {
            let (mapper, stops) = (Arc::clone(mapper), Arc::new(stops.clone()));
            move || {
                let t0 = Instant::now();
                let r = mapper.run_stops(&stops, &mut MapRng::seed_from_u64(seed));
                (r, 1e3 * t0.elapsed().as_secs_f64())
            }
        };
        let thread = threaded.then(|| {
            std::thread::Builder::new()
                .name("iasm-full-map".into())
                .spawn(job.clone())
        });
        match thread {
            Some(Ok(h)) => Work::Running(h),
            _ => {
                let (r, ms) = job();
                Work::Done(r, ms)
            }
        }
    }

    /// Waits for the thread, if it still runs.
    fn finish(self) -> (MapResult, f64) {
        match self {
            Work::Done(r, ms) => (r, ms),
            Work::Running(h) => match h.join() {
                Ok(done) => done,
                Err(panic) => std::panic::resume_unwind(panic),
            },
        }
    }
}

/// The first full map runs at this many stops; then at twice as many each time.
const FIRST_FULL: usize = 4;

impl OnlineMapper {
    /// An empty map; `seed` seeds every random draw (the same stops and seed give the same
    /// maps).
    pub fn new(mapper: Mapper, seed: u64) -> Self {
        Self {
            mapper: Arc::new(mapper),
            seed,
            stops: Stops::default(),
            pool: Vec::new(),
            sources: Vec::new(),
            rounds: 0,
            removed: 0,
            refused: Vec::new(),
            next_full: FIRST_FULL,
            last_full: 0,
            rng: MapRng::seed_from_u64(seed ^ 0x0e11_0e11),
            pending: None,
            threaded: true,
        }
    }

    /// Stops taken so far.
    pub fn stops(&self) -> usize {
        self.stops.len()
    }

    /// The mapper's parameters and particle budget.
    pub fn mapper(&self) -> &Mapper {
        &self.mapper
    }

    /// Adds one stop: the robot's pose and its DoAs (array-frame azimuths, rad, strongest
    /// first, at most `N`; non-finite ones are skipped as empty cells).
    ///
    /// # Errors
    /// [`Error::NonFinitePose`](crate::Error::NonFinitePose),
    /// [`Error::StopOutsideMap`](crate::Error::StopOutsideMap) or
    /// [`Error::TooManyDoas`](crate::Error::TooManyDoas), naming the stop; the map is
    /// unchanged.
    pub fn add_stop(&mut self, pose: Pose, doas_rad: &[f64]) -> Result<StopUpdate> {
        self.add_row(pose, doas_rad, None)
    }

    /// [`OnlineMapper::add_stop`], told whether the SSL cut the row at `N` (`cut`: a
    /// further peak passed its thresholds; `None` when it is not known, as for a table,
    /// and a full row is then taken as cut: see [`Mapper::run_rows`]).
    ///
    /// # Errors
    /// As [`OnlineMapper::add_stop`].
    pub fn add_row(
        &mut self,
        pose: Pose,
        doas_rad: &[f64],
        cut: Option<bool>,
    ) -> Result<StopUpdate> {
        let stop = self.stops.len();
        push_checked(&self.mapper, &mut self.stops, pose, doas_rad, cut)?;
        let mut update = StopUpdate {
            stop,
            ..StopUpdate::default()
        };
        if let Some(p) = self.pending.take() {
            let (rounds, ms) = self.adopt(p);
            (update.rounds, update.full_ms) = (rounds, Some(ms));
            // As the stop that started it would have ended.
            self.refused = self
                .mapper
                .one_per_place(std::mem::take(&mut self.refused), &self.sources);
        }
        self.pool.push(self.stops.heard()[stop].clone());

        let (associated, returned) = self.reassociate();
        update.associated = associated;
        let full_due = self.stops.len() >= self.next_full;
        // What the full map in this stop would have left (see `Pending`).
        let before = (self.rng.clone(), self.rounds);
        if !self.pool[stop].is_empty() || returned {
            self.search(&mut update);
        }
        // As the batch mapper ends its search.
        let removed = self
            .mapper
            .settle(&mut self.sources, &self.stops, &mut self.pool);
        self.removed += removed.len();
        self.refused.extend(removed);
        if full_due {
            while self.next_full <= self.stops.len() {
                self.next_full *= 2;
            }
            self.pending = Some(Pending {
                stops: self.stops.len(),
                rng: before.0,
                rounds: before.1,
                work: Work::start(&self.mapper, &self.stops, self.seed, self.threaded),
            });
            update.full = true;
        }
        // One refusal per place, as the map reports them: the vote tries its refused
        // proposals again at every stop.
        self.refused = self
            .mapper
            .one_per_place(std::mem::take(&mut self.refused), &self.sources);
        update.sources = self.sources.len();
        Ok(update)
    }

    /// Adds stops made before the mapper was (a merging node that joins late, a map
    /// rebuilt over a new region), each `(pose, DoAs, cut)` as [`OnlineMapper::add_row`]
    /// takes it, and maps them with one full map over every stop so far
    /// ([`OnlineMapper::consolidate`]): the map stop-by-stop updates end with after their
    /// last stop, at the cost of one batch map instead of an update per stop and a full
    /// map at each doubling. The next full map is due at the next power of two above the
    /// stops. Returns the rounds it ran.
    ///
    /// # Errors
    /// As [`OnlineMapper::add_row`], naming the first bad stop; the map is then unchanged.
    pub fn add_history<'a>(
        &mut self,
        rows: impl IntoIterator<Item = (Pose, &'a [f64], Option<bool>)>,
    ) -> Result<usize> {
        let mut stops = self.stops.clone();
        for (pose, doas_rad, cut) in rows {
            push_checked(&self.mapper, &mut stops, pose, doas_rad, cut)?;
        }
        self.pool
            .extend(stops.heard()[self.stops.len()..].iter().cloned());
        self.stops = stops;
        while self.next_full <= self.stops.len() {
            self.next_full *= 2;
        }
        Ok(self.consolidate())
    }

    /// Replaces the map with the batch mapper's over every stop so far, seeded with the
    /// mapper's seed: what [`Mapper::run`] gives on the same stops and seed. Returns the
    /// rounds it ran.
    pub fn consolidate(&mut self) -> usize {
        if self.last_full == self.stops.len() {
            return 0;
        }
        let pending = self.pending.take().filter(|p| p.stops == self.stops.len());
        let p = pending.unwrap_or_else(|| Pending {
            stops: self.stops.len(),
            rng: self.rng.clone(),
            rounds: self.rounds,
            work: Work::Done(
                self.mapper
                    .run_stops(&self.stops, &mut MapRng::seed_from_u64(self.seed)),
                0.0,
            ),
        });
        self.adopt(p).0
    }

    /// Waits for the full map running beside the stops, if one does; the next stop (or
    /// [`OnlineMapper::consolidate`]) takes it in. Nothing changes in the map: a replay
    /// that feeds stops faster than a robot makes them calls this between stops, so that
    /// each stop's time is its own.
    pub fn wait_for_full_map(&mut self) {
        if let Some(p) = self.pending.take() {
            let (r, ms) = p.work.finish();
            self.pending = Some(Pending {
                work: Work::Done(r, ms),
                ..p
            });
        }
    }

    /// Replaces the map with the full map `p` of the first `p.stops` stops, from the state
    /// the stop that started it would have left had it run the map itself. Returns the
    /// rounds it ran and its time (ms).
    fn adopt(&mut self, p: Pending) -> (usize, f64) {
        let (r, ms) = p.work.finish();
        self.pool = r.unexplained_bearings;
        self.rng = p.rng;
        self.rounds = p.rounds + r.rounds;
        self.sources = r.sources;
        self.removed = r.removed;
        self.refused = r.refused;
        self.last_full = p.stops;
        (r.rounds, ms)
    }

    /// Re-associates every DoA with the known sources, best supported first, with the
    /// batch mapper's rule: a source found early from few stops (where DoAs of sources not
    /// yet found crossed) loses the DoAs a better supported source explains, as it would
    /// had the batch mapper found them in that order. Sources that took a DoA of the last
    /// stop step their particle cloud with it; with [`IasmConfig::refine`] every source is
    /// refitted to its rays and the rays the fit drops go back to the pool. A source left
    /// with DoAs of fewer than [`IasmConfig::min_observations`] stops is dissolved.
    ///
    /// Returns the last stop's DoAs taken and whether a source was dissolved. The cost is
    /// one angle comparison per source, stop and DoA: no particle is touched but those of
    /// the sources the new stop hears.
    ///
    /// [`IasmConfig::refine`]: crate::IasmConfig::refine
    /// [`IasmConfig::min_observations`]: crate::IasmConfig::min_observations
    fn reassociate(&mut self) -> (usize, bool) {
        let last = self.stops.len() - 1;
        let c = self.mapper.config();
        let (refine, needed, variant, sigma_p) =
            (c.refine, c.min_observations, c.variant, c.sigma_p_m);
        let (sigma, trim) = (self.mapper.sigma(), self.mapper.trim());
        let mut order: Vec<usize> = (0..self.sources.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(self.sources[i].rays.len()));
        for s in &mut self.sources {
            for r in s.rays.drain(..) {
                r.give_back(&mut self.pool);
            }
        }
        let mut taken = 0;
        let mut dissolved = vec![false; self.sources.len()];
        for i in order {
            let s = &mut self.sources[i];
            let mut rays = self
                .mapper
                .associate([s.x, s.y], self.stops.poses(), &mut self.pool);
            if let Some(new) = rays.iter().find(|r| r.stop == last) {
                taken += 1;
                // One filter step on the source's own cloud with the ray it took.
                if !s.cluster.is_empty() {
                    let w = vec![1.0; s.cluster.len()];
                    let mut pf = ParticleFilter::from_parts(std::mem::take(&mut s.cluster), w);
                    pf.update(new.from, &[new.bearing], self.mapper.likelihood());
                    let weighted = pf.weighted_mean();
                    pf.resample(&mut self.rng);
                    pf.predict(sigma_p, &mut self.rng);
                    s.cluster = pf.particles().to_vec();
                    s.covariance = covariance(&s.cluster);
                    if !refine {
                        [s.x, s.y] = match variant {
                            Variant::Ws => weighted,
                            Variant::Ca | Variant::Wdp => mean(&s.cluster),
                        };
                    }
                }
            }
            if refine && let Some(p) = refit([s.x, s.y], &mut rays, sigma, trim, &mut self.pool) {
                (s.x, s.y, s.refined) = (p[0], p[1], true);
            }
            if rays.len() < needed {
                for r in rays {
                    r.give_back(&mut self.pool);
                }
                dissolved[i] = true;
                continue;
            }
            s.observations = rays.len();
            s.rays = rays;
        }
        let mut k = dissolved.iter();
        self.sources
            .retain(|_| !*k.next().expect("one flag per source"));
        let contradicted =
            self.mapper
                .drop_implausible(&mut self.sources, &self.stops, &mut self.pool);
        self.removed += contradicted.len();
        let any = !contradicted.is_empty();
        self.refused.extend(contradicted);
        (taken, dissolved.contains(&true) || any)
    }

    /// The batch mapper's search ([`Mapper::search`]) over the pool, from the rounds run
    /// so far: rounds until one fails (the next full map searches with the batch mapper's
    /// retries), each source required to explain a DoA of the new stop, then the vote.
    fn search(&mut self, update: &mut StopUpdate) {
        let plan = Search {
            first_round: self.rounds + 1,
            retries: 0,
            new_stop: Some(self.stops.len() - 1),
        };
        let before = self.sources.len();
        let rounds = self.mapper.search(
            &self.stops,
            &mut self.pool,
            &mut self.sources,
            &mut self.refused,
            plan,
            &mut self.rng,
        );
        update.rounds += rounds;
        self.rounds += rounds;
        update.found += self.sources.len() - before;
    }

    /// The map after the stops so far.
    pub fn map(&self) -> MapResult {
        let mut sources = self.sources.clone();
        self.mapper.mark_mirrors(&mut sources);
        self.mapper.date(&mut sources, &self.stops);
        MapResult {
            sources,
            rounds: self.rounds,
            particles: self.mapper.num_particles(),
            unexplained: self.mapper.unexplained(self.stops.poses(), &self.pool),
            unexplained_bearings: self.pool.clone(),
            removed: self.removed,
            refused: self.refused.clone(),
        }
    }
}

/// Adds a stop to `stops` as the online mapper takes it: a finite pose outside the map is
/// refused ([`Mapper::check_in_map`]), then [`Mapper::push_stop`] checks the rest. `stops`
/// is unchanged on an error.
fn push_checked(
    mapper: &Mapper,
    stops: &mut Stops,
    pose: Pose,
    doas_rad: &[f64],
    cut: Option<bool>,
) -> Result<()> {
    if pose.is_finite() {
        mapper.check_in_map(stops.len(), pose)?;
    }
    mapper.push_stop(stops, pose, doas_rad, cut)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::IasmConfig;
    use crate::error::Error;
    use crate::map::{Cell, OccupancyMap};
    use crate::ospa::ospa;
    use crate::wrap_rad;
    use rand::Rng;
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    const TRUTH: [[f64; 2]; 4] = [[1.5, 1.5], [4.0, -1.2], [5.5, 2.0], [2.5, -2.0]];

    /// An open 8 x 6 m room, 24 stops along y = 0 with turning headings, each hearing every
    /// source with 2 degrees of noise, and one stop in four a clutter DoA as well (a
    /// reflection's direction).
    fn survey() -> (OccupancyMap, Vec<Pose>, Vec<Vec<f64>>) {
        let (w, h) = (160, 120);
        let map = OccupancyMap::new(w, h, 0.05, [-1.0, -3.0], vec![Cell::Free; w * h]);
        let mut rng = StdRng::seed_from_u64(5);
        let noise = Normal::new(0.0, 2f64.to_radians()).unwrap();
        let poses: Vec<Pose> = (0..24)
            .map(|i| Pose::new(0.25 * f64::from(i), 0.1, 0.25 * f64::from(i)))
            .collect();
        let doas = poses
            .iter()
            .map(|p| {
                let mut row: Vec<f64> = TRUTH
                    .iter()
                    .map(|s| wrap_rad(p.bearing_to(*s) - p.theta + noise.sample(&mut rng)))
                    .collect();
                if rng.random_bool(0.25) {
                    row.push(wrap_rad(rng.random_range(-3.1..3.1)));
                }
                row
            })
            .collect();
        (map, poses, doas)
    }

    fn config() -> IasmConfig {
        IasmConfig {
            num_doas: 5,
            ..IasmConfig::default()
        }
    }

    #[test]
    fn after_the_last_stop_the_online_map_agrees_with_the_batch_map() {
        let (map, poses, with_clutter) = survey();
        let mapper = Mapper::new(&map, &config()).unwrap();
        // Without the clutter, and a DoA missed now and then.
        let mut rng = StdRng::seed_from_u64(9);
        let sparse: Vec<Vec<f64>> = with_clutter
            .iter()
            .map(|r| {
                r[..4]
                    .iter()
                    .copied()
                    .filter(|_| rng.random_bool(0.8))
                    .collect()
            })
            .collect();
        for (seed, clutter) in [
            (0, false),
            (1, false),
            (2, false),
            (3, false),
            (0, true),
            (1, true),
        ] {
            let doas = if clutter { &with_clutter } else { &sparse };
            let batch = mapper
                .run(&poses, doas, &mut MapRng::seed_from_u64(seed))
                .unwrap();
            let mut online = OnlineMapper::new(mapper.clone(), seed);
            for (p, row) in poses.iter().zip(doas) {
                online.add_stop(*p, row).unwrap();
            }
            // As it stands after stop 24 (its last full map was at stop 16): the same
            // sources as the batch map, within 0.1 m.
            let live = online.map();
            if clutter {
                // The batch mapper can make a ghost of clutter near the path (issue 10);
                // the exact agreement below is what is asserted here.
                online.consolidate();
                assert_eq!(online.map().positions(), batch.positions(), "seed {seed}");
                continue;
            }
            assert_eq!(
                batch.sources.len(),
                4,
                "seed {seed}: {:?}",
                batch.positions()
            );
            assert_eq!(live.sources.len(), 4, "seed {seed}: {:?}", live.positions());
            let apart = ospa(&live.positions(), &batch.positions(), 1.0, 1.0).total;
            let l = ospa(&live.positions(), &TRUTH, 1.0, 1.0).total;
            assert!(
                apart < 0.1 && l < 0.15,
                "seed {seed}: apart {apart:.3}, OSPA {l:.3}"
            );
            // Consolidated, it is the batch map of the same seed.
            online.consolidate();
            assert_eq!(online.map().positions(), batch.positions(), "seed {seed}");
        }
    }

    #[test]
    fn a_full_map_run_beside_the_stops_gives_the_maps_it_would_have_given_in_its_stop() {
        // The oracle runs each full map in the stop that is due one (`consolidate` right
        // after it, the old way); from the stop after it on, the maps must be the same, to
        // the bit, and the same whether the full maps ran on a thread or in place.
        let (map, poses, doas) = survey();
        let mapper = Mapper::new(&map, &config()).unwrap();
        for seed in 0..3 {
            let mut oracle = OnlineMapper::new(mapper.clone(), seed);
            let mut threaded = OnlineMapper::new(mapper.clone(), seed);
            let mut in_place = OnlineMapper::new(mapper.clone(), seed);
            in_place.threaded = false;
            let mut started = false;
            for (k, (p, row)) in poses.iter().zip(&doas).enumerate() {
                let u = oracle.add_stop(*p, row).unwrap();
                if u.full {
                    oracle.consolidate();
                }
                let t = threaded.add_stop(*p, row).unwrap();
                let i = in_place.add_stop(*p, row).unwrap();
                assert_eq!((t.full, t.full_ms.is_some()), (u.full, started), "stop {k}");
                assert_eq!(
                    (i.full, i.full_ms.is_some()),
                    (t.full, t.full_ms.is_some()),
                    "stop {k}"
                );
                assert_eq!(threaded.map(), in_place.map(), "seed {seed}, stop {k}");
                if !t.full {
                    assert_eq!(
                        threaded.map().positions(),
                        oracle.map().positions(),
                        "seed {seed}, stop {k}"
                    );
                }
                started = t.full;
            }
            // Consolidated at a stop that started a full map, it takes that map in: the
            // batch map.
            let batch = mapper
                .run(&poses[..16], &doas[..16], &mut MapRng::seed_from_u64(seed))
                .unwrap();
            let mut online = OnlineMapper::new(mapper.clone(), seed);
            for (p, row) in poses.iter().zip(&doas).take(16) {
                online.add_stop(*p, row).unwrap();
            }
            assert!(online.pending.is_some());
            online.wait_for_full_map();
            assert_eq!(online.consolidate(), batch.rounds);
            assert!(online.pending.is_none());
            assert_eq!(online.map().positions(), batch.positions(), "seed {seed}");
        }
    }

    #[test]
    fn a_history_added_at_once_is_the_batch_map_and_the_stops_after_it_go_on() {
        let (map, poses, doas) = survey();
        let mapper = Mapper::new(&map, &config()).unwrap();
        let rows = |r: std::ops::Range<usize>| {
            r.map(|k| (poses[k], &doas[k][..], None))
                .collect::<Vec<_>>()
        };
        for seed in 0..3 {
            let batch = mapper
                .run(&poses[..10], &doas[..10], &mut MapRng::seed_from_u64(seed))
                .unwrap();
            let mut online = OnlineMapper::new(mapper.clone(), seed);
            online.add_history(rows(0..10)).unwrap();
            assert_eq!(online.stops(), 10);
            assert_eq!(online.map().positions(), batch.positions(), "seed {seed}");
            // The next full map is due at 16 stops.
            let full: Vec<usize> = (10..24)
                .filter(|&k| online.add_stop(poses[k], &doas[k]).unwrap().full)
                .map(|k| k + 1)
                .collect();
            assert_eq!(full, [16], "seed {seed}");
            assert_eq!(online.map().sources.len(), 4, "seed {seed}");
        }
        // A bad stop in the history: named, and nothing of it is kept.
        let mut online = OnlineMapper::new(mapper.clone(), 0);
        online.add_history(rows(0..3)).unwrap();
        let before = online.map();
        let mut bad = rows(3..8);
        bad[2].0 = Pose::new(f64::NAN, 0.0, 0.0);
        let e = online.add_history(bad).unwrap_err();
        assert!(matches!(e, Error::NonFinitePose { index: 5 }), "{e}");
        assert_eq!(online.stops(), 3);
        assert_eq!(online.map(), before);
    }

    #[test]
    fn told_which_rows_were_cut_the_consolidated_map_is_the_batch_map_told_the_same() {
        let (map, poses, doas) = survey();
        let mapper = Mapper::new(&map, &config()).unwrap();
        // Every other full row cut, the rest not.
        let cut: Vec<bool> = doas
            .iter()
            .enumerate()
            .map(|(k, r)| r.len() == 5 && k % 2 == 0)
            .collect();
        for seed in 0..3 {
            let batch = mapper
                .run_rows(&poses, &doas, Some(&cut), &mut MapRng::seed_from_u64(seed))
                .unwrap();
            let mut online = OnlineMapper::new(mapper.clone(), seed);
            for ((p, row), &c) in poses.iter().zip(&doas).zip(&cut) {
                online.add_row(*p, row, Some(c)).unwrap();
            }
            online.consolidate();
            assert_eq!(online.map().positions(), batch.positions(), "seed {seed}");
        }
    }

    #[test]
    fn a_run_costs_a_fraction_of_recomputing_at_every_stop() {
        // Work counted in filtering rounds (each a pass of the map's particles over the
        // stops). Recomputing at every stop runs a full map of 1, 2, ..., K stops; the
        // online mapper runs full maps at stops 4, 8 and 16 and, between them, rounds only
        // for the DoAs a stop leaves unexplained, stopping at the first that fails.
        let (map, poses, doas) = survey();
        let mapper = Mapper::new(&map, &config()).unwrap();
        let recompute: usize = (1..=poses.len())
            .map(|k| {
                mapper
                    .run(&poses[..k], &doas[..k], &mut MapRng::seed_from_u64(1))
                    .unwrap()
                    .rounds
            })
            .sum();
        let mut online = OnlineMapper::new(mapper.clone(), 1);
        let updates: Vec<StopUpdate> = poses
            .iter()
            .zip(&doas)
            .map(|(p, row)| online.add_stop(*p, row).unwrap())
            .collect();
        let full: Vec<usize> = updates
            .iter()
            .filter(|u| u.full)
            .map(|u| u.stop + 1)
            .collect();
        assert_eq!(full, [4, 8, 16]);
        let online_rounds: usize = updates.iter().map(|u| u.rounds).sum();
        assert!(
            3 * online_rounds < recompute,
            "online {online_rounds} rounds, recompute {recompute}"
        );
        // Between full maps, a stop with a DoA left over runs one round that fails, or one
        // more per source it finds (the stops that take a full map in count its rounds).
        assert_eq!(
            updates
                .iter()
                .filter(|u| u.full_ms.is_some())
                .map(|u| u.stop + 1)
                .collect::<Vec<_>>(),
            [5, 9, 17]
        );
        for u in updates.iter().filter(|u| u.full_ms.is_none()) {
            assert!(u.rounds <= u.found + 1, "{u:?}");
        }
        // Without clutter, nothing is left over once the map is complete: no round at all.
        let clean: Vec<Vec<f64>> = doas.iter().map(|r| r[..4].to_vec()).collect();
        let mut online = OnlineMapper::new(mapper, 1);
        let late: Vec<StopUpdate> = poses
            .iter()
            .zip(&clean)
            .map(|(p, row)| online.add_stop(*p, row).unwrap())
            // Once stop 17 has taken in the full map stop 16 started.
            .skip(17)
            .collect();
        assert!(
            late.iter()
                .all(|u| u.rounds == 0 && u.associated == 4 && u.sources == 4),
            "{late:?}"
        );
    }

    #[test]
    fn a_bad_stop_is_refused_and_leaves_the_map_as_it_was() {
        let (map, poses, doas) = survey();
        let mut online = OnlineMapper::new(Mapper::new(&map, &config()).unwrap(), 1);
        for (p, row) in poses.iter().zip(&doas).take(10) {
            online.add_stop(*p, row).unwrap();
        }
        let before = online.map();
        let e = online
            .add_stop(Pose::new(f64::NAN, 0.0, 0.0), &doas[10])
            .unwrap_err();
        assert!(matches!(e, Error::NonFinitePose { index: 10 }), "{e}");
        let e = online.add_stop(poses[10], &[0.1; 6]).unwrap_err();
        assert!(
            matches!(
                e,
                Error::TooManyDoas {
                    index: 10,
                    got: 6,
                    n: 5
                }
            ),
            "{e}"
        );
        assert_eq!(online.map(), before);
        assert_eq!(online.stops(), 10);
    }
}
