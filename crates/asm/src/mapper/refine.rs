//! Refinement: bearing least squares with trimmed rays, the fits' helpers, and merging.

use super::*;

/// Moves `s` to `p`, fitted to `rays`, which it now explains (in stop order, as the
/// rounds' association leaves them).
pub(super) fn settle(s: &mut Source, p: [f64; 2], mut rays: Vec<Ray>) {
    rays.sort_by_key(|r| r.stop);
    (s.x, s.y, s.refined) = (p[0], p[1], true);
    s.observations = rays.len();
    s.rays = rays;
}

/// [`fit_bearings`] from `start`, with the rays the fit drops taken out of `rays` and
/// given back to `bearings` (they belong to something else); the fitted position, or
/// `None` (and `rays` untouched) when there is no fit.
pub(crate) fn refit(
    start: [f64; 2],
    rays: &mut Vec<Ray>,
    sigma: f64,
    trim: Trim,
    bearings: &mut [Vec<f64>],
) -> Option<[f64; 2]> {
    let (p, kept) = fit_bearings(start, rays, sigma, trim)?;
    let mut keep = vec![false; rays.len()];
    kept.iter().for_each(|&i| keep[i] = true);
    let mut k = keep.iter();
    rays.retain(|r| {
        let kept = *k.next().expect("one flag per ray");
        if !kept {
            r.give_back(bearings);
        }
        kept
    });
    Some(p)
}

/// A DoA that misses the bearing to a source by this many `sigma` or more, and another
/// mapped source's by less than one `sigma`, is that other source's: it does not excuse
/// its stop's silence towards the first (`Mapper::absences`).
///
/// Why: within `gamma` (15 degrees) of a ghost's bearing there is often a real source's
/// DoA, from every stop that sees both in similar directions. The ghost of
/// `speech_two_rt05` (GCC-PHAT, third rendering, one draw in ten: a source 0.75 m off
/// the path, between it and a talker, made by the vote of five stops' reflections) was
/// excused by four stops that heard only the talker, each DoA 0.5-2.4 degrees from the
/// talker and 8-13 from the ghost. Why 1.5 and 1: a DoA 1.5 `sigma` from a source is an
/// unlikely draw of it (one in seven) where the other source's is likely; a second source
/// heard in the same peak (one behind the other) is what [`IasmConfig::share_gate_sigmas`]
/// keeps, and fits within half a `sigma`. Measured: the
/// suite (3 renderings x 10 draws), `speech_two_rt05` GCC-PHAT 0.093 -> 0.061 m (90 ->
/// 100 % of maps with two sources); `fixtures/heldout`, `sparse_eight_speech` MVDR 0.268
/// -> 0.275 (one map of 30 finds 5 of 8); over 20 draws on each of three other renderings
/// of every scene of both, `speech_two_snr15` GCC-PHAT 98 -> 100 % right count and
/// nothing else moved; arrangement II (50 runs, ours and the authors' tables) unchanged.
/// Stricter (2 and 0.5 `sigma`) also removes the `speech_two_rt05` ghost; a DoA that
/// fits another source better at any miss (no thresholds) loses real sources in crowds
/// (the ReSpeaker's ten rows, MVDR, 98 -> 88 % right count over those draws).
pub const TAKEN_MISS_SIGMAS: f64 = 1.5;

/// The most passes of [`Mapper::reassociate`]. Each pass moves DoAs to the sources that fit
/// them better and refits the sources, which may bring other DoAs nearer another source;
/// each DoA moves once, so the passes end, and this bound only caps the cost. Measured:
/// the suite's maps settle after at most 3 passes that move something, arrangement II's
/// (100 runs, both methods) after at most 4.
pub const REASSOCIATE_PASSES: usize = 8;

/// A source's mirror image ([`Source::mirror`]) is reported when its image rays' squared
/// misses (in units of `sigma`) sum to less than this more than the source's own: the
/// image is then at least `exp(-9 / 2)`, about 1/90, as likely under the mapper's Gaussian
/// DoA model, the three-sigma rule for one number. A robot that turns by 10 degrees
/// between the stops that hear a source moves the image rays by 20: at `sigma` = 5
/// degrees, 16 per ray.
pub const MIRROR_CHI2: f64 = 9.0;

