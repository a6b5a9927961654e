//! A source's own reflections ([`IasmConfig::reflections`]): its blends with its image in
//! a wall near it, and its image heard instead of its direct sound, place it where its
//! direct sound is heard.
//!
//! A source's rays can be blends of its direct sound and its image in a wall near it:
//! from the stops that see it with its image close beside, its peak is pulled
//! towards the image, and the bearing fit of all its rays towards the wall (MVDR hears
//! `l_wing`'s wing talker, 0.8 m from the wing's east wall, 7-9 degrees towards its image
//! from two stops of six, and mapped it 1 m off, in the wing's corner). The robust trim
//! cannot see it: a ray within the gate, it pulls the fit until it misses it by no more
//! than the others. Where most of a source's rays meet in the room
//! ([`Medians::least_where`]), the blends stand out as rays between the source and its
//! image; the source then stands where its other rays meet ([`Mapper::unblended`]), if
//! that explains all its rays better under the mapper's DoA model ([`Mapper::cost`]: a
//! blend is taken as a peak anywhere between the source and its image) and the rays kept
//! still fix the position ([`KEPT_INFORMATION`]). Why in the room: a source heard from
//! stops in a line towards it has nearly parallel blends, which meet each other far off,
//! and from there, beyond the walls, no ray lies between the source and its image
//! (`l_wing`'s wing talker heard with MVDR at N = 4: three blends and a ray 3 degrees off
//! meet beyond the wing's corner, and the talker stood in that corner, 1.1 m off).
//!
//! A stop the map hides a source from cannot hear its direct sound: from where its rays
//! meet, such a stop's ray that misses it beyond the gate and passes one of its images
//! nearer is that image, and is left out of the fit as the blends are (within the gate it
//! is still taken as the direct sound, which a corner the map's raster rounds lets by).
//! `corridor_alcoves`' first alcove talker is heard with MVDR from the stop just past the
//! alcove's east corner at its image in the west wall, 12 degrees off; with a blend from
//! the stop before, its bearing fit stood 0.2 m off, and 0.04 m without them.
//!
//! And a source can be heard from some stops by its image instead of its direct sound:
//! two coherent arrivals closer than the array's main lobe make one apparent direction,
//! between them or beyond by their relative phase at each frequency (radar's glint), and
//! it often stands at the image. `corridor_alcoves`' second alcove talker, 0.4 m from the
//! alcove's back wall, is heard at its image, 7-10 degrees beside it, from four stops of
//! seven by both methods, even with the floor's reflection taken away; its bearing fit
//! stood 0.3 m towards the wall. For each wall near where most of a source's rays meet
//! (where they meet behind a wall, the source is that point's mirror in it), the rays that
//! pass the source's image nearer than the source are unfolded in the wall (the stop and
//! the ray mirrored: a ray through the image then passes the source) and fitted with the
//! others, again from that fit until those rays settle ([`Mapper::image_fit`]). The
//! source moves there ([`Mapper::imaged`]) when that explains its rays better by the
//! Bayesian information criterion with the DoA error unknown, `n ln(RSS / RSS_0) + k ln
//! n < 0` over its `n` rays, `k` of them taken as the image (each such choice one more
//! parameter: with five to eight rays, choosing freely between two bearings per ray fits
//! the noise), and moves it away from the wall at least as far as along it (an image
//! pulls the rays towards its wall, not along it).
//!
//! A source's image is heard from stops that gave it no DoA, too: the source missed
//! those stops' image DoAs by more than the gate where the rounds left it, and no other
//! source took them (`corridor_alcoves`' second alcove talker, mapped by the vote from
//! five DoAs, is heard at its image in the back wall from a sixth stop whose DoA stays
//! unexplained; the T-junction's west talker, 0.6 m from the crossbar's north wall, from
//! two). So the DoAs no source explains, at stops where the source has none, that pass
//! its image nearer than itself and within the gate (from where its rays meet) join the
//! fit as image rays. Under the rule against, each is another sound's, a miss at the gate
//! in `RSS_0`; each one taken is a choice in `k`, as a source's own image rays are. A DoA
//! so taken is the source's own from then on.

