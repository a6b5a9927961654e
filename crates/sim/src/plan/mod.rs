//! Rooms that are not boxes: a floor plan (a simple polygon) extruded to a height, each
//! wall with its own absorption, and their impulse responses.
//!
//! ## Why not the shoebox's lattice
//!
//! A shoebox's images tile space, each visible from everywhere in the room, so every
//! image within reach sounds. In a room whose plan is not convex (an L, a corridor with
//! alcoves) an image sounds only where its path stays in the room: a talker around a
//! corner has no direct path, and the reflection off the far wing's wall reaches the hall
//! only through the opening. So images are built by reflecting in the walls one at a time
//! (Borish, 1984), and each is checked per microphone by tracing its path back: every leg
//! must meet its wall within the wall's extent, from the room's side, and no leg may
//! cross another wall.
//!
//! ## Floor and ceiling apart
//!
//! The walls are vertical and the floor and ceiling horizontal, so an unfolded path's
//! plan view is the plan's own unfolded path: floor and ceiling reflections change
//! neither where a leg meets a wall nor whether it stays in the room. The images are
//! then pairs of a plan image (built and checked in 2-D) and a vertical image (the 1-D
//! lattice of the floor and the ceiling), which costs the walls' recursion in the plane
//! only.
//!
//! ## Early reflections exact, the late field diffuse
//!
//! Plan images multiply as `(walls - 1)^order`, and a reverberant room's tail needs
//! dozens of reflections. The response is therefore exact (every image, checked) for the
//! first [`EXACT_S`] after the direct sound, the part whose distinct reflections make
//! ghosts in a map, and beyond it the late field of statistical room acoustics: images of
//! all orders arrive at a rate of `4 pi c^3 t^2 / V` each with `1 / (4 pi c t)` of
//! pressure, so the response's mean square per sample is `c / (4 pi V fs)` decaying at
//! Sabine's rate, whatever the room's shape. (Sabine's rather than Eyring's: the specular
//! models this one is checked against decay more slowly than either, pyroomacoustics'
//! ray tracing of an L-shaped room at T20 = 0.55 s where Sabine says 0.54 and Eyring
//! 0.48, and a shoebox's full image lattice slower still; `fixtures/pra/rir_lshape.json`.) It is rendered as a diffuse field: plane
//! waves from [`TAIL_DIRECTIONS`] directions spread over the sphere, each an independent
//! noise, so that the microphones hear it with the coherence a real late field has. The
//! two are cross-faded over [`FADE_S`]. pyroomacoustics does the same with ray tracing
//! for the tail (`scripts/pra_plan_fixture.py` compares the two).

use crate::error::SimError;

/// How long after the direct sound the response is exact (s): the early reflections
/// (the first 50 ms, in room acoustics' definition of early sound: what the ear and an
/// array hear as distinct arrivals).
pub const EXACT_S: f64 = 0.05;
/// The cross-fade from the exact images to the diffuse tail (s).
pub const FADE_S: f64 = 0.005;
/// Plane waves that make the diffuse tail.
pub const TAIL_DIRECTIONS: usize = 32;
/// The most plan images built per source: a bound on work in a plan with many walls.
pub const MAX_PLAN_IMAGES: usize = 400_000;

/// A room whose floor plan is a simple polygon, extruded from the floor (`z = 0`) to
/// `height`.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanRoom {
    /// Corners, counter-clockwise.
    corners: Vec<[f64; 2]>,
    height: f64,
    /// Energy absorption of wall `i` (corner `i` to corner `i + 1`), then floor, ceiling.
    absorption: Vec<f64>,
}

fn invalid(field: &str, message: String) -> SimError {
    SimError::Invalid {
        field: field.into(),
        message,
    }
}

/// Whether segments `a-b` and `c-d` cross (touching at an end counts).
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let o = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if d1 == 0.0 && d2 == 0.0 {
        // On one line: they meet where their extents along it overlap.
        let k = usize::from((b[0] - a[0]).abs() < (b[1] - a[1]).abs());
        let (lo1, hi1) = (a[k].min(b[k]), a[k].max(b[k]));
        let (lo2, hi2) = (c[k].min(d[k]), c[k].max(d[k]));
        return lo1 <= hi2 && lo2 <= hi1;
    }
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0
}

