//! The room of a scene: a shoebox or a floor plan, as written and as checked.

use serde::{Deserialize, Serialize};

use super::{MAX_RT60_S, Scene, invalid};
use crate::error::SimError;
use crate::plan::PlanRoom;
use crate::room::{Room, Space};

/// The room of a scene: a shoebox (`dims`) or a floor plan (`plan` and `height`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RoomSpec {
    /// A shoebox's dimensions (m).
    pub dims: Option<[f64; 3]>,
    /// A floor plan's corners (m, in order, either way round; x and y not negative), for a
    /// room that is not a box ([`crate::plan`]).
    pub plan: Option<Vec<[f64; 2]>>,
    /// A floor plan's height (m).
    pub height: Option<f64>,
    /// Target reverberation time (s); exclusive with `absorption`.
    pub rt60: Option<f64>,
    /// Per-surface energy absorption: a shoebox's six (x0, x1, y0, y1, floor, ceiling), or
    /// one per wall of a plan (corner `i` to `i + 1`) then floor and ceiling.
    pub absorption: Option<Vec<f64>>,
}

impl Scene {
    /// The room as written: a shoebox from `dims`, or a plan from `plan` and `height`,
    /// with `rt60` or `absorption`.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the field.
    pub fn space(&self) -> Result<Space, SimError> {
        let r = &self.room;
        let both = || invalid("room", "give rt60 or absorption, not both");
        let neither = || invalid("room", "give rt60 or absorption");
        match (r.dims, &r.plan, r.height) {
            (Some(dims), None, None) => Ok(Space::Shoebox(match (r.rt60, &r.absorption) {
                (Some(t), None) => Room::with_rt60(dims, t, self.speed_of_sound)?,
                (None, Some(a)) => {
                    let six: [f64; 6] = a.as_slice().try_into().map_err(|_| {
                        invalid(
                            "room.absorption",
                            format!("{} values for a shoebox's six surfaces", a.len()),
                        )
                    })?;
                    Room::new(dims, six)?
                }
                (None, None) => return Err(neither()),
                (Some(_), Some(_)) => return Err(both()),
            })),
            (None, Some(plan), Some(height)) => {
                if let Some(c) = plan.iter().find(|c| c[0] < 0.0 || c[1] < 0.0) {
                    return Err(invalid(
                        "room.plan",
                        format!("corner {c:?}: give the plan in x, y >= 0 (the map starts at 0)"),
                    ));
                }
                Ok(Space::Plan(match (r.rt60, &r.absorption) {
                    (Some(t), None) => {
                        if !(t.is_finite() && t > 0.0 && t <= MAX_RT60_S) {
                            return Err(invalid(
                                "room.rt60",
                                format!("{t} s is not a reverberation time in (0, {MAX_RT60_S}] s"),
                            ));
                        }
                        PlanRoom::with_rt60(plan, height, t)?
                    }
                    (None, Some(a)) => PlanRoom::new(plan, height, a)?,
                    (None, None) => return Err(neither()),
                    (Some(_), Some(_)) => return Err(both()),
                }))
            }
            _ => Err(invalid(
                "room",
                "give dims (a shoebox) or plan and height (a floor plan), not both",
            )),
        }
    }

    /// The x and y extent of the room as written (m), from 0: what the waypoints must lie
    /// in before the stops are checked one by one.
    pub(super) fn room_extent(&self) -> [f64; 2] {
        match (&self.room.dims, &self.room.plan) {
            (Some(d), _) => [d[0], d[1]],
            (None, Some(p)) => p
                .iter()
                .fold([0.0f64; 2], |m, c| [m[0].max(c[0]), m[1].max(c[1])]),
            (None, None) => [0.0; 2],
        }
    }
}
