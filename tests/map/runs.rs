//! Several runs of one building mapped as one (`iasm map --dataset A --dataset B`): two
//! robots in two parts of an L-shaped floor (`fixtures/buildings`), each hearing a talker
//! the other cannot and one talker both hear along a single line of sight.

use std::path::Path;

use super::*;

/// The building's three talkers (`fixtures/buildings/two_robots_*.toml`): heard well only
/// from the hall, only from the wing, and from both.
const HALL_ONLY: [f64; 2] = [1.2, 2.5];
const WING_ONLY: [f64; 2] = [7.3, 7.2];
const BOTH: [f64; 2] = [6.0, 0.6];

/// How far the nearest source of `map` lies from `p` (m; infinite for an empty map).
fn nearest(map: &[[f64; 2]], p: [f64; 2]) -> f64 {
    map.iter()
        .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
        .fold(f64::INFINITY, f64::min)
}

fn render(dir: &tempfile::TempDir, which: &str) -> std::path::PathBuf {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("fixtures/buildings/two_robots_{which}.toml"));
    let out = path(dir, which);
    let o = iasm(&["simulate", arg(&scene), "--out", arg(&out)]);
    assert!(o.status.success(), "{}", show(&o));
    out
}

/// The union of two robots' stops holds every talker of the building, where each robot's
/// own map misses the talker only the other heard, and places the talker both heard where
/// their bearings cross, closer than either robot alone could (each heard it along one
/// line of sight, its range barely observed). The JSON says which stops were whose.
#[test]
fn two_robots_runs_map_as_one_building_better_than_either_alone() {
    let dir = tempdir();
    let (west, wing) = (render(&dir, "west"), render(&dir, "wing"));
    for method in ["gcc-phat", "mvdr"] {
        let map = |datasets: &[&Path]| {
            let mut args = vec!["map", "--method", method, "--num", "4", "--json"];
            for d in datasets {
                args.extend(["--dataset", arg(d)]);
            }
            let o = iasm(&args);
            assert!(o.status.success(), "{}", show(&o));
            json(&o)
        };
        let (alone_west, alone_wing) = (map(&[&west]), map(&[&wing]));
        let both = map(&[&west, &wing]);
        let (a, b, u) = (
            sources_of(&alone_west),
            sources_of(&alone_wing),
            sources_of(&both),
        );
        assert_eq!(u.len(), 3, "{method}: {u:?}");
        for t in [HALL_ONLY, WING_ONLY, BOTH] {
            assert!(nearest(&u, t) < 0.25, "{method}: {t:?} in {u:?}");
        }
        assert!(
            nearest(&a, WING_ONLY) > 0.5,
            "{method}: the hall robot's {a:?}"
        );
        assert!(
            nearest(&b, HALL_ONLY) > 0.5,
            "{method}: the wing robot's {b:?}"
        );
        assert!(
            nearest(&u, BOTH) < 0.5 * nearest(&a, BOTH).min(nearest(&b, BOTH)),
            "{method}: {u:?} against {a:?} and {b:?}"
        );
        let ospa = |m: &serde_json::Value| m["ospa"]["total"].as_f64().unwrap();
        assert!(ospa(&both) < 0.15, "{method}: {}", ospa(&both));
        assert!(ospa(&alone_west) > 0.4 && ospa(&alone_wing) > 0.4);
        // Stops 1-5 are the hall robot's, 6-10 the wing robot's.
        let runs = both["runs"].as_array().unwrap();
        let span = |i: usize| (runs[i]["first_stop"].as_u64(), runs[i]["stops"].as_u64());
        assert_eq!((span(0), span(1)), ((Some(1), Some(5)), (Some(6), Some(5))));
        assert!(alone_west.get("runs").is_none());
    }
    // A run's own files cannot be given for two.
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&west),
        "--dataset",
        arg(&wing),
        "--poses",
        arg(&west),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", show(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--poses with 2 data sets"));
}
