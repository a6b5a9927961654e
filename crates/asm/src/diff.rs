//! Two maps of one building compared: which sources were kept, which moved, which were
//! removed and which added.
//!
//! The two maps must be in one frame (two runs localised against one occupancy map, as
//! `iasm map` and the live node make them). Each source is a position with a covariance
//! ([`Source::covariance`](crate::Source::covariance)), and a covariance is what says
//! whether two positions are one place: the difference `d` of two estimates of one place
//! has covariance `S = Σa + Σb + 2 σ0² I`, where `σ0` ([`DiffConfig::floor_m`]) is the
//! error a map's covariance does not hold (the particle cloud of a source heard from a few
//! stops is tighter than the source's true error, and the two runs' frames agree only as
//! well as their localisation). Its squared Mahalanobis length `m² = dᵀ S⁻¹ d` is then
//! chi-square with two degrees of freedom, whose survival function is `exp(-m²/2)`: the
//! probability of a displacement at least that large were the source where it was
//! ([`Change::p_same`]).
//!
//! The comparison, in two passes, each an optimal assignment (the Hungarian algorithm of
//! [`crate::ospa::assignment`]):
//!
//! 1. **Kept**: the pairs whose `m²` is within the chi-square gate of
//!    [`DiffConfig::same_p`], matched to minimise the total `m²`.
//! 2. **Moved**: of the sources left, the pairs within [`DiffConfig::move_max_m`] of each
//!    other, matched to minimise the total distance.
//! 3. What is left of the first map was **removed**, of the second **added**.
//!
//! Kept pairs go first so that a source that stayed is never taken as another's new place.
//! A move pairs only sources of one kind when both maps say what their sources sound like
//! ([`Placed::kind`], from `iasm map --signatures`): a hum switched off and a voice
//! switched on are then removed and added. Without kinds, a source removed and another
//! added within `move_max_m` of each other cannot be told from one that moved; they are
//! reported as moved, and `move_max_m = 0` reports them as removed and added.
//!
//! Each change carries a confidence ([`Change::confidence`]): for a kept source `p_same`,
//! for a moved one `1 - p_same`, and for a removed or added one `1 - p_same` against the
//! nearest source of the other map (1 when the other map has none): how sure the
//! covariances make it that this is not the other map's source seen a little off.

use serde::{Deserialize, Serialize};

use crate::ospa::assignment;

/// A mapped source as the comparison sees it: where, how sure, and what it sounds like
/// when known.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Placed {
    /// x (m, the maps' common frame).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// The position's covariance (m²).
    pub covariance: [[f64; 2]; 2],
    /// What it sounds like (`iasm map --signatures`' kind: "speech", "tonal",
    /// "broadband"), when known: a source moves only as what it is, so a pair of two
    /// known and different kinds is never a move.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
}

impl From<&crate::Source> for Placed {
    fn from(s: &crate::Source) -> Self {
        Self {
            x: s.x,
            y: s.y,
            covariance: s.covariance,
            kind: None,
        }
    }
}

impl Placed {
    /// Whether `self` and `other` may be one source that moved: unless both kinds are
    /// known and differ.
    pub fn may_be(&self, other: &Placed) -> bool {
        match (&self.kind, &other.kind) {
            (Some(a), Some(b)) => a == b,
            _ => true,
        }
    }
}

/// How two maps are compared (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DiffConfig {
    /// Each map's position error beyond its covariance, a standard deviation per axis
    /// (m). Default 0.1 m: the mean OSPA of the suite's maps (0.07-0.1 m), which a source's
    /// covariance from a handful of stops leaves out (decision 0016).
    pub floor_m: f64,
    /// The chance of a kept source's displacement being within the gate: two positions are
    /// one place while `p_same >= 1 - same_p`. Default 0.99 (a gate of `m² <= 9.21`): in a
    /// map of ten sources that stayed, one is called moved in a tenth of comparisons.
    pub same_p: f64,
    /// The furthest a source is taken to have moved (m); beyond, it was removed and
    /// another added. Default 3.0 m: a talker who walks to another desk of the same room.
    pub move_max_m: f64,
}

impl Default for DiffConfig {
    fn default() -> Self {
        Self {
            floor_m: 0.1,
            same_p: 0.99,
            move_max_m: 3.0,
        }
    }
}

impl DiffConfig {
    /// Checks that every field is finite and in range.
    ///
    /// # Errors
    /// The first bad field, named, with its range.
    pub fn check(&self) -> Result<(), String> {
        if !(self.floor_m.is_finite() && self.floor_m >= 0.0) {
            return Err(format!("floor_m = {} must be >= 0 m", self.floor_m));
        }
        if !(self.same_p > 0.0 && self.same_p < 1.0) {
            return Err(format!("same_p = {} must lie in (0, 1)", self.same_p));
        }
        if !(self.move_max_m.is_finite() && self.move_max_m >= 0.0) {
            return Err(format!("move_max_m = {} must be >= 0 m", self.move_max_m));
        }
        Ok(())
    }

