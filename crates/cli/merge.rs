//! The merging mapper behind `iasm ros2-merge`: several robots' stops in, one building's
//! map out.
//!
//! Each robot's node publishes what it heard at each stop (`iasm_msgs/msg/Stop`: its pose
//! in the building's map frame, its ranked DoAs, whether N cut the row), so no audio
//! crosses the network. The stops of every robot are one I-ASM problem
//! ([`crate::pipeline::union`] is the same problem offline): a stop is added to the
//! stop-by-stop mapper as it arrives, whichever robot it comes from, and
//! [`MergeMapper::finish`] maps every stop at once in the order `iasm map --dataset A
//! --dataset B` takes them (the runs by name, each run's stops in order), so that the final
//! map is the offline union's (one batch map, `iasm map`'s, not the stops added again one by
//! one). A robot that drops off the network leaves its stops; one
//! that joins late adds its own; a stop heard twice (a reader that joined late is sent the
//! stops kept for it) is taken once.
//!
//! The map is searched in the building's grid once one is given ([`MergeMapper::set_grid`]),
//! and until then within [`crate::pipeline::OPEN_MARGIN_M`] of the stops, as `iasm map`
//! searches without a map; when that region changes, the mapper is rebuilt over the stops
//! so far.

use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::Result;
use asm::map::OccupancyMap;
use asm::{MapResult, Pose};
use serde::Serialize;

use crate::online::Session;
use crate::rosmap::MapMessages;
use crate::settings::Settings;

/// A stop as the merging mapper took it.
#[derive(Clone, Debug, Serialize)]
pub struct MergedStop {
    /// The run (the publishing node).
    pub run: String,
    /// Its place in its run, from 0.
    pub index: u32,
    /// When the robot arrived (ns since the epoch).
    pub arrived_ns: i64,
    /// Where it stood.
    pub pose: Pose,
    /// Its DoAs (degrees, array frame, strongest first).
    pub doas_deg: Vec<f64>,
    /// Whether N cut its row.
    pub cut: bool,
    /// The SSL method that heard them.
    pub method: String,
}

/// What the merging node says after each stop.
pub struct MergeUpdate {
    /// The map now.
    pub map: MapResult,
    /// The stops so far.
    pub stops: usize,
    /// Milliseconds the map update took.
    pub map_ms: f64,
}

/// Several robots' stops in, the building's map out.
pub struct MergeMapper {
    settings: Settings,
    seed: u64,
    /// Every stop, by run and index.
    stops: BTreeMap<(String, u32), MergedStop>,
    /// The stops in the order they came (keys of `stops`).
    order: Vec<(String, u32)>,
    grid: Option<OccupancyMap>,
    /// The map the session searches.
    map: Option<OccupancyMap>,
    session: Option<Session>,
}

/// The map JSON the merging node writes.
#[derive(Serialize)]
pub struct MergeReport<'a> {
    /// Its version.
    pub schema_version: u32,
    /// The frame of every coordinate.
    pub frame_id: &'static str,
    /// The particle filter's seed.
    pub seed: u64,
    /// Whether this is the final (full) map.
    pub final_map: bool,
    /// Each run's stop count.
    pub runs: BTreeMap<&'a str, usize>,
    /// The stops mapped, by run then index.
    pub stops: Vec<&'a MergedStop>,
    /// The mapper's settings.
    pub params: &'a asm::IasmConfig,
    /// The sources.
    pub sources: &'a [asm::Source],
    /// What was refused, and why.
    pub refused: &'a [asm::Refused],
}

impl MergeMapper {
    /// A merging mapper with `settings` (its `[iasm]` part: the stops' DoAs are given),
    /// its particle filter seeded by `seed`.
    ///
    /// # Errors
    /// Settings that do not validate.
    pub fn new(settings: Settings, seed: u64) -> Result<Self> {
        settings.validate()?;
        Ok(Self {
            settings,
            seed,
            stops: BTreeMap::new(),
            order: Vec::new(),
            grid: None,
            map: None,
            session: None,
        })
    }

    /// Searches the building's grid from the next stop on.
    pub fn set_grid(&mut self, grid: OccupancyMap) {
        self.grid = Some(grid);
    }