impl PlanRoom {
    /// A room with the given corners (either orientation; stored counter-clockwise),
    /// height, and absorption per wall (corner `i` to `i + 1`) followed by the floor's and
    /// the ceiling's.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for fewer than three corners, a corner not finite, a plan that
    /// crosses itself or has no area, a height not positive, or absorptions that are not
    /// one per wall plus two or lie outside `[0, 1]`.
    pub fn new(corners: &[[f64; 2]], height: f64, absorption: &[f64]) -> Result<Self, SimError> {
        let n = corners.len();
        if n < 3 {
            return Err(invalid(
                "room.plan",
                format!("{n} corners do not make a floor plan (at least 3)"),
            ));
        }
        if let Some(c) = corners
            .iter()
            .find(|c| !(c[0].is_finite() && c[1].is_finite()))
        {
            return Err(invalid("room.plan", format!("corner {c:?} is not finite")));
        }
        if !(height.is_finite() && height > 0.0) {
            return Err(invalid(
                "room.height",
                format!("{height} m is not a positive height"),
            ));
        }
        for i in 0..n {
            for j in i + 1..n {
                // Neighbouring walls share a corner; any other pair must not meet.
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue;
                }
                let (a, b) = (corners[i], corners[(i + 1) % n]);
                let (c, d) = (corners[j], corners[(j + 1) % n]);
                if segments_cross(a, b, c, d) {
                    return Err(invalid(
                        "room.plan",
                        format!("walls {i} and {j} cross: the plan must be a simple polygon"),
                    ));
                }
            }
        }
        let signed: f64 = (0..n)
            .map(|i| {
                let (a, b) = (corners[i], corners[(i + 1) % n]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum::<f64>()
            / 2.0;
        if signed.abs() < 1e-9 {
            return Err(invalid("room.plan", "the plan has no area".into()));
        }
        if absorption.len() != n + 2 {
            return Err(invalid(
                "room.absorption",
                format!(
                    "{} values for {n} walls, a floor and a ceiling (give {})",
                    absorption.len(),
                    n + 2
                ),
            ));
        }
        if let Some((i, a)) = absorption
            .iter()
            .enumerate()
            .find(|(_, a)| !(0.0..=1.0).contains(*a))
        {
            return Err(invalid(
                &format!("room.absorption[{i}]"),
                format!("{a} is outside [0, 1]"),
            ));
        }
        let (mut corners, mut absorption) = (corners.to_vec(), absorption.to_vec());
        if signed < 0.0 {
            // Clockwise: reverse the corners, and the walls with them (wall i ran from
            // corner i to i + 1; reversed, it runs from n - 1 - i - 1 to n - 1 - i).
            corners.reverse();
            absorption[..n].reverse();
            absorption[..n].rotate_left(1);
        }
        Ok(Self {
            corners,
            height,
            absorption,
        })
    }

    /// A room whose surfaces all absorb alike, with Sabine's reverberation time `rt60` (s),
    /// the rate of the statistical tail ([`PlanRoom::sabine_rt60`]).
    ///
    /// # Errors
    /// As [`PlanRoom::new`], and for an `rt60` not positive or shorter than the room can
    /// have.
    pub fn with_rt60(corners: &[[f64; 2]], height: f64, rt60: f64) -> Result<Self, SimError> {
        let open = Self::new(corners, height, &vec![1.0; corners.len() + 2])?;
        if !(rt60.is_finite() && rt60 > 0.0) {
            return Err(invalid(
                "room.rt60",
                format!("{rt60} s is not a positive time"),
            ));
        }
        // Sabine: rt60 = 0.161 V / (S a).
        let a = 0.161 * open.volume() / (open.surface() * rt60);
        if !(a > 0.0 && a < 1.0) {
            return Err(invalid(
                "room.rt60",
                format!("{rt60} s is not a reverberation time this room can have"),
            ));
        }
        Self::new(corners, height, &vec![a; corners.len() + 2])
    }

    /// Corners, counter-clockwise.
    pub fn corners(&self) -> &[[f64; 2]] {
        &self.corners
    }

    /// Height (m).
    pub fn height(&self) -> f64 {
        self.height
    }

    /// Energy absorption per wall (corner `i` to `i + 1`, counter-clockwise), then the
    /// floor's and the ceiling's.
    pub fn absorption(&self) -> &[f64] {
        &self.absorption
    }

    /// The plan's wall `i`: its two corners.
    pub fn wall(&self, i: usize) -> ([f64; 2], [f64; 2]) {
        let n = self.corners.len();
        (self.corners[i], self.corners[(i + 1) % n])
    }

    /// Floor area (m^2).
    pub fn area(&self) -> f64 {
        let n = self.corners.len();
        (0..n)
            .map(|i| {
                let (a, b) = self.wall(i);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum::<f64>()
            / 2.0
    }

    /// Volume (m^3).
    pub fn volume(&self) -> f64 {
        self.area() * self.height
    }

    /// Surface of walls, floor and ceiling (m^2).
    pub fn surface(&self) -> f64 {
        2.0 * self.area() + self.perimeter() * self.height
    }

    fn perimeter(&self) -> f64 {
        (0..self.corners.len())
            .map(|i| {
                let (a, b) = self.wall(i);
                (b[0] - a[0]).hypot(b[1] - a[1])
            })
            .sum()
    }

    /// The area-weighted mean absorption.
    pub fn mean_absorption(&self) -> f64 {
        let n = self.corners.len();
        let walls: f64 = (0..n)
            .map(|i| {
                let (a, b) = self.wall(i);
                (b[0] - a[0]).hypot(b[1] - a[1]) * self.height * self.absorption[i]
            })
            .sum();
        (walls + self.area() * (self.absorption[n] + self.absorption[n + 1])) / self.surface()
    }

    /// Sabine's reverberation time (s).
    pub fn sabine_rt60(&self) -> f64 {
        0.161 * self.volume() / (self.surface() * self.mean_absorption())
    }

    /// Eyring's reverberation time (s): the decay of the late field, whose every sound
    /// path loses `-ln(1 - a)` of its energy per reflection, `c S / (4 V)` reflections a
    /// second.
    pub fn eyring_rt60(&self) -> f64 {
        let a = self.mean_absorption().min(1.0 - 1e-12);
        0.161 * self.volume() / (-self.surface() * (1.0 - a).ln())
    }

    /// The plan's bounding box: `(min, max)` corners (m).
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for c in &self.corners {
            for k in 0..2 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        (lo, hi)
    }

    /// Whether the plan point `p` lies strictly inside the plan (further than 1 um from
    /// every wall).
    pub fn contains_plan(&self, p: [f64; 2]) -> bool {
        let n = self.corners.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = self.wall(i);
            if distance_to_segment(p, a, b) < 1e-6 {
                return false;
            }
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Whether `p` lies strictly inside the room.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        p[2] > 0.0 && p[2] < self.height && self.contains_plan([p[0], p[1]])
    }

    /// The distance (m) from the plan point `p` to the nearest wall.
    pub fn distance_to_walls(&self, p: [f64; 2]) -> f64 {
        (0..self.corners.len())
            .map(|i| {
                let (a, b) = self.wall(i);
                distance_to_segment(p, a, b)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether the plan points `a` and `b` see each other: the segment between them
    /// crosses no wall.
    pub fn sees(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        !self.blocked(a, b, [None, None])
    }

    /// Pressure reflection coefficient of wall `i` (`n` the floor, `n + 1` the ceiling).
    fn beta(&self, i: usize) -> f64 {
        (1.0 - self.absorption[i]).sqrt()
    }

    /// Whether the plan segment `a-b` crosses a wall other than `skip` (ends on a wall
    /// listed in `skip` do not count).
    ///
    /// A wall whose bounding box lies apart from the segment's cannot meet it, and most
    /// walls are such: they are passed over with four comparisons (this test ran for
    /// every leg of every image path, a tenth of a drawn scene's rendering).
    fn blocked(&self, a: [f64; 2], b: [f64; 2], skip: [Option<usize>; 2]) -> bool {
        let (lo, hi) = (
            [a[0].min(b[0]), a[1].min(b[1])],
            [a[0].max(b[0]), a[1].max(b[1])],
        );
        (0..self.corners.len())
            .filter(|w| !skip.contains(&Some(*w)))
            .any(|w| {
                let (c, d) = self.wall(w);
                let apart = c[0].max(d[0]) < lo[0]
                    || c[0].min(d[0]) > hi[0]
                    || c[1].max(d[1]) < lo[1]
                    || c[1].min(d[1]) > hi[1];
                !apart && segments_cross(a, b, c, d)
            })
    }
}

/// Distance from `p` to segment `a-b`.
pub(crate) fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// Signed side of `p` against the wall `a-b`: positive on the room's side (the left of a
/// counter-clockwise wall).
fn side(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// `p` mirrored in the line through `a` and `b`.
fn mirror(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
    let foot = [a[0] + t * dx, a[1] + t * dy];
    [2.0 * foot[0] - p[0], 2.0 * foot[1] - p[1]]
}

/// One plan image: its position, the image it was mirrored from and the wall it was
/// mirrored in (none for the source itself, index 0), its reflections and their gain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanImage {
    /// Position in the plan (m).
    pub pos: [f64; 2],
    /// The image it is a reflection of (`0` for the source and its first images).
    pub parent: usize,
    /// The wall it was mirrored in (`usize::MAX` for the source).
    pub wall: usize,
    /// Wall reflections.
    pub order: u32,
    /// Product of the walls' pressure reflection coefficients.
    pub gain: f64,
}

/// One image in height: its `z`, its floor and ceiling reflections and their gain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightImage {
    /// Height (m).
    pub z: f64,
    /// Floor and ceiling reflections.
    pub order: u32,
    /// Product of their pressure reflection coefficients.
    pub gain: f64,
}

/// Every image of a source in a [`PlanRoom`] that a response may need: the plan's
/// images (each still to be checked per microphone) and the heights'.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanImages {
    /// The source (m).
    pub src: [f64; 3],
    /// Plan images, the source first, each after its parent.
    pub plan: Vec<PlanImage>,
    /// Images in height, the source's own height first.
    pub heights: Vec<HeightImage>,
    /// At most this many reflections in all (plan and height), when given.
    pub max_order: Option<u32>,
}

impl PlanRoom {
    /// The images of `src` whose paths are no longer than `reach` (m) from anywhere in
    /// the room, with at most `max_order` reflections in all when given.
    ///
    /// An image is mirrored only in the walls it lies in front of (a path reflected by a
    /// wall arrives from the room's side), and an image further than `reach` from the
    /// plan's bounding box is not mirrored again: a path through it is at least that long.
    /// At most [`MAX_PLAN_IMAGES`] are built.
    pub fn images(&self, src: [f64; 3], reach: f64, max_order: Option<u32>) -> PlanImages {
        let n = self.corners.len();
        let (lo, hi) = self.bounds();
        let far = |p: [f64; 2]| {
            let dx = (lo[0] - p[0]).max(p[0] - hi[0]).max(0.0);
            let dy = (lo[1] - p[1]).max(p[1] - hi[1]).max(0.0);
            dx.hypot(dy)
        };
        let mut plan = vec![PlanImage {
            pos: [src[0], src[1]],
            parent: 0,
            wall: usize::MAX,
            order: 0,
            gain: 1.0,
        }];
        let mut next = 0;
        while next < plan.len() && plan.len() < MAX_PLAN_IMAGES {
            let im = plan[next];
            let id = next;
            next += 1;
            if max_order.is_some_and(|m| im.order >= m) || far(im.pos) > reach {
                continue;
            }
            for w in (0..n).filter(|&w| w != im.wall) {
                let (a, b) = self.wall(w);
                if side(im.pos, a, b) <= 0.0 {
                    continue;
                }
                plan.push(PlanImage {
                    pos: mirror(im.pos, a, b),
                    parent: id,
                    wall: w,
                    order: im.order + 1,
                    gain: im.gain * self.beta(w),
                });
            }
        }
        plan.truncate(MAX_PLAN_IMAGES);
        let h = self.height;
        let (bf, bc) = (self.beta(n), self.beta(n + 1));
        let n_max = ((reach + h) / (2.0 * h)).ceil() as i64 + 1;
        let mut heights = Vec::new();
        for k in -n_max..=n_max {
            for q in 0..2i64 {
                let z = (1 - 2 * q) as f64 * src[2] + 2.0 * k as f64 * h;
                if (z - h / 2.0).abs() > reach + h / 2.0 {
                    continue;
                }
                let (floor, ceiling) = ((k - q).unsigned_abs() as i32, k.unsigned_abs() as i32);
                heights.push(HeightImage {
                    z,
                    order: (floor + ceiling) as u32,
                    gain: bf.powi(floor) * bc.powi(ceiling),
                });
            }
        }
        heights.sort_by_key(|i| i.order);
        PlanImages {
            src,
            plan,
            heights,
            max_order,
        }
    }

    /// Whether plan image `id` of `images` sounds at the plan point `mic`: its path, traced
    /// back from `mic`, meets each of its walls within the wall, from the room's side, and
    /// no leg crosses another wall.
    pub fn visible(&self, images: &[PlanImage], id: usize, mic: [f64; 2]) -> bool {
        let src = images[0].pos;
        let mut from = mic;
        let mut last: Option<usize> = None;
        let mut k = id;
        while k != 0 {
            let im = images[k];
            let (a, b) = self.wall(im.wall);
            let s0 = side(from, a, b);
            if s0 <= 0.0 {
                return false;
            }
            // Where the leg towards the image meets the wall's line.
            let t = s0 / (s0 - side(im.pos, a, b));
            let p = [
                from[0] + t * (im.pos[0] - from[0]),
                from[1] + t * (im.pos[1] - from[1]),
            ];
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let u = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
            if !(0.0..=1.0).contains(&u) || self.blocked(from, p, [last, Some(im.wall)]) {
                return false;
            }
            from = p;
            last = Some(im.wall);
            k = im.parent;
        }
        !self.blocked(from, src, [last, None])
    }
}

/// The weight of the diffuse tail at time `t` (s): 0 before `start`, 1 from
/// `start + FADE_S`, a raised cosine between; the exact images are weighted by one minus
/// it.
pub fn tail_weight(t: f64, start: f64) -> f64 {
    let x = ((t - start) / FADE_S).clamp(0.0, 1.0);
    0.5 - 0.5 * (std::f64::consts::PI * x).cos()
}

/// When the diffuse tail takes over (s from emission) for a source heard from `d` m:
/// [`EXACT_S`] after the direct sound.
pub fn tail_start(d: f64, c: f64) -> f64 {
    d / c + EXACT_S
}

/// The images of `images` that sound at `mic` (3-D, with their gains and reflections in
/// all) arriving within `reach` m of travel.
pub fn sounding(
    room: &PlanRoom,
    images: &PlanImages,
    mic: [f64; 3],
    reach: f64,
) -> Vec<crate::ism::ImageSource> {
    sounding_among(room, images, 0..images.plan.len(), mic, reach)
}

/// [`sounding`] among the plan images `ids` (ascending) only.
fn sounding_among(
    room: &PlanRoom,
    images: &PlanImages,
    ids: impl Iterator<Item = usize>,
    mic: [f64; 3],
    reach: f64,
) -> Vec<crate::ism::ImageSource> {
    let m2 = [mic[0], mic[1]];
    let mut out = Vec::new();
    for id in ids {
        let im = &images.plan[id];
        let dxy2 = (im.pos[0] - m2[0]).powi(2) + (im.pos[1] - m2[1]).powi(2);
        if dxy2 > reach * reach || !room.visible(&images.plan, id, m2) {
            continue;
        }
        for z in &images.heights {
            let order = im.order + z.order;
            if images.max_order.is_some_and(|m| order > m)
                || dxy2 + (z.z - mic[2]).powi(2) > reach * reach
            {
                continue;
            }
            out.push(crate::ism::ImageSource {
                pos: [im.pos[0], im.pos[1], z.z],
                gain: im.gain * z.gain,
                order,
            });
        }
    }
    out
}

impl PlanImages {
    /// The plan images that may sound within `reach` m at a microphone within `radius` m
    /// of the plan point `centre`, ascending: those within `reach + radius` of it, less
    /// those [`PlanRoom::hidden_from_disc`] shows to be hidden from the whole disc. An
    /// array's microphones share it ([`add_plan_images`]'s `near`): nearly every image is
    /// hidden from the array, most of them at their first or second wall, and this
    /// settles it once for the array rather than once a microphone (the path traced for
    /// every image and microphone was half of a drawn scene's rendering).
    pub fn near(&self, room: &PlanRoom, centre: [f64; 2], radius: f64, reach: f64) -> Vec<usize> {
        let r2 = (reach + radius).powi(2);
        (0..self.plan.len())
            .filter(|&id| {
                let p = self.plan[id].pos;
                (p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2) <= r2
                    && !room.hidden_from_disc(&self.plan, id, centre, radius)
            })
            .collect()
    }
}

impl PlanRoom {
    /// Whether plan image `id` of `images` is hidden from every point within `radius` m
    /// of `centre`, by its first wall's side or by where its path meets a wall: a `true`
    /// here is a `false` of [`PlanRoom::visible`] at every such point; a `false` says
    /// nothing.
    ///
    /// Unfolded (each wall's reflection undone), a path from a point `q` to the image is
    /// the straight segment from `q` to it, and its `k`-th reflection lies where that
    /// segment meets the `k`-th wall mirrored in the walls before it. It lies within the
    /// wall only if `q` lies in the sector the mirrored wall spans from the image; a disc
    /// that lies wholly outside one of those sectors, by more than rounding, is hidden.
    pub fn hidden_from_disc(
        &self,
        images: &[PlanImage],
        id: usize,
        centre: [f64; 2],
        radius: f64,
    ) -> bool {
        if id == 0 {
            return false;
        }
        let margin = radius + 1e-6;
        let apex = images[id].pos;
        // Whether `centre` lies more than `margin` on the negative side of the line from
        // `a` to `b` (`side` is the distance times the length: compared squared).
        let clear_of = |a: [f64; 2], b: [f64; 2], sign: f64| {
            let at = side(centre, a, b) * sign;
            at < 0.0 && at * at > margin * margin * ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2))
        };
        let (a, b) = self.wall(images[id].wall);
        if clear_of(a, b, 1.0) {
            return true; // behind its first wall
        }
        // Is the disc wholly on the other side of the line from the apex through `p` than
        // `other` is?
        let beyond = |p: [f64; 2], other: [f64; 2]| {
            let reference = side(other, apex, p);
            reference != 0.0 && clear_of(apex, p, reference.signum())
        };
        let mut unfold: Vec<usize> = Vec::new();
        let mut k = id;
        while k != 0 {
            let (mut a, mut b) = self.wall(images[k].wall);
            for &w in unfold.iter().rev() {
                let (c, d) = self.wall(w);
                (a, b) = (mirror(a, c, d), mirror(b, c, d));
            }
            if beyond(a, b) || beyond(b, a) {
                return true;
            }
            unfold.push(images[k].wall);
            k = images[k].parent;
        }
        false
    }
}

/// How far (m) an image of a response `len` samples long at `fs` may be, with the exact
/// images faded out after `tail_from` (s) when given: the images [`add_plan_images`] adds.
pub fn image_reach(len: usize, fs: f64, c: f64, tail_from: Option<f64>) -> f64 {
    // As the shoebox's images: those that arrive within the response.
    let reach = len as f64 / fs * c;
    tail_from.map_or(reach, |s| reach.min((s + FADE_S) * c))
}

/// Adds to `h` (samples at `fs`, from emission) the images of `images` that sound at
/// `mic` and arrive within `h`, each weighted by one minus [`tail_weight`] when
/// `tail_from` (s) is given (and none after the fade). With `near`, only those plan images
/// are looked at ([`PlanImages::near`] within [`image_reach`] and the microphone's
/// distance from the point it was taken about).
#[allow(clippy::too_many_arguments)]
pub fn add_plan_images(
    room: &PlanRoom,
    images: &PlanImages,
    near: Option<&[usize]>,
    mic: [f64; 3],
    fs: f64,
    c: f64,
    h: &mut [f64],
    tail_from: Option<f64>,
) {
    let reach = image_reach(h.len(), fs, c, tail_from);
    let sounding = match near {
        Some(ids) => sounding_among(room, images, ids.iter().copied(), mic, reach),
        None => sounding(room, images, mic, reach),
    };
    for im in sounding {
        let d = (0..3)
            .map(|k| (im.pos[k] - mic[k]).powi(2))
            .sum::<f64>()
            .sqrt()
            .max(1e-3);
        let t = d / c;
        let fade = tail_from.map_or(1.0, |s| 1.0 - tail_weight(t, s));
        let amp = im.gain * fade / (4.0 * std::f64::consts::PI * d);
        crate::ism::add_impulse(h, t * fs, amp);
    }
}

/// [`TAIL_DIRECTIONS`] directions spread evenly over the sphere (a Fibonacci lattice):
/// unit vectors pointing towards where each plane wave comes from.
pub fn tail_directions() -> Vec<[f64; 3]> {
    let n = TAIL_DIRECTIONS as f64;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..TAIL_DIRECTIONS)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            [r * a.cos(), r * a.sin(), z]
        })
        .collect()
}

