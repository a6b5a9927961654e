//! Bad and unusual input files for `iasm map`: a clear error naming the file and the
//! problem, never a panic; and what ROS tools export read as it is meant.

use super::*;
use crate::util::*;

#[test]
fn a_missing_map_image_falls_back_to_the_only_pgm_with_a_warning() {
    let dir = tempdir();
    let root = dataset(&dir);
    let yaml = root.join("map/room.yaml");
    let text = std::fs::read_to_string(&yaml)
        .unwrap()
        .replace("room.pgm", "0201.pgm");
    std::fs::write(&yaml, text).unwrap();
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning") && err.contains("0201.pgm") && err.contains("room.pgm"),
        "{err}"
    );
}

#[test]
fn poses_and_doas_of_different_lengths_are_a_clear_error() {
    let dir = tempdir();
    let root = dataset(&dir);
    let doas = std::fs::read_to_string(root.join("doas.csv")).unwrap();
    let short: String = doas.lines().take(5).map(|l| format!("{l}\n")).collect();
    std::fs::write(root.join("short.csv"), short).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("short.csv"))]);
    assert_clear_error(&o, &["5 rows of DoAs", "20 poses", "short.csv"]);
}

#[test]
fn a_nan_or_non_numeric_pose_is_a_clear_error() {
    let dir = tempdir();
    let root = dataset(&dir);
    let poses = root.join("pose/poses.csv");
    let good = std::fs::read_to_string(&poses).unwrap();
    std::fs::write(&poses, good.replacen("0.3,0,", "0.3,NaN,", 1)).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv"))]);
    assert_clear_error(&o, &["poses.csv", "row 2", "y"]);
    std::fs::write(&poses, good.replacen("0.3,0,", "0.3,north,", 1)).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv"))]);
    assert_clear_error(&o, &["poses.csv", "row 2, column 2", "north"]);
}

#[test]
fn a_map_with_no_known_cell_is_a_clear_error() {
    let dir = tempdir();
    let root = dataset(&dir);
    let mut pgm = b"P5\n160 120\n255\n".to_vec();
    pgm.extend(std::iter::repeat_n(205u8, 160 * 120));
    std::fs::write(root.join("map/room.pgm"), pgm).unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv"))]);
    assert_clear_error(&o, &["room.yaml", "no known"]);
}

#[test]
fn malformed_yaml_and_pgm_are_clear_errors() {
    let dir = tempdir();
    let root = dataset(&dir);
    let yaml = root.join("map/room.yaml");
    let good = std::fs::read_to_string(&yaml).unwrap();
    std::fs::write(
        &yaml,
        good.replace("resolution: 0.05", "resolution: five cm"),
    )
    .unwrap();
    assert_clear_error(
        &map_with(&root, &["--doas", arg(&root.join("doas.csv"))]),
        &["room.yaml", "resolution"],
    );
    std::fs::write(
        &yaml,
        good.replace("origin: [-1.0, -3.0, 0.0]", "origin: [-1.0, -3.0, 0.5]"),
    )
    .unwrap();
    assert_clear_error(
        &map_with(&root, &["--doas", arg(&root.join("doas.csv"))]),
        &["room.yaml", "yaw"],
    );
    std::fs::write(&yaml, good).unwrap();
    std::fs::write(root.join("map/room.pgm"), b"P5\n160 120\n255\nshort").unwrap();
    assert_clear_error(
        &map_with(&root, &["--doas", arg(&root.join("doas.csv"))]),
        &["room.pgm", "bytes"],
    );
}

#[test]
fn r13_an_absurd_map_resolution_is_a_clear_error_not_a_panic() {
    // resolution: 999999999990.05 once made the DBSCAN grid overflow its allocation.
    let dir = tempdir();
    let root = dataset(&dir);
    let yaml = root.join("map/room.yaml");
    let text = std::fs::read_to_string(&yaml)
        .unwrap()
        .replace("resolution: 0.05", "resolution: 999999999990.05");
    std::fs::write(&yaml, text).unwrap();
    let t0 = std::time::Instant::now();
    let o = iasm(&[
        "map",
        "--map",
        arg(&yaml),
        "--poses",
        arg(&root.join("pose/poses.csv")),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
    ]);
    assert_clear_error(&o, &["room.yaml", "resolution"]);
    assert!(t0.elapsed().as_secs_f64() < 5.0, "{:?}", t0.elapsed());
}