use super::*;
use crate::mapper::refine::{KEPT_INFORMATION, Medians, weakest_information};

/// What a source's ray is when not its direct sound ([`Mapper::cost`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Aside {
    /// One peak of its direct sound and its image in a wall near it.
    Blend,
    /// Its image, heard from a stop the map hides it from.
    Image,
    /// Another sound's, heard from a stop the map hides it from.
    Other,
}

/// Where [`Mapper::unblended`] places a source, and the stops of its blends and images.
type Unblended = ([f64; 2], Vec<usize>, Vec<usize>);

/// How many times a source heard by its image is refitted, each time with the rays that
/// pass its image nearer than itself from where the last fit stands
/// ([`Mapper::image_fit`]): the rays so taken settle in one or two.
const IMAGE_FIT_ROUNDS: usize = 4;

impl Mirror {
    /// Ray `r` unfolded in the wall: from its stop's image along its reflected bearing.
    /// A ray that points at a source's image points from the stop's image at the source.
    fn unfold(&self, r: &Ray) -> Ray {
        let [x, y] = reflect_direction([r.bearing.cos(), r.bearing.sin()], self.normal);
        Ray {
            from: self.reflect(r.from),
            bearing: y.atan2(x),
            ..*r
        }
    }
}

impl Mapper {
    /// Each refined source with four rays or more placed where its direct sound is heard,
    /// its rays judged from where most of them meet ([`Medians::least`]): moved to the fit of
    /// its other rays where some of its own rays blend its direct sound with its image in
    /// a wall near it, judged from where most meet in a free cell of the map
    /// ([`Mapper::unblended`]), or else to where its direct rays and those
    /// that are its image, unfolded in the wall, meet ([`Mapper::imaged`]). Nothing on a
    /// map without walls, or with [`IasmConfig::reflections`] or [`IasmConfig::refine`]
    /// off.
    pub(in crate::mapper) fn place_by_own_reflections(
        &self,
        sources: &mut [Source],
        stops: &Stops,
        pool: &mut [Vec<f64>],
    ) {
        if !self.config.reflections || !self.config.refine || !self.surveyed {
            return;
        }
        for s in sources
            .iter_mut()
            .filter(|s| s.refined && s.rays.len() >= 4)
        {
            // Where most of its rays meet: the image rule judges its rays from there
            // (behind a wall, that point's mirror is the source); the blends from where
            // most meet in the room, as a blend lies between the source and its image.
            let mut medians = Medians::of(s.rays.iter());
            let (at, _) = medians.least([s.x, s.y]);
            let free = |q: [f64; 2]| matches!(self.map.cell_at(q), Some(Cell::Free));
            let (in_room, _) = medians.least_where([s.x, s.y], free);
            if let Some((p, blends, images)) = self.unblended(s, in_room) {
                (s.x, s.y) = (p[0], p[1]);
                (s.blends, s.images) = (blends, images);
            } else if let Some((p, images)) = self.imaged(s, at, &self.spare_rays(s, stops, pool)) {
                (s.x, s.y) = (p[0], p[1]);
                // The spare DoAs taken as its image are its own now.
                let claimed: Vec<Ray> = (images.iter())
                    .filter(|r| !s.rays.iter().any(|o| o.stop == r.stop))
                    .copied()
                    .collect();
                for r in claimed {
                    r.take_from(pool);
                    s.rays.push(r);
                }
                s.rays.sort_by_key(|r| r.stop);
                s.observations = s.rays.len();
                s.images = images.iter().map(|r| r.stop).collect();
                s.images.sort_unstable();
            }
        }
    }

