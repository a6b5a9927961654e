//! Reassociation once every source is known: each DoA to the source nearest its bearing.

use super::*;

impl Mapper {
    /// Gives every DoA that a source explains to the source it fits best
    /// ([`IasmConfig::reassociate`]): a ray moves to another source that lies nearer its
    /// bearing, within `gamma`, when that source holds no DoA of the ray's stop yet; the
    /// sources that gained or lost rays are refined again (with [`IasmConfig::refine`]),
    /// and those left with fewer than [`IasmConfig::min_observations`] stops are removed,
    /// their DoAs given back to `bearings`. Repeated until nothing moves (at most
    /// [`REASSOCIATE_PASSES`] times). A DoA shared by two sources ([`Ray::shared`]) and a
    /// linear array's DoA, which stands for two bearings ([`Ray::twin`]), stay where they
    /// are. Returns the removed sources, as [`Refusal::Reassigned`].
    ///
    /// # Panics
    /// If a ray's stop lies outside `bearings`.
    pub fn reassociate(
        &self,
        sources: &mut Vec<Source>,
        bearings: &mut [Vec<f64>],
    ) -> Vec<Refused> {
        let mut refused = Vec::new();
        // The DoAs moved so far (stop, bearing): each moves once, so that two sources
        // whose refits move them cannot pass one DoA back and forth.
        let mut moved: Vec<(usize, f64)> = Vec::new();
        for _ in 0..REASSOCIATE_PASSES {
            let at: Vec<[f64; 2]> = sources.iter().map(|s| [s.x, s.y]).collect();
            let mut touched = vec![false; sources.len()];
            for i in 0..sources.len() {
                let mut k = 0;
                while k < sources[i].rays.len() {
                    let r = sources[i].rays[k];
                    let own = r.miss(at[i]);
                    let free =
                        !r.shared && r.twin.is_none() && !moved.contains(&(r.stop, r.bearing));
                    let better = free
                        .then(|| {
                            (0..sources.len())
                                .filter(|&j| {
                                    j != i && sources[j].rays.iter().all(|q| q.stop != r.stop)
                                })
                                .map(|j| (j, r.miss(at[j])))
                                .filter(|&(_, miss)| miss < own && miss <= self.gamma)
                                .min_by(|a, b| a.1.total_cmp(&b.1))
                        })
                        .flatten();
                    match better {
                        Some((j, _)) => {
                            let r = sources[i].rays.remove(k);
                            moved.push((r.stop, r.bearing));
                            sources[j].rays.push(r);
                            (touched[i], touched[j]) = (true, true);
                        }
                        None => k += 1,
                    }
                }
            }
            if !touched.contains(&true) {
                break;
            }
            for (s, _) in sources.iter_mut().zip(touched).filter(|(_, t)| *t) {
                // In stop order, as the rounds' association leaves them (the explanation
                // lists them so).
                s.rays.sort_by_key(|r| r.stop);
                if self.config.refine
                    && let Some(p) = refit([s.x, s.y], &mut s.rays, self.sigma, self.trim, bearings)
                {
                    (s.x, s.y, s.refined) = (p[0], p[1], true);
                }
                s.observations = s.rays.len();
            }
            sources.retain_mut(|s| {
                let stops = stops_of(&s.rays);
                if stops.len() >= self.config.min_observations {
                    return true;
                }
                refused.push(Refused {
                    x: s.x,
                    y: s.y,
                    stops,
                    rule: Refusal::Reassigned,
                });
                for r in s.rays.drain(..) {
                    r.give_back(bearings);
                }
                false
            });
        }
        refused
    }
}
