//! The map is the room ([`IasmConfig::room_margin_m`]): no source is reported where the
//! map holds a wall or space the robot never saw behind one.
//!
//! A source outside the room (in a wall, or in the unknown that every stop that heard it
//! sees only through a wall, or in the unknown just behind a wall's face) moves to the free
//! place nearest it where its DoAs still fit, or is refused. Unknown space that a stop
//! sees through free cells is unsurveyed, not beyond the walls, and a source there stays,
//! unless a wall lies between it and the free cell nearest it. Which free places are
//! looked at: the free cells within the vote's reach of it, `merge_dist_m` + 2 `sigma` of
//! its nearest stop's range (a DoA error of 2 `sigma` moves a crossing by that much along
//! it), nearest first; the first that keeps as many of its stops within the gate as the
//! source had, less one, is taken. Looking further would let any source beyond a wall
//! slide along its rays into the room.

use super::*;

/// What the room rule did with a source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum InRoom {
    /// It lies in the room (or the rule is off, or the map is an open region).
    Inside,
    /// It fits its DoAs at this free place, in the room.
    MovedTo([f64; 2]),
    /// Its DoAs fit nowhere in the room near it.
    Outside,
}

impl Mapper {
    /// Whether the rule applies: it is on and the map was surveyed (has walls).
    fn room_rule(&self) -> bool {
        self.config.room_margin_m > 0.0 && self.surveyed
    }

    /// Whether `p` lies in the room: a free cell within [`IasmConfig::room_margin_m`]
    /// (always, where the rule does not apply).
    pub(super) fn in_room(&self, p: [f64; 2]) -> bool {
        !self.room_rule()
            || matches!(self.map.cell_at(p), Some(Cell::Free))
            || !self
                .map
                .free_within(p, self.config.room_margin_m)
                .is_empty()
    }

    /// Whether a stop that heard the source at `p` (one of `rays`) sees it through cells
    /// that are not occupied: the unknown it stands in is then space the robot did not
    /// survey (a corner its range sensor never turned to, a doorway's far side), not space
    /// behind a wall. Occupied cells within [`IasmConfig::room_margin_m`] of `p` are its
    /// own (the wall it stands at, the furniture it stands on).
    fn seen_in_the_open(&self, p: [f64; 2], rays: &[Ray]) -> bool {
        rays.iter().any(|r| self.sees(r.from, p))
    }

    /// Whether the map shows a place `to` to a stop at `from`: no occupied cell on the
    /// way, leaving out the [`IasmConfig::room_margin_m`] at `to` (a source's own wall, its
    /// own table). The one question of what a stop sees that the room rule, the
    /// reflection rules and the map's dating ask.
    pub(super) fn sees(&self, from: [f64; 2], to: [f64; 2]) -> bool {
        self.wall_short_of(from, to, self.config.room_margin_m)
            .is_none()
    }

    /// The first occupied cell on the straight way from `from` to `to`, leaving out the
    /// last `margin` metres at `to` (the wall or furniture a source there stands at); `None`
    /// when the way is clear or no longer than `margin`: [`Mapper::sees`] with the room's
    /// margin, and the wall rule with its clearance.
    pub(super) fn wall_short_of(
        &self,
        from: [f64; 2],
        to: [f64; 2],
        margin: f64,
    ) -> Option<[f64; 2]> {
        let d = [to[0] - from[0], to[1] - from[1]];
        let len = d[0].hypot(d[1]);
        if len <= margin {
            return None;
        }
        let keep = 1.0 - margin / len;
        self.map
            .first_occupied(from, [from[0] + keep * d[0], from[1] + keep * d[1]])
    }

    /// Whether `p` lies in unknown space just behind a wall's face: the free cell nearest
    /// it, within [`IasmConfig::merge_dist_m`], is on the wall's other side.
    fn behind_a_face(&self, p: [f64; 2]) -> bool {
        if !self.room_rule() || !matches!(self.map.cell_at(p), None | Some(Cell::Unknown)) {
            return false;
        }
        self.map
            .free_within(p, self.config.merge_dist_m)
            .first()
            .is_some_and(|&q| self.map.first_occupied(q, p).is_some())
    }

    /// Where a source at `p` explaining `rays` may stand in the room (see the module docs).
    pub(super) fn place_in_room(&self, p: [f64; 2], rays: &[Ray]) -> InRoom {
        if !self.behind_a_face(p) && (self.in_room(p) || self.seen_in_the_open(p, rays)) {
            return InRoom::Inside;
        }
        let gate = 2.0 * self.sigma;
        let fitting = |q: [f64; 2]| {
            let mut stops: Vec<usize> = rays
                .iter()
                .filter(|r| r.miss(q) <= gate)
                .map(|r| r.stop)
                .collect();
            stops.dedup();
            stops.len()
        };
        let need = fitting(p)
            .saturating_sub(1)
            .max(self.config.min_observations);
        let range = rays
            .iter()
            .map(|r| (r.from[0] - p[0]).hypot(r.from[1] - p[1]))
            .fold(f64::INFINITY, f64::min);
        if !range.is_finite() {
            return InRoom::Outside;
        }
        let reach = self.config.merge_dist_m + range * gate.tan();
        self.map
            .free_within(p, reach)
            .into_iter()
            .find(|&q| fitting(q) >= need)
            .map_or(InRoom::Outside, InRoom::MovedTo)
    }

    /// Every source in the room: moved into it where its DoAs fit (see [`Mapper::place_in_room`]),
    /// refused otherwise, its DoAs given back to `pool`.
    pub(super) fn keep_in_room(
        &self,
        sources: &mut Vec<Source>,
        pool: &mut [Vec<f64>],
    ) -> Vec<Refused> {
        let mut refused = Vec::new();
        sources.retain_mut(|s| match self.place_in_room([s.x, s.y], &s.rays) {
            InRoom::Inside => true,
            InRoom::MovedTo(q) => {
                (s.x, s.y) = (q[0], q[1]);
                true
            }
            InRoom::Outside => {
                refused.push(Refused {
                    x: s.x,
                    y: s.y,
                    stops: stops_of(&s.rays),
                    rule: Refusal::OutsideRoom,
                });
                for r in s.rays.drain(..) {
                    r.give_back(pool);
                }
                false
            }
        });
        refused
    }
}