    /// Where `s` stands without the rays that blend it with its own image, or come from
    /// stops the map hides it from: the bearing fit of its other rays, from `at`, where
    /// most of its rays meet, and the stops of the blends and of the images (rays from
    /// hidden stops at its image) left out there. `None` when no ray is left out
    /// there, or the fit is not taken: a ray left out no longer so at the fit, less than
    /// [`KEPT_INFORMATION`] of the information on the position kept, or the rays explained
    /// no better than where `s` stands ([`Mapper::cost`]).
    fn unblended(&self, s: &Source, at: [f64; 2]) -> Option<Unblended> {
        let rays = &s.rays;
        let here = [s.x, s.y];
        let (_, out) = self.cost(at, rays);
        if out.iter().all(Option::is_none) {
            return None;
        }
        let own: Vec<Ray> = rays
            .iter()
            .zip(&out)
            .filter(|(_, aside)| aside.is_none())
            .map(|(r, _)| *r)
            .collect();
        let (p, _) = fit_bearings(at, &own, self.sigma, self.trim)?;
        let (cost, still) = self.cost(p, rays);
        let weakest = |set: &[Ray]| weakest_information(p, set.iter());
        (out.iter()
            .zip(&still)
            .all(|(was, is)| was.is_none() || is.is_some())
            && weakest(&own) >= KEPT_INFORMATION * weakest(rays)
            && cost < self.cost(here, rays).0)
            .then(|| {
                let stops = |kind: Aside| {
                    let of = rays.iter().zip(&out).filter(|(_, a)| **a == Some(kind));
                    of.map(|(r, _)| r.stop).collect()
                };
                (p, stops(Aside::Blend), stops(Aside::Image))
            })
    }

    /// Where `s` stands if some of its rays are its image in one wall near it, and those
    /// rays (see the module docs): of the walls around `at`, where most of its rays meet,
    /// the one whose fit ([`Mapper::image_fit`]) explains its rays best by the Bayesian
    /// information criterion, if that explains them better than where `s` stands and moves
    /// it away from the wall more than along it. `spare` are DoAs no source explains, at
    /// stops where `s` has none: those that pass its image in that wall from where its
    /// rays meet are its image too, if the fit takes them (under the rule against, each is
    /// another sound's, a miss at the gate). `None` for a source with blends
    /// ([`Mapper::unblended`] has placed it).
    fn imaged(&self, s: &Source, at: [f64; 2], spare: &[Ray]) -> Option<([f64; 2], Vec<Ray>)> {
        if !s.blends.is_empty() {
            return None;
        }
        let here = [s.x, s.y];
        let behind = !matches!(self.map.cell_at(at), Some(Cell::Free));
        let gate = 2.0 * self.sigma;
        let score = |(p, images, misses): &([f64; 2], Vec<bool>, f64),
                     wall: &Mirror,
                     rays: &[Ray]| {
            let n = rays.len() as f64;
            let k = images.iter().filter(|&&b| b).count() as f64;
            let own = s.rays.len();
            let direct = self.squared_misses(
                (rays.iter().enumerate()).map(|(i, r)| if i < own { r.miss(here) } else { gate }),
            );
            let d = [p[0] - here[0], p[1] - here[1]];
            let away = d[0] * wall.normal[0] + d[1] * wall.normal[1];
            let along = (d[0] * wall.normal[1] - d[1] * wall.normal[0]).abs();
            let bic = n * (misses / direct).ln() + k * n.ln();
            (bic < 0.0 && away >= along).then_some(bic)
        };
        self.mirrors(at)
            .into_iter()
            .filter_map(|m| {
                // Where most rays meet behind a wall, the source is that point's mirror.
                let (start, wall) = if behind {
                    let normal = [-m.normal[0], -m.normal[1]];
                    (m.image, Mirror::of(m.image, m.wall, normal))
                } else {
                    (at, m)
                };
                // The spare DoAs through the image from where the rays meet (the angle
                // first: the map is asked only for the few that pass).
                let first = Mirror::of(start, wall.wall, wall.normal);
                let mut rays = s.rays.clone();
                rays.extend(spare.iter().filter(|r| {
                    let [x, y] = [first.image[0] - r.from[0], first.image[1] - r.from[1]];
                    wrap_rad(r.bearing - y.atan2(x)).abs() < gate.min(r.miss(start))
                        && self.image_miss(&first, r, start).is_some()
                }));
                let fit = self.image_fit(&rays, s.rays.len(), start, &wall)?;
                Some((score(&fit, &wall, &rays)?, fit, rays))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, (p, images, _), rays)| {
                let taken = rays.iter().zip(&images).filter(|(_, b)| **b);
                (p, taken.map(|(r, _)| *r).collect())
            })
    }

