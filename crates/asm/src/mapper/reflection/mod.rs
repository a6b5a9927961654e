//! Heard by reflection ([`IasmConfig::reflections`]): a source whose DoAs are another
//! source's reflections in the map's walls is no source.
//!
//! A talker in an alcove is heard from the corridor's far stops only by its reflections
//! in the alcove's side walls, and the reflections heard from either side cross at the
//! alcove's mouth, in the room, as consistently as a source's own rays meet; a plain
//! room's walls do the same wherever two stops hear one source's images. The map says
//! where the walls are, so each DoA's ray can be traced through them, reflected
//! specularly where it meets one (the image-source model unfolded, as in
//! reflection-aware localisation: An et al., ICRA 2018; to the first order, [`MAX_ORDER`];
//! a wall's direction from its cells around the point hit). A ray is a mapped source's
//! reflection when
//!
//! - its reflected leg passes the source before the next wall, within the vote's gate
//!   (2 `sigma`, as the angle at the stop to the source's image), and within one `sigma`
//!   of how well the source that took it fits it (a real source's own rays, a fraction of
//!   a degree off, are not explained by an image 8 degrees off);
//! - the stop heard the mapped source's direct sound too (a DoA near its bearing), or the
//!   map hides the source from it: a reflection is weaker than its direct sound and never
//!   heard without it in plain view.
//!
//! A reflection can also be heard blended with its direct sound: a robot's array is small
//! against speech's wavelengths, and when a source stands near a wall its image is close
//! enough in bearing and strength that both make one peak between them
//! ([`Mapper::blends`]: within 60 degrees of each other, the reflected path at most twice
//! the direct one). From stops on one side such peaks all point between the source and
//! the wall, and they cross near the wall: MVDR hears `corridor_alcoves`' talker, 1 m
//! from an alcove's side wall, that way from four stops, and a source stood in the
//! alcove's corner. A ray is such a blend of a mapped source when it lies between the
//! source's bearing and its image's, more than a `sigma` from each (nearer, it is the
//! source's own DoA or a plain reflection), the map shows the source to the stop and the
//! wall where the reflection meets it, and the source that took the ray stands no farther
//! from that wall than the mapped one.
//!
//! A source whose rays are, all but one, another's reflections or blends or its direct
//! bearing, or come from stops the map hides the source from (no direct sound of it can
//! reach them), as many reflections and blends as a source needs stops and half of its
//! rays or more, is removed, provided that other source is not itself explained so (two
//! sources explaining each other are both kept: the rule does not choose).
//!
//! A source's own rays can be its blends or its image in a wall near it too: see [`own`].

use super::rules::principal_axis;
use super::*;
use std::cell::OnceCell;

mod own;

/// How far around the point where a DoA's ray meets a wall the wall's cells are taken to
/// say which way it runs (m): twice a wall's thickness on a map, short enough that a
/// corner's other wall is not in it from most points.
const WALL_REACH_M: f64 = 0.3;

/// How elongated that stretch of cells must be (the ratio of the spreads along and across
/// its principal axis): at a corner the cells turn, and no one line mirrors. A wall 0.15 m
/// thick seen over 0.6 m has 4; two walls meeting at a right angle near 1.
const WALL_ELONGATION: f64 = 2.5;

/// The most reflections a DoA's ray is traced through: the first order, one wall, from
/// every stop. Why not the second (two walls, as at a corner or across an alcove): on the
/// drawn scenes, DoAs lie at second-order images no more often than chance, from stops
/// that see the source and from stops the map hides it from alike, where first-order
/// images are heard twice as often as chance (`scripts/doas_at_images.py`, decision
/// 0019). Traced to the second order towards hidden sources, the rule moved 1-3 of 48
/// drawn scenes within their spread and no held-out scene; it was written for
/// `corridor_alcoves`' alcove talker, heard from the corridor's first stops 2-4 degrees
/// from its second-order image, whose ghost at the alcove's mouth it explained away
/// (GCC-PHAT worst map 0.431 -> 0.288 m). And second-order images are many and lie by
/// chance within the gate of real sources' bearings (`sparse_ten`, ten talkers: the
/// right count 100 -> 93 % with GCC-PHAT when every stop traced them).
const MAX_ORDER: usize = 1;

