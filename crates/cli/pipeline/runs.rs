//! Several runs of one building as one survey.
//!
//! A building is larger than one robot's run. The stops of several robots, or of one
//! robot's several runs, whose poses share the building's map frame are one I-ASM problem:
//! the DoAs of every stop, each with its pose, in one occupancy map. Nothing in the
//! paper's algorithm asks that the stops come from one trajectory: its particle filter
//! weighs each stop's DoAs from that stop's pose, and the implicit association clusters
//! them wherever they cross. So the union is the runs' stops one after the other, each
//! localised with its own run's settings (its array, its robot's noise), and mapped once.
//! A source that one robot hears along a single line of sight (its range barely observed)
//! and another from across the building is then placed where the two robots' bearings
//! cross, which neither robot's own map can do.
//!
//! What the runs must share: the frame (checked where it can be: their occupancy maps must
//! be the same grid, or only one has one), the array's mirror ambiguity (a linear array in
//! one run and not another is refused). The truth of the union is the union of the runs'
//! truths, a source listed by two runs within [`SAME_SOURCE_M`] counted once.

use super::*;

/// Two runs' true sources closer than this (m) are one source of the building.
pub const SAME_SOURCE_M: f64 = 0.05;

/// Where a run's stops lie in the union.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RunSpan {
    /// The run's name (its data set folder).
    pub name: String,
    /// Its first stop in the union, counted from 1.
    pub first_stop: usize,
    /// How many stops it has.
    pub stops: usize,
}

/// The runs `runs` (each a name, where its survey comes from and its settings) loaded and
/// joined ([`union`]); one run is loaded as it is.
///
/// # Errors
/// A run that cannot be loaded (named), or runs that cannot be joined ([`union`]).
pub fn load_runs(runs: &[(String, SurveyInputs, Settings)]) -> Result<(Survey, Vec<RunSpan>)> {
    let surveys = runs
        .iter()
        .map(|(name, inputs, settings)| {
            Survey::load(inputs, settings)
                .with_context(|| format!("run {name}"))
                .map(|s| (name.clone(), s))
        })
        .collect::<Result<Vec<_>>>()?;
    union(surveys)
}