    /// The bearing fit of `rays` from `start` with those that pass a source's image in
    /// `wall` nearer than the source itself ([`Mapper::image_miss`]) unfolded in the wall,
    /// taken again from the fit until the rays so taken no longer change
    /// ([`IMAGE_FIT_ROUNDS`] at most): the fit, which rays are images there, and their
    /// squared misses ([`Mapper::squared_misses`]; an image ray's at the image). The rays
    /// from `own` on are spare: the image's if they pass it within the gate, and left out
    /// of the fit (a miss at the gate) if not. `None` when fewer than two rays are images,
    /// or the fit leaves the room's free cells.
    fn image_fit(
        &self,
        rays: &[Ray],
        own: usize,
        start: [f64; 2],
        wall: &Mirror,
    ) -> Option<([f64; 2], Vec<bool>, f64)> {
        let gate = 2.0 * self.sigma;
        // `c` mirrored in the wall, and each ray's miss at `c`, at `c`'s image where that
        // is nearer, and whether it is (a spare ray's miss is at most the gate).
        let misses = |c: [f64; 2]| -> Option<(Mirror, Vec<(f64, bool)>)> {
            let m = Mirror::of(c, wall.wall, wall.normal);
            (m.off(c) > 0.0).then(|| {
                let v = rays
                    .iter()
                    .enumerate()
                    .map(|(i, r)| {
                        let direct = if i < own { r.miss(c) } else { gate };
                        match self.image_miss(&m, r, c) {
                            Some(image) if image < direct => (image, true),
                            _ => (direct, false),
                        }
                    })
                    .collect();
                (m, v)
            })
        };
        let images = |v: &[(f64, bool)]| v.iter().map(|x| x.1).collect::<Vec<bool>>();
        let (mut c, (mut m, mut taken)) = (start, misses(start)?);
        let mut fit = None;
        for _ in 0..IMAGE_FIT_ROUNDS {
            if taken.iter().filter(|x| x.1).count() < 2 {
                break;
            }
            let unfolded: Vec<Ray> = rays
                .iter()
                .zip(&taken)
                .enumerate()
                .filter(|(i, (_, x))| *i < own || x.1)
                .map(|(_, (r, x))| if x.1 { m.unfold(r) } else { *r })
                .collect();
            let Some((p, _)) = fit_bearings(c, &unfolded, self.sigma, self.trim) else {
                break;
            };
            let Some((at_p, there)) = misses(p) else {
                fit = None;
                break;
            };
            let settled = images(&there) == images(&taken);
            fit = (there.iter().filter(|x| x.1).count() >= 2
                && matches!(self.map.cell_at(p), Some(Cell::Free)))
            .then(|| {
                (
                    p,
                    images(&there),
                    self.squared_misses(there.iter().map(|x| x.0)),
                )
            });
            (c, m, taken) = (p, at_p, there);
            if settled {
                break;
            }
        }
        fit
    }

    /// The sum of the squared `misses` (rad), each at most the vote's gate (2 `sigma`:
    /// beyond it, another sound's), never zero.
    fn squared_misses(&self, misses: impl Iterator<Item = f64>) -> f64 {
        let gate = 2.0 * self.sigma;
        misses.map(|m| m.min(gate).powi(2)).sum::<f64>().max(1e-12)
    }