/// One leg of a DoA's ray traced through the map's walls, after one reflection or more.
#[derive(Clone, Copy, Debug)]
struct Leg {
    /// Where it leaves the wall it was reflected by (m).
    from: [f64; 2],
    /// Its direction (unit).
    dir: [f64; 2],
    /// The path's length from the stop to `from` (m).
    before: f64,
    /// Its own length, to the next wall or the map's end (m).
    len: f64,
}

/// The widest angle at a stop between a source and its image in a wall that the SSL is
/// taken to hear as one peak between them (a blend, [`Mapper::blends`]): rad. Why 60
/// degrees: a robot's array is small against speech's wavelengths, and two coherent
/// arrivals closer than its main lobe's half-width merge into one peak, placed between
/// them by their strengths and phases. The paper's array (0.235 m) has a main lobe 60
/// degrees from peak to first null at 2 kHz (asin(1.22 lambda / D)), wider below; in
/// `corridor_alcoves` MVDR hears the talker 1 m from an alcove's side wall, 26-42 degrees
/// from its image, as one peak half-way between them from four stops.
const BLEND_WEDGE: f64 = std::f64::consts::FRAC_PI_3;

/// The longest reflected path, against the direct path, of a reflection that blends with
/// its direct sound ([`Mapper::blends`]): twice, the image within 6 dB of the direct sound
/// before the wall takes its share. A weaker reflection moves the peak of the two by
/// little, and a source far from its wall (a ghost in the corridor, a wall 1.8 m behind
/// it) has no blend of it between itself and the wall.
const BLEND_PATH_RATIO: f64 = 2.0;

/// A wall a source is mirrored in: the source's image, a point of the wall, and the
/// wall's unit normal towards the source.
#[derive(Clone, Copy, Debug)]
struct Mirror {
    image: [f64; 2],
    wall: [f64; 2],
    normal: [f64; 2],
}

impl Mirror {
    /// A source at `s` mirrored in the wall through `wall` whose unit normal, towards
    /// `s`, is `normal`.
    fn of(s: [f64; 2], wall: [f64; 2], normal: [f64; 2]) -> Self {
        let mut m = Mirror {
            image: s,
            wall,
            normal,
        };
        m.image = m.reflect(s);
        m
    }

    /// The point `q` mirrored in the wall.
    fn reflect(&self, q: [f64; 2]) -> [f64; 2] {
        let off = self.off(q);
        [
            q[0] - 2.0 * off * self.normal[0],
            q[1] - 2.0 * off * self.normal[1],
        ]
    }

    /// How far `q` stands from the wall, on the source's side (m).
    fn off(&self, q: [f64; 2]) -> f64 {
        (q[0] - self.wall[0]) * self.normal[0] + (q[1] - self.wall[1]) * self.normal[1]
    }
}

/// How many directions around a source are searched for the walls it is mirrored in
/// ([`Mapper::mirrors`]): every 10 degrees, so that a wall 2 m long seen from 3 m away
/// is met by two of them or more.
const MIRROR_DIRECTIONS: usize = 36;

/// How far from a source its walls are searched for (m): a room's half-width (as the
/// search margin without a map, `--open-margin`). A wall farther off mirrors the source
/// more than 6 m behind it, and its reflection reaches the stops with the reverberation,
/// not as a peak beside the direct sound.
const MIRROR_REACH_M: f64 = 3.0;

impl Leg {
    /// The angle at the stop between the ray and a source at `s` mirrored through the
    /// leg's walls (its image), where `s` lies along this leg; `None` elsewhere.
    fn miss(&self, s: [f64; 2], slack: f64) -> Option<f64> {
        let v = [s[0] - self.from[0], s[1] - self.from[1]];
        let along = v[0] * self.dir[0] + v[1] * self.dir[1];
        let across = (v[0] * self.dir[1] - v[1] * self.dir[0]).abs();
        (0.0..=self.len + slack)
            .contains(&along)
            .then(|| across.atan2(self.before + along))
    }
}