    /// The gate on `m²`: the chi-square (2 degrees of freedom) quantile of `same_p`.
    pub fn gate(&self) -> f64 {
        -2.0 * (1.0 - self.same_p).ln()
    }
}

/// What happened to a source between the two maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChangeKind {
    /// In both maps, at one place.
    Kept,
    /// In both maps, at places too far apart to be one.
    Moved,
    /// In the first map only.
    Removed,
    /// In the second map only.
    Added,
}

impl ChangeKind {
    /// Its name as the JSON writes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Kept => "kept",
            Self::Moved => "moved",
            Self::Removed => "removed",
            Self::Added => "added",
        }
    }
}

/// One source's change between the maps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Change {
    /// What happened.
    pub kind: ChangeKind,
    /// Its index in the first map (none when added).
    pub before: Option<usize>,
    /// Its index in the second map (none when removed).
    pub after: Option<usize>,
    /// The other map's source it was compared with: its partner, or for a removed or added
    /// source the nearest source of the other map (none when that map has none).
    pub nearest: Option<usize>,
    /// The distance to that source (m).
    pub distance_m: Option<f64>,
    /// The squared Mahalanobis length of that difference (see the module docs).
    pub mahalanobis2: Option<f64>,
    /// `exp(-m²/2)`: the chance of a difference at least as large between two estimates
    /// of one place (0 when the other map has no source).
    pub p_same: f64,
    /// How sure the covariances make the kind: `p_same` when kept, `1 - p_same` otherwise.
    pub confidence: f64,
}

/// The squared Mahalanobis length of `b - a` under both covariances and the floor.
pub fn mahalanobis2(a: &Placed, b: &Placed, floor_m: f64) -> f64 {
    let f = 2.0 * floor_m * floor_m;
    let s = [
        [
            a.covariance[0][0] + b.covariance[0][0] + f,
            a.covariance[0][1] + b.covariance[0][1],
        ],
        [
            a.covariance[1][0] + b.covariance[1][0],
            a.covariance[1][1] + b.covariance[1][1] + f,
        ],
    ];
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
    if !(det > 0.0 && det.is_finite()) {
        // Two points with no uncertainty: one place only if they coincide.
        return if dx == 0.0 && dy == 0.0 {
            0.0
        } else {
            f64::INFINITY
        };
    }
    // S⁻¹ = [[s11, -s01], [-s10, s00]] / det.
    (dx * (s[1][1] * dx - s[0][1] * dy) + dy * (s[0][0] * dy - s[1][0] * dx)) / det
}

fn distance(a: &Placed, b: &Placed) -> f64 {
    (b.x - a.x).hypot(b.y - a.y)
}

/// The pairs of an optimal assignment between `n` rows and `m` columns under `cost`,
/// where a pair may be made only at a cost of at most `limit` and leaving a row or a
/// column unpaired costs `limit / 2` (as OSPA's cut-off does): the least total of the
/// pairs' costs and the unpaired ones'.
fn matched(
    n: usize,
    m: usize,
    limit: f64,
    cost: impl Fn(usize, usize) -> f64,
) -> Vec<(usize, usize)> {
    if n == 0 || m == 0 {
        return Vec::new();
    }
    // A square problem with a dummy column per row and a dummy row per column.
    let barred = 4.0 * limit + 1.0;
    let k = n + m;
    let table: Vec<Vec<f64>> = (0..k)
        .map(|i| {
            (0..k)
                .map(|j| match (i < n, j < m) {
                    (true, true) => {
                        let c = cost(i, j);
                        if c <= limit { c } else { barred }
                    }
                    (true, false) | (false, true) => 0.5 * limit,
                    (false, false) => 0.0,
                })
                .collect()
        })
        .collect();
    assignment(&table)
        .into_iter()
        .enumerate()
        .filter(|&(i, j)| i < n && j < m && cost(i, j) <= limit)
        .collect()
}