/// The point nearest every ray's line in the least-squares sense (perpendicular
/// distances), or `None` when the lines are (nearly) parallel: a start for
/// [`fit_bearings`] where no estimate is at hand.
pub(super) fn least_squares_crossing(rays: &[Ray]) -> Option<[f64; 2]> {
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for r in rays {
        let (c, s) = (r.bearing.cos(), r.bearing.sin());
        // I - d d^T, the projection across the ray.
        let (p11, p12, p22) = (1.0 - c * c, -c * s, 1.0 - s * s);
        a11 += p11;
        a12 += p12;
        a22 += p22;
        b1 += p11 * r.from[0] + p12 * r.from[1];
        b2 += p12 * r.from[0] + p22 * r.from[1];
    }
    let det = a11 * a22 - a12 * a12;
    (det.abs() > 1e-9 * (a11 + a22).powi(2))
        .then(|| [(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det])
}

/// The position that minimises the squared wrapped angles between `rays` and the bearings
/// from their stops to it, from `start`: Gauss-Newton, dropping the worst ray and refitting
/// while a residual exceeds `2 sigma`. `None` when fewer than three rays remain, the
/// geometry is degenerate (parallel rays), or the solution leaves the neighbourhood of
/// `start` (2 m), where the particle estimate is the safer one. No [`Trim`]: every kept
/// ray moves the position ([`fit_bearings`] takes one).
pub fn refine_by_bearings(start: [f64; 2], rays: &[Ray], sigma: f64) -> Option<[f64; 2]> {
    fit_bearings(start, rays, sigma, Trim::OFF).map(|(p, _)| p)
}

/// How much of a bearing fit's spread is the source's own: kept rays that miss the fit by
/// more than `mads` robust standard deviations of the rays' misses (1.4826 times their
/// median), and by more than `floor` (rad), do not move the position (see
/// [`IasmConfig::trim_mads`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trim {
    /// The trim in robust standard deviations; 0 turns it off.
    pub mads: f64,
    /// The narrowest trim (rad).
    pub floor: f64,
}

impl Trim {
    /// No trim: every kept ray moves the position.
    pub const OFF: Trim = Trim {
        mads: 0.0,
        floor: 0.0,
    };

    /// The trim `config` sets ([`IasmConfig::trim_mads`], [`IasmConfig::trim_floor_deg`]).
    pub fn of(config: &IasmConfig) -> Self {
        Trim {
            mads: config.trim_mads,
            floor: config.trim_floor_deg.to_radians(),
        }
    }
}

/// [`refine_by_bearings`] with a [`Trim`], and the indices (into `rays`, ascending) of the
/// rays the fit kept (the trimmed ones among them).
pub fn fit_bearings(
    start: [f64; 2],
    rays: &[Ray],
    sigma: f64,
    trim: Trim,
) -> Option<([f64; 2], Vec<usize>)> {
    fit_within(start, rays, sigma, 2.0, trim)
}