    /// The stops so far, in the order they came.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Whether no stop has come.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// The map to search: the grid, else the region around the stops so far.
    fn current_map(&self) -> Result<OccupancyMap> {
        if let Some(g) = &self.grid {
            return Ok(g.clone());
        }
        let points: Vec<[f64; 2]> = self
            .order
            .iter()
            .map(|k| {
                let p = self.stops[k].pose;
                [p.x, p.y]
            })
            .collect();
        Ok(OccupancyMap::open_around(
            &points,
            crate::pipeline::OPEN_MARGIN_M,
            crate::pipeline::OPEN_RESOLUTION_M,
        )?)
    }

    /// A session over `keys`' stops on `map`.
    fn session_over<'a>(
        &'a self,
        map: &OccupancyMap,
        keys: impl Iterator<Item = &'a (String, u32)>,
    ) -> Result<Session> {
        let mut s = Session::new(map, &self.settings, self.seed, None, 1.0, 1.0)?;
        s.add_history(keys.map(|k| {
            let st = &self.stops[k];
            (st.pose, &st.doas_deg[..], Some(st.cut))
        }))?;
        Ok(s)
    }

    /// Adds a stop; `None` when it was had already (the same run and index).
    ///
    /// # Errors
    /// A pose that is not finite, more DoAs than N on a row not cut, or a map with no
    /// room for particles; the stop is not kept then.
    pub fn add(&mut self, stop: MergedStop) -> Result<Option<MergeUpdate>> {
        let key = (stop.run.clone(), stop.index);
        if self.stops.contains_key(&key) {
            return Ok(None);
        }
        let t0 = Instant::now();
        self.stops.insert(key.clone(), stop);
        self.order.push(key.clone());
        let added = (|| -> Result<()> {
            let map = self.current_map()?;
            match self.session.as_mut() {
                Some(session) if self.map.as_ref() == Some(&map) => {
                    let st = &self.stops[&key];
                    let name = format!("{} stop {}", st.run, st.index + 1);
                    session.add_row(&name, st.pose, &st.doas_deg, Some(st.cut))?;
                }
                _ => {
                    // A new region: one batch map over the stops so far (`Session::add_history`).
                    let s = self.session_over(&map, self.order.iter())?;
                    self.session = Some(s);
                    self.map = Some(map);
                }
            }
            Ok(())
        })();
        if let Err(e) = added {
            self.stops.remove(&key);
            self.order.pop();
            self.session = None;
            return Err(e);
        }
        Ok(Some(MergeUpdate {
            map: self.session.as_ref().expect("set").map(),
            stops: self.order.len(),
            map_ms: 1e3 * t0.elapsed().as_secs_f64(),
        }))
    }

    /// The full map over every stop, the runs by name and each run's stops in order (the
    /// map `iasm map --dataset` gives of the runs in that order); `None` before the first.
    ///
    /// # Errors
    /// As [`MergeMapper::add`].
    pub fn finish(&mut self) -> Result<Option<MapResult>> {
        if self.order.is_empty() {
            return Ok(None);
        }
        let map = self.current_map()?;
        let config = asm::IasmConfig {
            mirror_axis_deg: self
                .settings
                .iasm
                .mirror_axis_deg
                .or(self.settings.mic_array()?.mirror_axis_deg()),
            ..self.settings.iasm.clone()
        };
        let n = config.num_doas;
        // One batch map (`iasm map`'s), not the stops added again one by one: a row not
        // cut is taken to N, as a table's row is.
        let stops: Vec<&MergedStop> = self.stops.values().collect();
        let poses: Vec<Pose> = stops.iter().map(|s| s.pose).collect();
        let rows: Vec<Vec<f64>> = stops
            .iter()
            .map(|s| {
                let keep = if s.cut {
                    s.doas_deg.len()
                } else {
                    s.doas_deg.len().min(n)
                };
                s.doas_deg[..keep].iter().map(|a| a.to_radians()).collect()
            })
            .collect();
        let cut: Vec<bool> = stops.iter().map(|s| s.cut).collect();
        let mapper = asm::Mapper::new(&map, &config)?;
        Ok(Some(mapper.run_seeded(
            &poses,
            &rows,
            Some(&cut),
            self.seed,
        )?))
    }

    /// The messages of `result` over every stop (in the order they came), stamped
    /// `stamp_ns`.
    pub fn messages(&self, result: &MapResult, stamp_ns: i64) -> Option<MapMessages> {
        let map = self.map.as_ref()?;
        let stops = self.order.iter().map(|k| {
            let s = &self.stops[k];
            (s.pose, s.arrived_ns, s.doas_deg.as_slice())
        });
        Some(crate::rosmap::messages_over(result, stops, map, stamp_ns))
    }

    /// The map JSON of `result`.
    pub fn report<'a>(&'a self, result: &'a MapResult, final_map: bool) -> MergeReport<'a> {
        let mut runs = BTreeMap::new();
        for (run, _) in self.stops.keys() {
            *runs.entry(run.as_str()).or_default() += 1;
        }
        MergeReport {
            schema_version: 1,
            frame_id: crate::rosmap::FRAME,
            seed: self.seed,
            final_map,
            runs,
            stops: self.stops.values().collect(),
            params: &self.settings.iasm,
            sources: &result.sources,
            refused: &result.refused,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two robots' stops around two sources: bearings computed from the poses.
    fn stops() -> Vec<MergedStop> {
        let sources = [[1.0, 2.0], [5.0, 2.5]];
        let mut out = Vec::new();
        for (run, xs) in [("/r2", [3.0, 4.0, 5.0, 6.0]), ("/r1", [0.0, 1.0, 2.0, 3.0])] {
            for (i, x) in xs.into_iter().enumerate() {
                let pose = Pose {
                    x,
                    y: 0.0,
                    theta: 0.3,
                };
                let doas = sources
                    .iter()
                    .map(|s| pose.azimuth_to(*s).to_degrees())
                    .collect();
                out.push(MergedStop {
                    run: run.into(),
                    index: u32::try_from(i).unwrap(),
                    arrived_ns: 0,
                    pose,
                    doas_deg: doas,
                    cut: false,
                    method: "truth".into(),
                });
            }
        }
        out
    }

    #[test]
    fn stops_of_two_robots_in_any_order_end_in_the_map_of_their_union() {
        let settings = Settings::default();
        let mut interleaved = MergeMapper::new(settings.clone(), 3).unwrap();
        let all = stops();
        // r2's and r1's stops interleaved, one of them twice.
        for k in [0, 4, 1, 5, 2, 6, 3, 7, 5] {
            interleaved.add(all[k].clone()).unwrap();
        }
        assert_eq!(interleaved.len(), 8);
        // The offline union of the two runs (r1's stops, then r2's), as `iasm map` maps it.
        let ordered: Vec<&MergedStop> = [4, 5, 6, 7, 0, 1, 2, 3].iter().map(|&k| &all[k]).collect();
        let points: Vec<[f64; 2]> = ordered.iter().map(|s| [s.pose.x, s.pose.y]).collect();
        let survey = crate::pipeline::Survey {
            map: OccupancyMap::open_around(&points, 3.0, 0.05).unwrap(),
            open_margin_m: Some(3.0),
            poses: ordered.iter().map(|s| s.pose).collect(),
            doas_deg: ordered
                .iter()
                .map(|s| s.doas_deg.iter().map(|&d| Some(d)).collect())
                .collect(),
            cut: Some(vec![false; 8]),
            truth: None,
            doa_source: "truth".into(),
            mirror_axis_deg: None,
        };
        let a = interleaved.finish().unwrap().unwrap();
        let b = survey.map(&settings.iasm, 3).unwrap();
        assert_eq!(a.positions(), b.positions());
        let truth = [[1.0, 2.0], [5.0, 2.5]];
        assert_eq!(a.sources.len(), 2, "{:?}", a.positions());
        for t in truth {
            let d = a
                .positions()
                .iter()
                .map(|p| (p[0] - t[0]).hypot(p[1] - t[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 0.1, "{t:?}: {d}");
        }
        let r = interleaved.report(&a, true);
        assert_eq!(r.runs.get("/r1"), Some(&4));
        assert_eq!((r.stops[0].run.as_str(), r.stops[0].index), ("/r1", 0));
    }
}