/// Compares `before` with `after` (see the module docs): one [`Change`] per source of
/// either map, the kept and moved first (in the order of `before`), then the removed, then
/// the added.
pub fn diff(before: &[Placed], after: &[Placed], config: &DiffConfig) -> Vec<Change> {
    let gate = config.gate();
    let m2 = |i: usize, j: usize| mahalanobis2(&before[i], &after[j], config.floor_m);
    let mut pair_of_before: Vec<Option<(usize, ChangeKind)>> = vec![None; before.len()];
    let mut paired_after = vec![false; after.len()];
    for (i, j) in matched(before.len(), after.len(), gate, m2) {
        pair_of_before[i] = Some((j, ChangeKind::Kept));
        paired_after[j] = true;
    }
    let left_before: Vec<usize> = (0..before.len())
        .filter(|&i| pair_of_before[i].is_none())
        .collect();
    let left_after: Vec<usize> = (0..after.len()).filter(|&j| !paired_after[j]).collect();
    for (a, b) in matched(
        left_before.len(),
        left_after.len(),
        config.move_max_m,
        |a, b| {
            let (p, q) = (&before[left_before[a]], &after[left_after[b]]);
            if p.may_be(q) {
                distance(p, q)
            } else {
                f64::INFINITY
            }
        },
    ) {
        pair_of_before[left_before[a]] = Some((left_after[b], ChangeKind::Moved));
        paired_after[left_after[b]] = true;
    }
    // A change of `kind` of `before[i]` and `after[j]` (either may be absent): the source
    // of the other map nearest it, and the compared pair `(i, j)` whose distance and m² it
    // carries (the pair itself, or an unpaired source and that nearest one).
    let change = |kind,
                  i: Option<usize>,
                  j: Option<usize>,
                  nearest: Option<usize>,
                  compared: Option<(usize, usize)>| {
        let (d, v) = compared
            .map(|(a, b)| (distance(&before[a], &after[b]), m2(a, b)))
            .unzip();
        let p_same = v.map_or(0.0, |v| (-0.5 * v).exp());
        Change {
            kind,
            before: i,
            after: j,
            nearest,
            distance_m: d,
            mahalanobis2: v,
            p_same,
            confidence: if kind == ChangeKind::Kept {
                p_same
            } else {
                1.0 - p_same
            },
        }
    };
    let nearest = |p: &Placed, others: &[Placed]| {
        (0..others.len())
            .min_by(|&x, &y| distance(p, &others[x]).total_cmp(&distance(p, &others[y])))
    };
    let mut out: Vec<Change> = pair_of_before
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            p.map(|(j, kind)| change(kind, Some(i), Some(j), Some(j), Some((i, j))))
        })
        .collect();
    out.extend(
        (0..before.len())
            .filter(|&i| pair_of_before[i].is_none())
            .map(|i| {
                let n = nearest(&before[i], after);
                change(ChangeKind::Removed, Some(i), None, n, n.map(|j| (i, j)))
            }),
    );
    out.extend((0..after.len()).filter(|&j| !paired_after[j]).map(|j| {
        let n = nearest(&after[j], before);
        change(ChangeKind::Added, None, Some(j), n, n.map(|i| (i, j)))
    }));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64, y: f64, sigma: f64) -> Placed {
        Placed {
            x,
            y,
            covariance: [[sigma * sigma, 0.0], [0.0, sigma * sigma]],
            kind: None,
        }
    }

    #[test]
    fn a_hum_switched_off_and_a_voice_switched_on_are_not_a_move() {
        // 2 m apart: without kinds one source moved; with a hum before and speech after,
        // one was removed and another added; with speech both times, a move.
        let (mut hum, mut voice) = (at(0.0, 0.0, 0.05), at(2.0, 0.0, 0.05));
        let d = |a: &Placed, b: &Placed| {
            diff(
                std::slice::from_ref(a),
                std::slice::from_ref(b),
                &DiffConfig::default(),
            )
            .iter()
            .map(|c| c.kind)
            .collect::<Vec<_>>()
        };
        assert_eq!(d(&hum, &voice), [ChangeKind::Moved]);
        hum.kind = Some("tonal".into());
        voice.kind = Some("speech".into());
        assert_eq!(d(&hum, &voice), [ChangeKind::Removed, ChangeKind::Added]);
        hum.kind = Some("speech".into());
        assert_eq!(d(&hum, &voice), [ChangeKind::Moved]);
    }

    fn kinds(c: &[Change]) -> Vec<(ChangeKind, Option<usize>, Option<usize>)> {
        c.iter().map(|c| (c.kind, c.before, c.after)).collect()
    }

    #[test]
    fn the_mahalanobis_length_is_the_distance_over_the_summed_deviations() {
        // Isotropic: S = (0.1² + 0.2² + 2·0.1²) I = 0.07 I; d = 0.5 m gives 0.25 / 0.07.
        let v = mahalanobis2(&at(0.0, 0.0, 0.1), &at(0.3, 0.4, 0.2), 0.1);
        assert!((v - 0.25 / 0.07).abs() < 1e-12, "{v}");
        // Along a long axis a difference counts for less than across it.
        let long = Placed {
            x: 0.0,
            y: 0.0,
            covariance: [[1.0, 0.0], [0.0, 0.01]],
            kind: None,
        };
        let along = mahalanobis2(&long, &at(0.5, 0.0, 0.0), 0.0);
        let across = mahalanobis2(&long, &at(0.0, 0.5, 0.0), 0.0);
        assert!((along - 0.25).abs() < 1e-12 && (across - 25.0).abs() < 1e-9);
        // The gate of 0.99 is the chi-square quantile with two degrees of freedom.
        assert!((DiffConfig::default().gate() - 9.2103).abs() < 1e-4);
    }

    #[test]
    fn a_source_kept_a_source_moved_one_removed_one_added() {
        let before = [at(1.0, 1.0, 0.05), at(5.0, 4.0, 0.05), at(0.5, 4.5, 0.05)];
        // The first stays within its error, the second walks 2.5 m, the third is gone,
        // and a new one stands over 4 m from every old place.
        let after = [at(3.0, 8.5, 0.05), at(1.05, 0.97, 0.05), at(5.0, 1.5, 0.05)];
        let c = diff(&before, &after, &DiffConfig::default());
        assert_eq!(
            kinds(&c),
            vec![
                (ChangeKind::Kept, Some(0), Some(1)),
                (ChangeKind::Moved, Some(1), Some(2)),
                (ChangeKind::Removed, Some(2), None),
                (ChangeKind::Added, None, Some(0)),
            ]
        );
        let moved = c[1];
        assert!((moved.distance_m.unwrap() - 2.5).abs() < 1e-12);
        assert!(moved.confidence > 0.999 && c[0].confidence > 0.5);
        // The removed one is compared with its nearest source of the second map.
        assert_eq!(c[2].nearest, Some(1));
        assert!((c[2].distance_m.unwrap() - 0.55f64.hypot(3.53)).abs() < 1e-12);
        assert!(c[2].confidence > 0.999 && c[3].confidence > 0.999);
    }

    #[test]
    fn a_kept_source_is_never_taken_as_another_sources_new_place() {
        // A source stays at (2, 0); another, 1 m away, is gone. Nearest-first pairing
        // could give the survivor to the gone one; the kept pass comes first.
        let before = [at(3.0, 0.0, 0.05), at(2.0, 0.0, 0.05)];
        let after = [at(2.02, 0.0, 0.05)];
        let c = diff(&before, &after, &DiffConfig::default());
        assert_eq!(
            kinds(&c),
            vec![
                (ChangeKind::Kept, Some(1), Some(0)),
                (ChangeKind::Removed, Some(0), None)
            ]
        );
    }

    #[test]
    fn beyond_the_move_limit_a_source_is_removed_and_another_added() {
        let before = [at(0.0, 0.0, 0.05)];
        let after = [at(2.0, 0.0, 0.05)];
        let far = DiffConfig {
            move_max_m: 1.5,
            ..DiffConfig::default()
        };
        assert_eq!(
            kinds(&diff(&before, &after, &far)),
            vec![
                (ChangeKind::Removed, Some(0), None),
                (ChangeKind::Added, None, Some(0))
            ]
        );
        assert_eq!(
            kinds(&diff(&before, &after, &DiffConfig::default())),
            vec![(ChangeKind::Moved, Some(0), Some(0))]
        );
    }

    #[test]
    fn uncertain_maps_keep_what_sure_maps_call_moved() {
        // 0.4 m apart: two sure maps (5 cm, floor 5 cm) say moved, two vague ones
        // (0.3 m) say kept.
        let sure = DiffConfig {
            floor_m: 0.05,
            ..DiffConfig::default()
        };
        let moved = diff(&[at(0.0, 0.0, 0.05)], &[at(0.4, 0.0, 0.05)], &sure);
        let kept = diff(&[at(0.0, 0.0, 0.3)], &[at(0.4, 0.0, 0.3)], &sure);
        assert_eq!(moved[0].kind, ChangeKind::Moved);
        assert_eq!(kept[0].kind, ChangeKind::Kept);
    }

    #[test]
    fn empty_maps_give_only_removals_or_additions_with_full_confidence() {
        let a = [at(0.0, 0.0, 0.05), at(1.0, 0.0, 0.05)];
        let c = diff(&a, &[], &DiffConfig::default());
        assert!(
            c.iter()
                .all(|c| c.kind == ChangeKind::Removed && c.confidence == 1.0)
        );
        let c = diff(&[], &a, &DiffConfig::default());
        assert!(
            c.iter()
                .all(|c| c.kind == ChangeKind::Added && c.nearest.is_none())
        );
        assert!(diff(&[], &[], &DiffConfig::default()).is_empty());
    }
}