/// [`fit_bearings`] with the solution allowed within `limit` (m) of `start`.
pub(super) fn fit_within(
    start: [f64; 2],
    rays: &[Ray],
    sigma: f64,
    limit: f64,
    trim: Trim,
) -> Option<([f64; 2], Vec<usize>)> {
    let solve = |kept: &[usize], from: [f64; 2]| -> Option<[f64; 2]> {
        if kept.len() < 3 {
            return None;
        }
        let mut s = from;
        for _ in 0..20 {
            let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for ray in kept.iter().map(|&i| &rays[i]) {
                let e = wrap_rad((s[1] - ray.from[1]).atan2(s[0] - ray.from[0]) - ray.bearing);
                let [jx, jy] = bearing_gradient(s, ray.from);
                a11 += jx * jx;
                a12 += jx * jy;
                a22 += jy * jy;
                b1 += jx * e;
                b2 += jy * e;
            }
            let det = a11 * a22 - a12 * a12;
            if det.abs() < 1e-12 * (a11 * a22).max(1e-300) {
                return None;
            }
            let step = [(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det];
            s = [s[0] - step[0], s[1] - step[1]];
            if step[0].hypot(step[1]) < 1e-6 {
                break;
            }
        }
        (s.iter().all(|v| v.is_finite()) && (s[0] - start[0]).hypot(s[1] - start[1]) < limit)
            .then_some(s)
    };
    // Drop the worst ray while it lies beyond 2 sigma, refitting each time: one outlier
    // cannot then drag the fit far enough to push good rays out of the gate.
    let mut kept: Vec<usize> = (0..rays.len()).collect();
    let mut s = solve(&kept, start)?;
    loop {
        let (worst, e) = kept
            .iter()
            .enumerate()
            .map(|(k, &i)| (k, rays[i].miss(s)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        if e <= 2.0 * sigma {
            return Some((trimmed(s, &kept, rays, (trim, 2.0 * sigma), solve), kept));
        }
        kept.remove(worst);
        s = solve(&kept, s)?;
    }
}

/// The fit `s` of the `kept` rays again without those [`Trim`] leaves out: judged first
/// from where most of them meet ([`unmasked`]), else from `s`, until it keeps the same
/// rays (at most three refits). `s` itself when nothing is trimmed, when
/// fewer than four rays are kept, when the trimmed fit fails, or when a kept ray misses
/// the trimmed fit by more than `gate` (the `2 sigma` that kept it): the rays left out
/// then carried the geometry (the only ones across a line of nearly collinear rays, which
/// fix the range), not an error to be rid of. Hard rejection rather than a smooth
/// M-estimator weight: a ray beyond the trim is another sound's, not a worse measurement
/// of this one.
pub(super) fn trimmed(
    s: [f64; 2],
    kept: &[usize],
    rays: &[Ray],
    (trim, gate): (Trim, f64),
    solve: impl Fn(&[usize], [f64; 2]) -> Option<[f64; 2]>,
) -> [f64; 2] {
    if trim.mads <= 0.0 || kept.len() < 4 {
        return s;
    }
    if let Some(p) = unmasked(s, kept, rays, (trim, gate), &solve) {
        return p;
    }
    let mut p = s;
    let mut misses: Vec<f64> = Vec::with_capacity(kept.len());
    for _ in 0..3 {
        misses.clear();
        misses.extend(kept.iter().map(|&i| rays[i].miss(p)));
        misses.sort_by(f64::total_cmp);
        let cut = (trim.mads * 1.4826 * misses[misses.len() / 2]).max(trim.floor);
        let inliers = within(kept, rays, p, cut);
        if inliers.len() == kept.len() {
            break;
        }
        match solve(&inliers, p) {
            Some(q) => p = q,
            None => return s,
        }
    }
    if kept.iter().all(|&i| rays[i].miss(p) <= gate) {
        p
    } else {
        s
    }
}

/// The `kept` rays that miss `at` by `cut` (rad) or less.
fn within(kept: &[usize], rays: &[Ray], at: [f64; 2], cut: f64) -> Vec<usize> {
    kept.iter()
        .copied()
        .filter(|&i| rays[i].miss(at) <= cut)
        .collect()
}

/// The trim of [`trimmed`] judged from where the median miss is least (Rousseeuw's least
/// median of squares, over the points where two of the `kept` rays cross), not from the
/// least-squares fit `s`: a few rays a reflection bent pull least squares off the rest,
/// so that every ray misses it by a little and none stands out (masking); from where most
/// rays meet, the bent ones do. `None` when no crossing has a smaller median miss than
/// `s`, or its fit is not taken (every ray let back in, the `gate` or
/// [`KEPT_INFORMATION`] not met): the trim from `s` then judges.
fn unmasked(
    s: [f64; 2],
    kept: &[usize],
    rays: &[Ray],
    (trim, gate): (Trim, f64),
    solve: &impl Fn(&[usize], [f64; 2]) -> Option<[f64; 2]>,
) -> Option<[f64; 2]> {
    // Rays that all meet the fit more closely than the DoAs can be told apart hide nothing.
    if kept.iter().all(|&i| rays[i].miss(s) <= trim.floor) {
        return None;
    }
    let mut medians = Medians::of(kept.iter().map(|&i| &rays[i]));
    let (mut at, least) = medians.least(s);
    if at == s {
        return None;
    }
    // The least median of a few misses understates their spread: Rousseeuw's small-sample
    // factor, 1 + 5 / (n - 2) for a position fitted to n rays; from the fit on, the rays'
    // own median judges, and a clean ray the first point missed by a hair is let back in.
    let mut spread = 1.4826 * (1.0 + 5.0 / (kept.len() - 2) as f64) * least;
    let mut used: Vec<usize> = Vec::new();
    let mut p = s;
    for _ in 0..3 {
        let cut = (trim.mads * spread).max(trim.floor);
        let inliers = within(kept, rays, at, cut);
        if inliers.len() == kept.len() {
            return None;
        }
        if inliers == used {
            break;
        }
        p = solve(&inliers, at)?;
        (at, used) = (p, inliers);
        spread = 1.4826 * medians.at(p);
    }
    let weakest = |set: &[usize]| weakest_information(p, set.iter().map(|&i| &rays[i]));
    (kept.iter().all(|&i| rays[i].miss(p) <= gate)
        && weakest(&used) >= KEPT_INFORMATION * weakest(kept))
    .then_some(p)
}

/// The median miss of a set of rays at a point, and the point of [`crossings`] where it
/// is least: where most of the rays meet (Rousseeuw's least median of squares).
pub(super) struct Medians {
    /// Each ray's stop and the unit vector of its bearing.
    heads: Vec<([f64; 2], [f64; 2])>,
    misses: Vec<f64>,
}

impl Medians {
    pub(super) fn of<'a>(rays: impl Iterator<Item = &'a Ray>) -> Self {
        let heads: Vec<_> = rays
            .map(|r| (r.from, [r.bearing.cos(), r.bearing.sin()]))
            .collect();
        let misses = Vec::with_capacity(heads.len());
        Medians { heads, misses }
    }

    /// The rays' median miss at `q` (rad; the upper median of an even count).
    pub(super) fn at(&mut self, q: [f64; 2]) -> f64 {
        median_miss(&self.heads, &mut self.misses, q)
    }

    /// Of `s` and the points where two of the rays cross, the one with the least median
    /// miss, and that miss (rad): `s` unless a crossing has a smaller one.
    pub(super) fn least(&mut self, s: [f64; 2]) -> ([f64; 2], f64) {
        self.least_where(s, |_| true)
    }

    /// [`Medians::least`] over the points `keep` allows (`s` too only if it allows it):
    /// `s` and an infinite miss when it allows none.
    pub(super) fn least_where(
        &mut self,
        s: [f64; 2],
        keep: impl Fn([f64; 2]) -> bool,
    ) -> ([f64; 2], f64) {
        let (mut at, mut least) = (s, if keep(s) { self.at(s) } else { f64::INFINITY });
        for q in crossings(&self.heads).filter(|&q| keep(q)) {
            let m = median_miss(&self.heads, &mut self.misses, q);
            if m < least {
                (at, least) = (q, m);
            }
        }
        (at, least)
    }
}

/// [`Medians::at`], by 1 - cos of each miss (as the misses order, with no arctangent per
/// ray and point), turned into an angle once; `misses` is scratch.
fn median_miss(heads: &[([f64; 2], [f64; 2])], misses: &mut Vec<f64>, q: [f64; 2]) -> f64 {
    misses.clear();
    misses.extend(heads.iter().map(|(from, d)| {
        let v = [q[0] - from[0], q[1] - from[1]];
        let norm = v[0].hypot(v[1]).max(1e-12);
        1.0 - (d[0] * v[0] + d[1] * v[1]) / norm
    }));
    let half = misses.len() / 2;
    let one_less_cos = *misses.select_nth_unstable_by(half, f64::total_cmp).1;
    (1.0 - one_less_cos).clamp(-1.0, 1.0).acos()
}

/// A trimmed fit must keep this share of the information that all the source's rays give
/// on its position in the direction they fix worst (the least eigenvalue of the sum of
/// the bearings' gradients' outer products): its standard deviation there may grow by
/// at most 1 / sqrt(1/2), 41 %. Rays that agree closely because their stops lie on one
/// line towards the source say nothing about its range; the few from elsewhere that fix
/// it are not to be trimmed as the ones that disagree.
pub(super) const KEPT_INFORMATION: f64 = 0.5;

/// The least eigenvalue of the Fisher information (up to the DoA variance) that `rays`
/// give on a source at `p` (1/m^2).
pub(super) fn weakest_information<'a>(p: [f64; 2], rays: impl Iterator<Item = &'a Ray>) -> f64 {
    let [a11, a12, a22] = information(p, rays);
    let (mean, half) = ((a11 + a22) / 2.0, ((a11 - a22) / 2.0).hypot(a12));
    mean - half
}

/// The Fisher information (up to the DoA variance) that `rays` give on a source at `p`:
/// the sum of their bearings' gradients' outer products, as its entries `[xx, xy, yy]`
/// (1/m^2).
fn information<'a>(p: [f64; 2], rays: impl Iterator<Item = &'a Ray>) -> [f64; 3] {
    rays.fold([0.0; 3], |[a11, a12, a22], r| {
        let [jx, jy] = bearing_gradient(p, r.from);
        [a11 + jx * jx, a12 + jx * jy, a22 + jy * jy]
    })
}

