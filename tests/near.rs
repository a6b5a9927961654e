//! Near sources below the array (issue 9): on the authors' recordings, DoAs of sources
//! under 1.5 m carry 4-5 degree errors, in MBSS Locate's tables as in ours. With the
//! geometry known exactly, our far-field front end localises such sources within a degree:
//! the plane-wave model, the 10-degree elevation grid and the azimuth-only refinement are
//! not what limits it there.

use iasm::pipeline::Simulated;
use iasm::scenes::{parse_scene, prepare};
use iasm::score::diagnose;
use ssl::{Method, SslConfig};

/// A talker on the floor, 0.8 m from the robot's path at its nearest, the array's origin
/// 0.45 m above the floor (the source 25-30 degrees below it up close), RT60 0.5 s.
const SCENE: &str = r#"
name = "near_below"
seed = 9
fs = 16000
clip_s = 0.3
snr_db = 30.0
[room]
dims = [8.0, 6.0, 3.0]
rt60 = 0.5
[array]
preset = "iasm6"
height = 0.45
[[sources]]
pos = [4.0, 3.8, 0.05]
signal = "speech_shaped"
[trajectory]
waypoints = [[1.0, 3.0], [7.0, 3.0]]
spacing = 0.3
"#;

// See: issue 9
#[test]
fn r9_near_sources_below_the_array_are_found_within_a_degree_and_a_half() {
    let (scene, _) = parse_scene(SCENE).unwrap();
    let sim = Simulated::render(prepare(scene).unwrap(), "near".into()).unwrap();
    for method in Method::BLOCKWISE {
        let ssl = SslConfig {
            method,
            num_peaks: 1,
            ..SslConfig::default()
        };
        let survey = sim.survey(&ssl).unwrap();
        let d = diagnose(
            &survey.doas_deg,
            &survey.poses,
            &sim.truth,
            1,
            10.0,
            5.0,
            None,
        )
        .unwrap();
        // 0-1 m and 1-1.5 m: the bands where the real recordings err by 4-5 degrees.
        for b in &d.bands[..2] {
            assert!(b.doas >= 3, "{method}: {d:?}");
            assert!(b.mean_abs_err_deg < 1.5, "{method} {}: {d:?}", b.band);
        }
        assert_eq!(d.recall_3m, 1.0, "{method}: {d:?}");
    }
}