/// The diffuse tail's plane waves at the array's centre: [`TAIL_DIRECTIONS`] independent
/// Gaussian noises of `len` samples, each `1 / sqrt(TAIL_DIRECTIONS)` of the late field's
/// pressure, which has a mean square of `c / (4 pi V fs)` per sample at emission, decays
/// at the room's Sabine rate and fades in from `tail_from` (s).
pub fn tail_waves(
    room: &PlanRoom,
    fs: f64,
    c: f64,
    len: usize,
    tail_from: f64,
    seed: u64,
) -> Vec<Vec<f64>> {
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = StdRng::seed_from_u64(seed);
    let level = (c / (4.0 * std::f64::consts::PI * room.volume() * fs)).sqrt()
        / (TAIL_DIRECTIONS as f64).sqrt();
    // Amplitude decays 60 dB in rt60: exp(-ln(1000) t / rt60).
    let rate = 1000f64.ln() / room.sabine_rt60();
    let first = (tail_from * fs).floor().max(0.0).min(len as f64) as usize;
    // The decay and the fade-in are the same for every wave: computed once per sample
    // (an exponential and a cosine per sample and wave were a tenth of a drawn scene's
    // rendering), and applied in the same order as before, so the same bits.
    let envelope: Vec<(f64, f64)> = (first..len)
        .map(|k| {
            let t = k as f64 / fs;
            ((-rate * t).exp(), tail_weight(t, tail_from))
        })
        .collect();
    (0..TAIL_DIRECTIONS)
        .map(|_| {
            let mut x = vec![0.0; len];
            for (v, &(decay, fade)) in x[first..].iter_mut().zip(&envelope) {
                let g: f64 = StandardNormal.sample(&mut rng);
                *v = g * level * decay * fade;
            }
            x
        })
        .collect()
}