    /// The miss (rad) of ray `r` at the image of a source at `s` in `m`'s wall, where its
    /// stop may hear that image ([`Mapper::image_beside`], the point of reflection on the
    /// wall) and sees `s`.
    fn image_miss(&self, m: &Mirror, r: &Ray, s: [f64; 2]) -> Option<f64> {
        self.wall_image_miss(m, r, s)
            .filter(|_| self.sees(r.from, s))
    }

    /// The miss (rad) of ray `r` at the image of a source at `s` in `m`'s wall, where its
    /// stop may hear that image ([`Mapper::image_beside`]) and the point of reflection is
    /// on the wall, whether or not the stop sees `s`.
    fn wall_image_miss(&self, m: &Mirror, r: &Ray, s: [f64; 2]) -> Option<f64> {
        let (_, mirrored, at) = Self::image_beside(m, r.from, s)?;
        self.on_wall(at)
            .then(|| wrap_rad(r.bearing - mirrored).abs())
    }

    /// How well a source at `q` explains `rays` (-2 log-likelihood, up to a constant), and
    /// which of them it does not take as its direct sound: each ray's squared miss in
    /// `sigma`s (the mapper's Gaussian DoA model), or for a blend ([`Mapper::blends`])
    /// `2 ln(w / (sqrt(2 pi) sigma))` where that is less (a peak anywhere between the
    /// source and its image, `w` apart), at most 4 (beyond the `2 sigma` gate, another
    /// sound's). A ray from a stop the map hides `q` from that misses `q` beyond the gate
    /// and passes one of its images (the reflection meeting a wall) nearer is no direct
    /// sound of it: its squared miss at that image, an image within the gate and another
    /// sound's beyond.
    fn cost(&self, q: [f64; 2], rays: &[Ray]) -> (f64, Vec<Option<Aside>>) {
        let mirrors = self.mirrors(q);
        let uniform = (std::f64::consts::TAU.sqrt() * self.sigma).ln();
        let mut total = 0.0;
        let aside = rays
            .iter()
            .map(|r| {
                let miss = r.miss(q);
                let direct = (miss / self.sigma).powi(2);
                // From a stop the map hides `q` from, a ray beyond the gate and nearer one
                // of its images than itself is that image (within the gate, the direct
                // sound by a corner the map's raster rounds).
                let image = || {
                    (mirrors.iter())
                        .filter_map(|m| self.wall_image_miss(m, r, q))
                        .fold(f64::INFINITY, f64::min)
                };
                let hidden = miss > 2.0 * self.sigma && !self.sees(r.from, q);
                let (c, aside) = if let Some(image) = hidden.then(image).filter(|&i| i < miss) {
                    (
                        (image / self.sigma).powi(2),
                        Some(if image < 2.0 * self.sigma {
                            Aside::Image
                        } else {
                            Aside::Other
                        }),
                    )
                } else {
                    (self.blend_of(r, q, q, || &mirrors))
                        .map(|w| 2.0 * (w.ln() - uniform))
                        .filter(|&b| b < direct)
                        .map_or((direct, None), |b| (b, Some(Aside::Blend)))
                };
                total += c.min(4.0);
                aside
            })
            .collect();
        (total, aside)
    }

    /// The DoAs of `pool` (world bearings no source explains, by stop) at the stops where `s`
    /// has no ray, as rays from those stops; none for a linear array's (each has a twin).
    fn spare_rays(&self, s: &Source, stops: &Stops, pool: &[Vec<f64>]) -> Vec<Ray> {
        if self.mirror.is_some() {
            return Vec::new();
        }
        let poses = stops.poses();
        pool.iter()
            .enumerate()
            .filter(|(k, _)| !s.rays.iter().any(|r| r.stop == *k))
            .flat_map(|(k, row)| {
                row.iter().map(move |&bearing| Ray {
                    stop: k,
                    from: poses[k].position(),
                    bearing,
                    twin: None,
                    shared: false,
                })
            })
            .collect()
    }
}