impl Mapper {
    /// The legs of ray `r` after each of its first `max_order` specular reflections in
    /// the map's walls (a wall's direction from its cells around the point hit, or where a
    /// corner's other wall is among them, from those along the line through it,
    /// [`line_through`]; the trace ends at a corner itself, where no one line mirrors, or
    /// where it leaves the map).
    fn reflected_legs(&self, r: &Ray, max_order: usize) -> Vec<Leg> {
        let (x0, x1, y0, y1) = self.bounds;
        let far = 2.0 * (x1 - x0).hypot(y1 - y0);
        let step_off = 2.0 * self.map.resolution();
        let (mut from, mut dir, mut before) = (r.from, [r.bearing.cos(), r.bearing.sin()], 0.0);
        let mut legs = Vec::with_capacity(max_order);
        for order in 0..=max_order {
            let end = [from[0] + far * dir[0], from[1] + far * dir[1]];
            let hit = self.map.first_occupied(from, end);
            let len = hit.map_or(far, |h| (h[0] - from[0]).hypot(h[1] - from[1]));
            if order > 0 {
                legs.push(Leg {
                    from,
                    dir,
                    before,
                    len,
                });
            }
            let Some(hit) = hit.filter(|_| order < max_order) else {
                break;
            };
            // The normal of the wall at the point hit, towards the side the ray came from
            // (beside a corner, of the line through it).
            let Some(normal) = self.wall_normal(hit, [-dir[0], -dir[1]], true) else {
                break;
            };
            dir = reflect_direction(dir, normal);
            before += len;
            from = [hit[0] + step_off * normal[0], hit[1] + step_off * normal[1]];
        }
        legs
    }

    /// The unit normal of the wall met at `hit` (the line of its cells within
    /// [`WALL_REACH_M`]), on the side `towards` points to; `None` where the cells do not
    /// run along one line (a corner), unless `beside_corner` asks for the line through
    /// `hit` there ([`line_through`]), as a traced ray takes it. Why not for the walls
    /// around a source ([`Mapper::mirrors`]): they are searched from many directions, and
    /// each is found where its cells run along one line; taken beside corners too,
    /// `notched_hall_respeaker6`'s talker 0.4 m from two walls was mapped further off with
    /// MVDR (0.48 -> 0.52 m).
    fn wall_normal(
        &self,
        hit: [f64; 2],
        towards: [f64; 2],
        beside_corner: bool,
    ) -> Option<[f64; 2]> {
        let cells = self.map.occupied_within(hit, WALL_REACH_M);
        let n = line_normal(&cells).or_else(|| {
            beside_corner
                .then(|| line_through(hit, &cells, self.map.resolution()))
                .flatten()
        })?;
        Some(facing(n, towards))
    }

    /// The walls around `s` that mirror it: the first wall met in each of
    /// [`MIRROR_DIRECTIONS`] directions within [`MIRROR_REACH_M`], its line from its
    /// cells around the point met (as [`Mapper::reflected_legs`] takes it), each line once.
    fn mirrors(&self, s: [f64; 2]) -> Vec<Mirror> {
        let mut out: Vec<Mirror> = Vec::new();
        let same_line = 10f64.to_radians().cos();
        for k in 0..MIRROR_DIRECTIONS {
            let a = std::f64::consts::TAU * k as f64 / MIRROR_DIRECTIONS as f64;
            let end = [
                s[0] + MIRROR_REACH_M * a.cos(),
                s[1] + MIRROR_REACH_M * a.sin(),
            ];
            let Some(wall) = self.map.first_occupied(s, end) else {
                continue;
            };
            let towards = [s[0] - wall[0], s[1] - wall[1]];
            let Some(normal) = self.wall_normal(wall, towards, false) else {
                continue;
            };
            let mirror = Mirror::of(s, wall, normal);
            let off = mirror.off(s);
            // One line once: the wall met nearest the source, where the cells around it
            // are the farthest from the wall's ends.
            let near = |m: &Mirror| (m.wall[0] - s[0]).hypot(m.wall[1] - s[1]);
            match out.iter_mut().find(|m| {
                m.normal[0] * normal[0] + m.normal[1] * normal[1] > same_line
                    && (m.off(s) - off).abs() <= WALL_REACH_M / 2.0
            }) {
                Some(m) if near(&mirror) < near(m) => *m = mirror,
                Some(_) => {}
                None => out.push(mirror),
            }
        }
        out
    }

