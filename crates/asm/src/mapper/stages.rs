//! What a map runs after the paper's rounds, as one list.
//!
//! Algorithm 1 of the paper is `rounds.rs` (filtering, clustering, implicit association,
//! round after round) and, last, the merge of close estimates ([`Mapper::merge`]).
//! Everything the default profile does after that is a [`Stage`], and
//! [`IasmConfig::stages`] is the list a configuration runs, in the order it runs it
//! ([`Mapper::settle`], shared by the batch map and the online mapper's full maps): the
//! paper profile's is empty. Each stage is a `&self` method of the [`Mapper`]: it reads the
//! stops and the occupancy map, which it cannot change, changes only the sources and the
//! pool of unexplained DoAs, and says what it removed and why ([`Refused`]). Why each is
//! there, and the measurement that keeps it, is in `docs/decisions/0014-mapper-settings.md`.

use super::rules::own_orphaned_shares;
use super::*;

/// A step after the paper's rounds (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// What cannot be a source is refused ([`Mapper::drop_implausible`]): on the robot's
    /// path ([`IasmConfig::min_range_m`]), contradicted by nearer stops that heard nothing
    /// there ([`IasmConfig::absence_ratio`]), beyond the map or behind a wall
    /// ([`IasmConfig::beyond_map_m`], [`IasmConfig::wall_clearance_m`]), outside the room
    /// ([`IasmConfig::room_margin_m`]), made of another's reflections
    /// ([`IasmConfig::reflections`]), or too thinly heard once cut rows count less
    /// ([`IasmConfig::vote_min_thresholded_stops`]).
    Refuse,
    /// Every DoA to the mapped source it fits best, then the refusals again on what each
    /// keeps ([`IasmConfig::reassociate`]).
    Reassociate,
    /// A source's own blends with its image in a near wall do not move it, and one heard
    /// by its image stands where its unfolded rays meet ([`IasmConfig::reflections`], with
    /// [`IasmConfig::refine`]).
    OwnReflections,
    /// The map is the room, once more for sources the merge or the previous stage moved
    /// ([`IasmConfig::room_margin_m`]).
    Room,
}

impl IasmConfig {
    /// The stages this configuration runs after the rounds, in order (see the module docs):
    /// a stage whose settings are all off is left out.
    pub fn stages(&self) -> Vec<Stage> {
        let refuse = self.min_range_m > 0.0
            || self.absence_ratio > 0.0
            || self.beyond_map_m > 0.0
            || self.wall_clearance_m > 0.0
            || self.room_margin_m > 0.0
            || self.reflections
            || self.vote_min_stops > 0;
        [
            (Stage::Refuse, refuse),
            (Stage::Reassociate, self.reassociate),
            (Stage::OwnReflections, self.reflections && self.refine),
            (Stage::Room, self.room_margin_m > 0.0),
        ]
        .into_iter()
        .filter_map(|(s, on)| on.then_some(s))
        .collect()
    }
}

impl Mapper {
    /// Ends Algorithm 1 with the paper's merge and runs [`IasmConfig::stages`] on the
    /// sources, in the batch map and between the online map's full maps. Returns the
    /// removed sources with their rules; their DoAs go back to `pool`.
    ///
    /// Why the refusals run again after the reassociation: a round's cloud that settles
    /// short of a talker, on the talker's rays, passes the first with the talker's DoAs;
    /// reassociated, it keeps only what else it had (reflections that happen to cross
    /// there) and is judged on those. Measured (20 seeds on each of three renderings of the
    /// suite's and `fixtures/heldout`'s scenes, both methods): `one_source` GCC-PHAT lost
    /// its ghost (4 maps of 60 held one, 0.042 -> 0.009 m), `sparse_eight_speech` MVDR
    /// lost a thinly heard real source in one map of 60 (0.229 -> 0.231 m); the mean over
    /// the scenes 0.0870 -> 0.0864 m. Why the merges before and after it: two estimates of
    /// one source closer than the merge distance would split its DoAs between them and
    /// move apart, and the refusals may leave two such.
    ///
    /// # Panics
    /// As [`Mapper::drop_implausible`].
    pub(crate) fn settle(
        &self,
        sources: &mut Vec<Source>,
        stops: &Stops,
        pool: &mut [Vec<f64>],
    ) -> Vec<Refused> {
        // The paper's last step ends Algorithm 1: the estimates of one source merged.
        self.merge(sources);
        let mut removed = Vec::new();
        for stage in self.config.stages() {
            match stage {
                Stage::Refuse => removed.extend(self.drop_implausible(sources, stops, pool)),
                Stage::Reassociate => {
                    self.merge(sources);
                    removed.extend(self.reassociate(sources, pool));
                    removed.extend(self.drop_implausible(sources, stops, pool));
                    self.merge(sources);
                }
                Stage::OwnReflections => self.place_by_own_reflections(sources, stops, pool),
                Stage::Room => removed.extend(self.keep_in_room(sources, pool)),
            }
        }
        own_orphaned_shares(sources, pool);
        removed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_runs_no_stage_and_the_default_every_stage_in_order() {
        assert_eq!(IasmConfig::profile(Profile::Paper).stages(), vec![]);
        assert_eq!(
            IasmConfig::default().stages(),
            vec![
                Stage::Refuse,
                Stage::Reassociate,
                Stage::OwnReflections,
                Stage::Room
            ]
        );
        // A stage whose settings are off is not in the list; one setting of its own keeps
        // it there.
        let c = IasmConfig {
            reflections: false,
            room_margin_m: 0.0,
            reassociate: false,
            ..IasmConfig::default()
        };
        assert_eq!(c.stages(), vec![Stage::Refuse]);
        let c = IasmConfig {
            min_range_m: 0.3,
            ..IasmConfig::profile(Profile::Paper)
        };
        assert_eq!(c.stages(), vec![Stage::Refuse]);
    }
}