/// The covariance (m^2) of a position at `p` fitted to `rays` whose DoAs err by `sigma`
/// (rad): the inverse of their Fisher information, `sigma^2 (sum g g^T)^-1` with `g` each
/// bearing's gradient (the Cramer-Rao bound of the bearing fit). `None` when the rays fix
/// no position (parallel lines, or fewer than two).
pub(super) fn bearing_covariance(p: [f64; 2], rays: &[Ray], sigma: f64) -> Option<[[f64; 2]; 2]> {
    let [a11, a12, a22] = information(p, rays.iter());
    let det = a11 * a22 - a12 * a12;
    let s2 = sigma * sigma;
    (det > 1e-12 * (a11 + a22).powi(2) && det > 0.0).then(|| {
        [
            [s2 * a22 / det, -s2 * a12 / det],
            [-s2 * a12 / det, s2 * a11 / det],
        ]
    })
}

/// The gradient (1/m) of the bearing from `from` to `p` with respect to `p`.
fn bearing_gradient(p: [f64; 2], from: [f64; 2]) -> [f64; 2] {
    let (dx, dy) = (p[0] - from[0], p[1] - from[1]);
    let d2 = (dx * dx + dy * dy).max(1e-6);
    [-dy / d2, dx / d2]
}

/// Up to this many rays, every pair's crossing is a candidate of [`unmasked`].
const ALL_PAIRS: usize = 12;