    /// The bearings from `from` of a source at `s` and of its image in `m`'s wall (rad),
    /// and where the reflection meets the wall's line, where a stop there may hear the
    /// image beside the source: on the room's side of the wall, the image within
    /// [`BLEND_WEDGE`] of the source and its path at most [`BLEND_PATH_RATIO`] times the
    /// direct one. Whether the wall is there is [`Mapper::on_wall`]'s to say.
    fn image_beside(m: &Mirror, from: [f64; 2], s: [f64; 2]) -> Option<(f64, f64, [f64; 2])> {
        let (to_s, to_p) = (m.off(s), m.off(from));
        if to_s <= 0.0 || to_p <= 0.0 {
            return None;
        }
        let bearing = |q: [f64; 2]| (q[1] - from[1]).atan2(q[0] - from[0]);
        let dist = |q: [f64; 2]| (q[0] - from[0]).hypot(q[1] - from[1]);
        let (direct, mirrored) = (bearing(s), bearing(m.image));
        let t = to_p / (to_p + to_s);
        let at = [
            from[0] + t * (m.image[0] - from[0]),
            from[1] + t * (m.image[1] - from[1]),
        ];
        (wrap_rad(mirrored - direct).abs() <= BLEND_WEDGE
            && dist(m.image) <= BLEND_PATH_RATIO * dist(s))
        .then_some((direct, mirrored, at))
    }

    /// Whether the map holds a wall at `at` (within half [`WALL_REACH_M`]).
    fn on_wall(&self, at: [f64; 2]) -> bool {
        !self.map.occupied_within(at, WALL_REACH_M / 2.0).is_empty()
    }

    /// Whether ray `r` is heard between a source at `s` and its image in `m`'s wall, as
    /// one peak of both ([`BLEND_WEDGE`], [`BLEND_PATH_RATIO`]), by a stop on the room's
    /// side of that wall with the point of reflection on it, and a source at `g` that took
    /// the ray no farther from the wall than `s`: rays that blend a source's direct sound
    /// with its reflection point between them, and cross near the wall. The angle at the
    /// stop between the source and its image (rad) when it is; `None` otherwise.
    fn blends(&self, m: &Mirror, r: &Ray, s: [f64; 2], g: [f64; 2]) -> Option<f64> {
        if m.off(g) > m.off(s) {
            return None;
        }
        let (direct, mirrored, at) = Self::image_beside(m, r.from, s)?;
        let wedge = wrap_rad(mirrored - direct).abs();
        (wrap_rad(r.bearing - mirrored).abs() > self.sigma
            && wrap_rad(r.bearing - direct).abs() + wrap_rad(r.bearing - mirrored).abs()
                <= wedge + 1e-9
            && self.on_wall(at))
        .then_some(wedge)
    }

