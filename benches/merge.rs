//! How far one merging node (`iasm ros2-merge`) carries a building: the time of each map
//! update against the stops merged so far, to 2,000 stops of four robots.
//!
//! The building: one floor 32 x 12 m, open (the particle filter's particles per round grow
//! with the free area: an open floor is the costly case), 16 talkers on a 4 x 6 m lattice;
//! four robots, each patrolling its own line along the floor (y = 1.5, 4.5, 7.5, 10.5 m)
//! back and forth, a stop every 0.2 m, 500 stops each. Each stop hears the four nearest
//! talkers, their exact bearings (N = 4): the mapper's cost, not the front end's. The stops
//! arrive round-robin, as four robots' do. What is timed is `MergeMapper::add` (the
//! update the node publishes after each stop; the stop after 4, 8, 16, ... stops takes in
//! the full map over every stop that the stop before started beside it, see
//! `asm::online`, and here, the stops coming back to back, waits for it) and, at the end,
//! `MergeMapper::finish` (the full map Ctrl-C ends with).
//!
//! A plain benchmark (its updates take milliseconds to tens of seconds, each once, which
//! criterion's repeated samples do not fit): `cargo bench --bench merge` prints the curve;
//! figures go to BENCHMARKS.md and docs/guide/robots.md.

use std::time::Instant;

use asm::Pose;
use iasm::merge::{MergeMapper, MergedStop};
use iasm::settings::Settings;

/// The building's talkers.
fn talkers() -> Vec<[f64; 2]> {
    (0..8)
        .flat_map(|i| [3.0, 9.0].map(|y| [2.0 + 4.0 * f64::from(i), y]))
        .collect()
}

/// The four robots' stops, round-robin.
fn stops(per_robot: usize) -> Vec<MergedStop> {
    let sources = talkers();
    let xs: Vec<f64> = (0..150).map(|k| 1.0 + 0.2 * f64::from(k)).collect();
    let runs: Vec<Vec<MergedStop>> = (0..4u32)
        .map(|r| {
            let y = 1.5 + 3.0 * f64::from(r);
            // Back and forth along the line.
            let path = xs.iter().chain(xs.iter().rev()).cycle().take(per_robot);
            path.enumerate()
                .map(|(k, &x)| {
                    let pose = Pose { x, y, theta: 0.0 };
                    let mut near = sources.clone();
                    let d = |s: &[f64; 2]| (s[0] - x).hypot(s[1] - y);
                    near.sort_by(|a, b| d(a).total_cmp(&d(b)));
                    MergedStop {
                        run: format!("/robot{}/iasm", r + 1),
                        index: u32::try_from(k).expect("small"),
                        arrived_ns: 0,
                        pose,
                        doas_deg: near[..4]
                            .iter()
                            .map(|s| pose.azimuth_to(*s).to_degrees())
                            .collect(),
                        cut: false,
                        method: "truth".into(),
                    }
                })
                .collect()
        })
        .collect();
    (0..per_robot)
        .flat_map(|k| runs.iter().map(move |r| r[k].clone()))
        .collect()
}

fn main() {
    let all = stops(500);
    let mut settings = Settings::default();
    settings.iasm.num_doas = 4;
    let mut m = MergeMapper::new(settings, 1).expect("default settings");
    let points: Vec<[f64; 2]> = all.iter().map(|s| [s.pose.x, s.pose.y]).collect();
    m.set_grid(asm::map::OccupancyMap::open_around(&points, 1.5, 0.05).expect("a region"));
    println!(
        "{} stops of 4 robots, {} talkers, one 32 x 12 m floor; ms per update:",
        all.len(),
        talkers().len()
    );
    println!(
        "{:>6} {:>14} {:>14} {:>10} {:>8} {:>8}",
        "stops", "median since", "full map (ms)", "sources", "OSPA (m)", "run (s)"
    );
    let mut window: Vec<f64> = Vec::new();
    let mut full: Option<f64> = None;
    let total = Instant::now();
    for (i, s) in all.iter().enumerate() {
        let k = i + 1;
        let t0 = Instant::now();
        let u = m.add(s.clone()).expect("a stop").expect("a new stop");
        let ms = 1e3 * t0.elapsed().as_secs_f64();
        if k > 4 && (k - 1).is_power_of_two() {
            full = Some(ms);
        } else {
            window.push(ms);
        }
        if k % 250 == 0 || k == 100 || k == 50 {
            window.sort_by(f64::total_cmp);
            let ospa = asm::ospa::ospa(&u.map.positions(), &talkers(), 1.0, 1.0).total;
            println!(
                "{k:>6} {:>14.1} {:>14} {:>10} {:>8.3} {:>8.0}",
                window[window.len() / 2],
                full.take().map_or("-".to_owned(), |f| format!("{f:.0}")),
                u.map.sources.len(),
                ospa,
                total.elapsed().as_secs_f64()
            );
            window.clear();
        }
    }
    let t0 = Instant::now();
    let f = m.finish().expect("a map").expect("stops");
    println!(
        "final full map over {} stops: {:.1} s, {} sources, OSPA {:.3} m (the run: {:.0} s)",
        m.len(),
        t0.elapsed().as_secs_f64(),
        f.sources.len(),
        asm::ospa::ospa(&f.positions(), &talkers(), 1.0, 1.0).total,
        total.elapsed().as_secs_f64()
    );
}