/// The impulse response (`cfg.rir_len` samples at `cfg.fs`, not high-passed) from `src`
/// to `mic` in `room`: the exact images with at most `cfg.max_order` reflections when
/// given, and with
/// `tail_seed` the diffuse tail (heard at the array's centre: the waves undelayed) from
/// [`EXACT_S`] after the direct sound.
pub fn plan_rir(
    room: &PlanRoom,
    src: [f64; 3],
    mic: [f64; 3],
    cfg: &crate::render::RenderConfig,
    tail_seed: Option<u64>,
) -> Vec<f64> {
    let (fs, c, len, max_order) = (cfg.fs, cfg.speed_of_sound, cfg.rir_len, cfg.max_order);
    let d = (0..3)
        .map(|k| (src[k] - mic[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    let tail_from = tail_seed.map(|_| tail_start(d, c));
    let reach = tail_from.map_or(len as f64 / fs, |s| s + FADE_S) * c;
    let images = room.images(src, reach, max_order);
    let mut h = vec![0.0; len];
    add_plan_images(room, &images, None, mic, fs, c, &mut h, tail_from);
    if let (Some(seed), Some(from)) = (tail_seed, tail_from) {
        for wave in tail_waves(room, fs, c, len, from, seed) {
            h.iter_mut().zip(&wave).for_each(|(h, w)| *h += w);
        }
    }
    h
}

#[cfg(test)]
mod tests;