/// The runs' surveys as one: their stops one after the other, the building's map, the
/// union of their truths; and where each run's stops lie.
///
/// # Errors
/// No run; runs whose occupancy maps differ (they must share the building's map: give it
/// with `--map`); runs of which some were heard by a linear array and others not, or by
/// linear arrays along other lines.
pub fn union(runs: Vec<(String, Survey)>) -> Result<(Survey, Vec<RunSpan>)> {
    ensure!(!runs.is_empty(), "no run to map");
    let mut spans = Vec::with_capacity(runs.len());
    let mut at = 1;
    for (name, s) in &runs {
        spans.push(RunSpan {
            name: name.clone(),
            first_stop: at,
            stops: s.poses.len(),
        });
        at += s.poses.len();
    }
    if runs.len() == 1 {
        let (_, s) = runs.into_iter().next().expect("one");
        return Ok((s, spans));
    }
    // The building's map: the one grid the runs share; else the region around every stop.
    let mut grid: Option<(&str, &OccupancyMap)> = None;
    for (name, s) in &runs {
        if s.open_margin_m.is_some() {
            continue;
        }
        match grid {
            None => grid = Some((name, &s.map)),
            Some((first, m)) if *m != s.map => bail!(
                "runs {first} and {name} have different occupancy maps: the runs of one map must share the building's map frame (give the building's map with --map)"
            ),
            Some(_) => {}
        }
    }
    let (first_name, first) = &runs[0];
    for (name, s) in &runs[1..] {
        ensure!(
            s.mirror_axis_deg == first.mirror_axis_deg,
            "runs {first_name} and {name} were heard by arrays of other kinds (a linear array's mirror axis {:?} and {:?} degrees): map them apart",
            first.mirror_axis_deg,
            s.mirror_axis_deg
        );
    }
    let poses: Vec<Pose> = runs.iter().flat_map(|(_, s)| s.poses.clone()).collect();
    let (map, open_margin_m) = match grid {
        Some((_, m)) => (m.clone(), None),
        None => {
            let margin = runs
                .iter()
                .filter_map(|(_, s)| s.open_margin_m)
                .fold(0.0, f64::max);
            let stops: Vec<[f64; 2]> = poses.iter().map(|p| [p.x, p.y]).collect();
            (
                OccupancyMap::open_around(&stops, margin, OPEN_RESOLUTION_M)?,
                Some(margin),
            )
        }
    };
    let cut = runs
        .iter()
        .map(|(_, s)| s.cut.clone())
        .collect::<Option<Vec<_>>>()
        .map(|c| c.concat());
    let truth =
        runs.iter()
            .filter_map(|(_, s)| s.truth.as_ref())
            .fold(None::<Vec<[f64; 2]>>, |acc, t| {
                let mut all = acc.unwrap_or_default();
                for q in t {
                    if all
                        .iter()
                        .all(|a| (a[0] - q[0]).hypot(a[1] - q[1]) >= SAME_SOURCE_M)
                    {
                        all.push(*q);
                    }
                }
                Some(all)
            });
    let sources: Vec<&str> = runs.iter().map(|(_, s)| s.doa_source.as_str()).collect();
    let doa_source = if sources.iter().all(|s| *s == sources[0]) {
        sources[0].to_owned()
    } else {
        runs.iter()
            .map(|(n, s)| format!("{n}: {}", s.doa_source))
            .collect::<Vec<_>>()
            .join("; ")
    };
    let mirror_axis_deg = first.mirror_axis_deg;
    let doas_deg: Table = runs.iter().flat_map(|(_, s)| s.doas_deg.clone()).collect();
    let survey = Survey {
        map,
        open_margin_m,
        poses,
        doas_deg,
        cut,
        truth,
        doa_source,
        mirror_axis_deg,
    };
    Ok((survey, spans))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(poses: &[[f64; 3]], truth: &[[f64; 2]], open: bool) -> Survey {
        let stops: Vec<[f64; 2]> = poses.iter().map(|p| [p[0], p[1]]).collect();
        Survey {
            map: OccupancyMap::open_around(&stops, 3.0, 0.05).unwrap(),
            open_margin_m: open.then_some(3.0),
            poses: poses
                .iter()
                .map(|p| Pose {
                    x: p[0],
                    y: p[1],
                    theta: p[2],
                })
                .collect(),
            doas_deg: poses.iter().map(|_| vec![Some(10.0)]).collect(),
            cut: Some(vec![false; poses.len()]),
            truth: Some(truth.to_vec()),
            doa_source: "ssl:mvdr".into(),
            mirror_axis_deg: None,
        }
    }

    #[test]
    fn the_union_is_the_runs_stops_in_turn_with_one_truth_of_the_building() {
        let a = run(
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
            &[[2.0, 2.0], [5.0, 0.0]],
            true,
        );
        let b = run(
            &[[6.0, 3.0, 1.0], [6.0, 4.0, 1.0], [6.0, 5.0, 1.0]],
            &[[5.0, 0.02], [7.0, 6.0]],
            true,
        );
        let (u, spans) = union(vec![("a".into(), a), ("b".into(), b)]).unwrap();
        assert_eq!(u.poses.len(), 5);
        assert_eq!((u.poses[2].x, u.poses[2].y), (6.0, 3.0));
        assert_eq!(u.doas_deg.len(), 5);
        assert_eq!(u.cut.as_ref().map(Vec::len), Some(5));
        // The source both runs list 2 cm apart is one source.
        assert_eq!(u.truth.as_ref().unwrap().len(), 3);
        assert_eq!(
            spans,
            [
                RunSpan {
                    name: "a".into(),
                    first_stop: 1,
                    stops: 2
                },
                RunSpan {
                    name: "b".into(),
                    first_stop: 3,
                    stops: 3
                }
            ]
        );
        // Without a grid, the region around every stop of both runs.
        let free = |p| u.map.cell_at(p) == Some(asm::map::Cell::Free);
        assert!(free([6.0, 7.5]) && free([0.0, -2.5]));
    }

    #[test]
    fn runs_with_other_maps_or_arrays_are_refused_by_name() {
        let a = run(&[[0.0, 0.0, 0.0]], &[], false);
        let b = run(&[[4.0, 0.0, 0.0]], &[], false);
        let e = union(vec![("a".into(), a.clone()), ("b".into(), b)]).unwrap_err();
        assert!(
            e.to_string()
                .contains("runs a and b have different occupancy maps"),
            "{e}"
        );
        let mut c = a.clone();
        c.mirror_axis_deg = Some(0.0);
        let e = union(vec![("a".into(), a), ("c".into(), c)]).unwrap_err();
        assert!(e.to_string().contains("arrays of other kinds"), "{e}");
    }
}