    /// Whether ray `r`, taken by a source at `g`, blends a source at `s` with its image in
    /// one of the walls `mirrors` gives ([`Mapper::blends`]), missing `s` by more than a
    /// `sigma` and within [`BLEND_WEDGE`], from a stop the map shows `s` to: the narrowest
    /// angle between `s` and such an image (rad), or `None`. The walls are asked for only
    /// once the miss and the sight tell nothing against a blend.
    fn blend_of<'m>(
        &self,
        r: &Ray,
        s: [f64; 2],
        g: [f64; 2],
        mirrors: impl FnOnce() -> &'m [Mirror],
    ) -> Option<f64> {
        let miss = r.miss(s);
        if miss <= self.sigma || miss > BLEND_WEDGE || !self.sees(r.from, s) {
            return None;
        }
        mirrors()
            .iter()
            .filter_map(|m| self.blends(m, r, s, g))
            .min_by(f64::total_cmp)
    }

    /// Whether the rays of `g` (their reflected legs in `legs`) are the direct sound, the
    /// reflections or the blends of `s` (its walls in `mirrors`), or come from stops the
    /// map hides `g` from: each but one, as many reflections and blends as a source needs
    /// stops ([`IasmConfig::min_observations`]) and half of them or more (see the module
    /// docs).
    fn echoes(
        &self,
        g: &Source,
        legs: &[Vec<Leg>],
        s: &Source,
        mirrors: &OnceCell<Vec<Mirror>>,
        stops: &Stops,
    ) -> bool {
        let (at, own, gate) = ([s.x, s.y], [g.x, g.y], 2.0 * self.sigma);
        let (mut direct, mut reflected, mut unexplained) = (0, 0, 0);
        let slack = self.config.room_margin_m;
        for (r, legs) in g.rays.iter().zip(legs) {
            let miss = r.miss(at);
            // A reflection, with the source's direct sound heard at its stop too, or hidden.
            let reflection = || {
                let to = stops.poses()[r.stop].bearing_to(at);
                nearest_image(legs, at, slack)
                    .is_some_and(|m| m <= gate && m <= r.miss(own) + self.sigma)
                    && (!self.sees(r.from, at)
                        || stops.heard()[r.stop]
                            .iter()
                            .any(|&h| h != r.bearing && wrap_rad(h - to).abs() <= gate))
            };
            let blend = || {
                self.blend_of(r, at, own, || mirrors.get_or_init(|| self.mirrors(at)))
                    .is_some()
            };
            if reflection() || blend() {
                reflected += 1;
            } else if miss <= gate || !self.sees(r.from, own) {
                direct += 1;
            } else {
                unexplained += 1;
                if unexplained > 1 {
                    return false;
                }
            }
        }
        let n = g.rays.len();
        reflected >= self.config.min_observations.max(2)
            && 2 * reflected >= n
            && direct + reflected + 1 >= n
    }

    /// Marks in `why` ([`Refusal::Reflection`]) the sources still standing (no reason
    /// yet) whose rays are another standing source's reflections ([`Mapper::echoes`]),
    /// that other source not itself explained so; whether any was marked. Nothing on a
    /// map without walls, or with [`IasmConfig::reflections`] off.
    pub(super) fn heard_by_reflection(
        &self,
        sources: &[Source],
        stops: &Stops,
        why: &mut [Option<Refusal>],
    ) -> bool {
        if !self.config.reflections || !self.surveyed {
            return false;
        }
        let standing: Vec<usize> = (0..sources.len()).filter(|&i| why[i].is_none()).collect();
        // Each standing source's walls, found when a ray first needs them.
        let mirrors: Vec<OnceCell<Vec<Mirror>>> =
            standing.iter().map(|_| OnceCell::new()).collect();
        // For each standing source, the standing sources whose reflections it is.
        let of: Vec<Vec<usize>> = standing
            .iter()
            .map(|&i| {
                let g = &sources[i];
                let legs: Vec<Vec<Leg>> = (g.rays.iter())
                    .map(|r| self.reflected_legs(r, MAX_ORDER))
                    .collect();
                (0..standing.len())
                    .filter(|&k| {
                        let j = standing[k];
                        j != i && self.echoes(g, &legs, &sources[j], &mirrors[k], stops)
                    })
                    .collect()
            })
            .collect();
        let mut marked = false;
        for (k, sources_of) in of.iter().enumerate() {
            if sources_of.iter().any(|&m| of[m].is_empty()) {
                why[standing[k]] = Some(Refusal::Reflection);
                marked = true;
            }
        }
        marked
    }
}

/// The direction `dir` reflected specularly by a wall whose unit normal is `normal`.
fn reflect_direction(dir: [f64; 2], normal: [f64; 2]) -> [f64; 2] {
    let dot = dir[0] * normal[0] + dir[1] * normal[1];
    [
        dir[0] - 2.0 * dot * normal[0],
        dir[1] - 2.0 * dot * normal[1],
    ]
}