/// Where pairs of the rays `heads` (each a stop and the unit vector of its bearing) cross
/// ahead of both stops, at an angle whose sine is 0.001 or more: the candidates of the
/// least median of the misses. Every pair up to 12 rays; beyond, each ray with four
/// others, from its neighbours' stops to those half the run away (the subsets of
/// Rousseeuw's estimator need not be all: one pair of clean rays is enough), so that the
/// cost stays linear.
fn crossings(heads: &[([f64; 2], [f64; 2])]) -> impl Iterator<Item = [f64; 2]> + '_ {
    let n = heads.len();
    let offsets: Vec<usize> = if n <= ALL_PAIRS {
        (1..n).collect()
    } else {
        (1..=4).map(|k| k * n / 9).collect()
    };
    (0..n)
        .flat_map(move |i| offsets.clone().into_iter().map(move |d| (i, (i + d) % n)))
        .filter(move |&(i, j)| n > ALL_PAIRS || i < j)
        .filter_map(|(i, j)| crossing_of(heads[i], heads[j], 1e-3))
        .filter(|&(_, t, u)| t > 0.0 && u > 0.0)
        .map(|(q, _, _)| q)
}

/// Repeatedly merges the closest pair of sources nearer than `dist` into their mean;
/// returns the indices of the sources that absorbed others.
pub(crate) fn merge_close(sources: &mut Vec<Source>, dist: f64) -> Vec<usize> {
    let mut merged: Vec<usize> = Vec::new();
    loop {
        let mut best: Option<(usize, usize, f64)> = None;
        for i in 0..sources.len() {
            for j in i + 1..sources.len() {
                let d = (sources[i].x - sources[j].x).hypot(sources[i].y - sources[j].y);
                if d < dist && best.is_none_or(|b| d < b.2) {
                    best = Some((i, j, d));
                }
            }
        }
        let Some((i, j, _)) = best else {
            return merged;
        };
        // Indices past j move down by one.
        merged.retain(|&m| m != j);
        merged.iter_mut().filter(|m| **m > j).for_each(|m| *m -= 1);
        if !merged.contains(&i) {
            merged.push(i);
        }
        let b = sources.remove(j);
        let a = &mut sources[i];
        a.x = 0.5 * (a.x + b.x);
        a.y = 0.5 * (a.y + b.y);
        a.observations += b.observations;
        a.particles += b.particles;
        a.cluster.extend(b.cluster);
        a.rays.extend(b.rays);
        a.covariance = covariance(&a.cluster);
    }
}