// See: issue 13

#[test]
fn r13_a_ros_exported_pose_csv_with_a_quaternion_maps_like_the_plain_table() {
    let dir = tempdir();
    let root = dataset(&dir);
    let mut ros = String::from(
        "stamp,frame_id,pose.position.x,pose.position.y,pose.position.z,\
         pose.orientation.x,pose.orientation.y,pose.orientation.z,pose.orientation.w\n",
    );
    for (k, &(x, y, th)) in drive().iter().enumerate() {
        let half = th.to_radians() / 2.0;
        ros.push_str(&format!(
            "{k}.0,map,{x},{y},0.0,0.0,0.0,{},{}\n",
            half.sin(),
            half.cos()
        ));
    }
    let ros_path = path(&dir, "ros_poses.csv");
    std::fs::write(&ros_path, ros).unwrap();
    let run = |poses: &Path| {
        json(&iasm(&[
            "map",
            "--dataset",
            arg(&root),
            "--poses",
            arg(poses),
            "--doas",
            arg(&root.join("doas.csv")),
            "--num",
            "3",
            "--json",
        ]))
    };
    let plain = run(&root.join("pose/poses.csv"));
    let v = run(&ros_path);
    assert_eq!(v["sources"].as_array().unwrap().len(), 3, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.15, "{v}");
    assert!(
        (v["ospa"]["total"].as_f64().unwrap() - plain["ospa"]["total"].as_f64().unwrap()).abs()
            < 1e-6,
        "{v}\n{plain}"
    );
}

// See: issue 13

#[test]
fn r13_a_map_yaml_with_a_quoted_hash_and_a_block_origin_is_read_as_yaml() {
    let dir = tempdir();
    let root = dataset(&dir);
    std::fs::rename(root.join("map/room.pgm"), root.join("map/room#1.pgm")).unwrap();
    std::fs::write(
        root.join("map/room.yaml"),
        "image: \"room#1.pgm\"   # quoted: the # is part of the name\nresolution: 0.05\n\
         origin:\n  - -1.0\n  - -3.0\n  - 0.0\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv")), "--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("warning"), "{}", show(&o)); // the named image was found
    let v = json(&o);
    assert_eq!(v["sources"].as_array().unwrap().len(), 3, "{v}");
    assert!(v["ospa"]["total"].as_f64().unwrap() < 0.15, "{v}");
}

/// Poses in another frame than the map (every stop 100 m off it) are an error that says
/// so, not an empty map with exit 0; the same poses in the map's frame map the sources.
// See: issue 71 (`poses_II_100m_off.csv`)
#[test]
fn r71_stops_that_all_lie_outside_the_map_are_a_clear_error() {
    let dir = tempdir();
    let root = dataset(&dir);
    let o = map_with(&root, &["--doas", arg(&root.join("doas.csv"))]);
    assert!(o.status.success(), "{}", show(&o));
    let far: String = drive()
        .iter()
        .map(|(x, y, th)| format!("{},{y},{th}\n", x + 100.0))
        .collect();
    std::fs::write(root.join("far.csv"), far).unwrap();
    let o = map_with(
        &root,
        &[
            "--doas",
            arg(&root.join("doas.csv")),
            "--poses",
            arg(&root.join("far.csv")),
        ],
    );
    assert_clear_error(
        &o,
        &[
            "none of the 20 stops lies in the occupancy map",
            "map's frame",
        ],
    );
}

/// An OSPA order whose c^p overflows a double is computed relative to c: `--ospa-p 400`
/// prints a finite OSPA; an order below 1 or a cutoff that is not finite is refused.
// See: issue 71
#[test]
fn r71_an_ospa_order_beyond_a_double_gives_a_finite_figure() {
    let dir = tempdir();
    let root = dataset(&dir);
    let o = map_with(
        &root,
        &[
            "--doas",
            arg(&root.join("doas.csv")),
            "--ospa-p",
            "400",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", show(&o));
    let total = json(&o)["ospa"]["total"].as_f64().unwrap();
    assert!(total.is_finite() && (0.0..=1.0).contains(&total), "{total}");
    let doas = root.join("doas.csv");
    for bad in [["--ospa-p", "0.5"], ["--ospa-c", "inf"]] {
        let mut args = vec!["--doas", arg(&doas)];
        args.extend_from_slice(&bad);
        let o = map_with(&root, &args);
        assert_clear_error(&o, &["finite"]);
    }
}