/// The least angle at the stop between a ray and the image of a source at `s` along one
/// of the ray's reflected `legs` (see [`Leg::miss`]); `None` when none passes it.
fn nearest_image<'a>(
    legs: impl IntoIterator<Item = &'a Leg>,
    s: [f64; 2],
    slack: f64,
) -> Option<f64> {
    legs.into_iter()
        .filter_map(|leg| leg.miss(s, slack))
        .min_by(f64::total_cmp)
}

/// The unit normal of the line through `cells` (their principal axis); `None` when they
/// do not run along one line ([`WALL_ELONGATION`]) or are too few to say.
fn line_normal(cells: &[[f64; 2]]) -> Option<[f64; 2]> {
    if cells.len() < 3 {
        return None;
    }
    let axis = principal_axis(cells);
    (axis.along >= WALL_ELONGATION.powi(2) * axis.across)
        .then(|| [-axis.angle.sin(), axis.angle.cos()])
}

/// The unit normal `n` or its opposite, whichever points to the side `towards` points to.
fn facing(n: [f64; 2], towards: [f64; 2]) -> [f64; 2] {
    if n[0] * towards[0] + n[1] * towards[1] < 0.0 {
        [-n[0], -n[1]]
    } else {
        n
    }
}

/// How finely [`line_through`] turns its line through the point hit: every 2 degrees,
/// then refined by the cells along it.
const LINE_STEPS: usize = 90;

/// The unit normal of the wall through `hit`, one of `cells` (those within
/// [`WALL_REACH_M`], each `res` m wide), where their principal axis says none
/// ([`line_normal`]: a corner's other wall among them): of the lines through `hit`, the one
/// that the most cells lie along, within a cell of it, where it holds [`WALL_ELONGATION`]
/// times as many as the line across it, its direction refined by those cells' principal
/// axis. `None` at a corner itself, where both walls' lines through `hit` hold alike. A ray
/// that meets `corridor_alcoves`' alcove wall 0.2 m from the corridor's wall is reflected
/// by it, where the trace ended before.
/// Why only where the principal axis says none: taken for every point hit, it mapped the
/// corridor alike (0.098 m) and a held-out corner talker better, but the thick walls of a
/// map (a wall 0.2 m thick, four cells) hold as many cells across the line through `hit`
/// as along it within a cell, and the trace of `mapper::tests::mirror` ended at a plain
/// wall. Where a corner's other wall is near
/// enough to turn the principal axis but not to break it (the alcove of this module's
/// tests: 8 degrees 0.1 m from the corner, a reflection 16 degrees off), that axis stands.
fn line_through(hit: [f64; 2], cells: &[[f64; 2]], res: f64) -> Option<[f64; 2]> {
    let normal = |k: usize| {
        let a = std::f64::consts::PI * k as f64 / LINE_STEPS as f64;
        [-a.sin(), a.cos()]
    };
    // The cells whose centres lie within a cell of the line through `hit` whose normal is
    // `n`.
    let on = |n: [f64; 2]| {
        let off = move |c: &&[f64; 2]| ((c[0] - hit[0]) * n[0] + (c[1] - hit[1]) * n[1]).abs();
        cells.iter().filter(move |c| off(c) <= res)
    };
    let counts: Vec<usize> = (0..LINE_STEPS).map(|k| on(normal(k)).count()).collect();
    let best = (0..LINE_STEPS).max_by_key(|&k| counts[k])?;
    let across = counts[(best + LINE_STEPS / 2) % LINE_STEPS].max(1);
    if (counts[best] as f64) < WALL_ELONGATION * across as f64 {
        return None;
    }
    // The line's own cells say which way it runs between the steps.
    let n = normal(best);
    let wall: Vec<[f64; 2]> = on(n).copied().collect();
    Some(line_normal(&wall).unwrap_or(n))
}

#[cfg(test)]
mod tests;
