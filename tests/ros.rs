//! `--mcap`: a map as ROS 2 messages, read back and decoded, each message checked against
//! what it must hold: the map JSON's sources and covariances, the pose table, the rays
//! towards the true sources, and the occupancy map's cells (decoded by `bag`'s own CDR
//! reader, written independently of `iasm-ros`).

use std::path::Path;

use iasm_ros::msg::{Marker, MarkerArray, Message, Path as RosPath, PoseArray};

use crate::util::*;

const TRUTH: [[f64; 2]; 3] = [[1.5, 1.5], [4.0, -1.2], [5.5, 2.0]];

/// One message as the file holds it.
struct Read {
    topic: String,
    schema: String,
    schema_encoding: String,
    encoding: String,
    qos: String,
    log_time: u64,
    data: Vec<u8>,
}

fn read_mcap(path: &Path) -> Vec<Read> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            Read {
                topic: m.channel.topic.clone(),
                schema: schema.name.clone(),
                schema_encoding: schema.encoding.clone(),
                encoding: m.channel.message_encoding.clone(),
                qos: m
                    .channel
                    .metadata
                    .get("offered_qos_profiles")
                    .cloned()
                    .unwrap_or_default(),
                log_time: m.log_time,
                data: m.data.into_owned(),
            }
        })
        .collect()
}

/// The test room with a wall (occupied) along x = 3 from y = 0.5 to 1.5 and an unknown
/// block in the top-left corner: a grid whose cells tell its rows apart.
fn walled(root: &Path) {
    mapping_dataset(root, &TRUTH, &drive());
    let (w, h) = (160usize, 120usize);
    let mut px = vec![254u8; w * h];
    for j in 0..h {
        for i in 0..w {
            // Cell (i, j) of the image, row 0 at the top: world x = -1 + 0.05 (i + 0.5),
            // y = -3 + 0.05 (h - 1 - j + 0.5).
            let (x, y) = (
                -1.0 + 0.05 * (i as f64 + 0.5),
                -3.0 + 0.05 * ((h - 1 - j) as f64 + 0.5),
            );
            if (2.9..3.1).contains(&x) && (0.5..1.5).contains(&y) {
                px[j * w + i] = 0;
            } else if x < 0.0 && y > 2.0 {
                px[j * w + i] = 205;
            }
        }
    }
    let mut pgm = format!("P5\n{w} {h}\n255\n").into_bytes();
    pgm.extend(px);
    std::fs::write(root.join("map/room.pgm"), pgm).unwrap();
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn a_maps_mcap_holds_its_sources_ellipses_rays_path_and_grid_in_frame_map() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    walled(&root);
    let (out, file) = (path(&dir, "m.json"), path(&dir, "m.mcap"));
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--num",
        "3",
        "--seed",
        "4",
        "--out",
        arg(&out),
        "--mcap",
        arg(&file),
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let v = json_file(&out);
    assert_eq!(v["frame_id"], "map");
    let sources = v["sources"].as_array().unwrap();
    assert_eq!(sources.len(), 3, "{v}");
    let msgs = read_mcap(&file);
    let topics: Vec<&str> = msgs.iter().map(|m| m.topic.as_str()).collect();
    assert_eq!(
        topics,
        [
            "/map",
            "/iasm/path",
            "/iasm/doas",
            "/iasm/sources",
            "/iasm/source_poses"
        ]
    );
    for m in &msgs {
        assert_eq!(
            (m.schema_encoding.as_str(), m.encoding.as_str()),
            ("ros2msg", "cdr")
        );
        // The last of 20 stops, one second apart.
        assert_eq!(m.log_time, 19_000_000_000);
        // /map is offered transient local (durability 1), the rest volatile (2).
        let durability = if m.topic == "/map" {
            "durability: 1"
        } else {
            "durability: 2"
        };
        assert!(
            m.qos.contains(durability) && m.qos.contains("reliability: 1"),
            "{}",
            m.qos
        );
    }
    let by = |t: &str| msgs.iter().find(|m| m.topic == t).unwrap();

    grid_is_the_pgms(by("/map"));
    poses_are_the_jsons(&by("/iasm/source_poses").data, sources);
    markers_are_the_jsons(&by("/iasm/sources").data, sources);
    path_is_the_pose_tables(&by("/iasm/path").data);
    rays_point_at_the_truth(&by("/iasm/doas").data);
}

/// `/map`, decoded by the bag reader: the PGM's cells of [`walled`], rows from the bottom.
fn grid_is_the_pgms(m: &Read) {
    assert_eq!(m.schema, "nav_msgs/msg/OccupancyGrid");
    let g = bag::msg::grid(bag::msg::Encoding::Cdr, &m.data).unwrap();
    assert_eq!(
        (g.frame_id.as_str(), g.width, g.height, g.resolution),
        ("map", 160, 120, 0.05)
    );
    assert!((g.origin.x + 1.0).abs() < 1e-12 && (g.origin.y + 3.0).abs() < 1e-12);
    let cell = |x: f64, y: f64| {
        let (i, r) = (((x + 1.0) / 0.05) as usize, ((y + 3.0) / 0.05) as usize);
        g.data[r * 160 + i]
    };
    assert_eq!(cell(3.0, 1.0), 100);
    assert_eq!(cell(3.0, 0.4), 0);
    assert_eq!(cell(-0.5, 2.5), -1);
    assert_eq!(cell(-0.5, 1.9), 0);
    assert_eq!(g.data.iter().filter(|&&c| c == 100).count(), 4 * 20);
    assert_eq!(g.data.iter().filter(|&&c| c == -1).count(), 20 * 20);
}

/// `/iasm/source_poses`, the sources for programs: the JSON's, in its order.
fn poses_are_the_jsons(data: &[u8], sources: &[serde_json::Value]) {
    let poses = PoseArray::from_cdr(data).unwrap();
    assert_eq!(poses.header.frame_id, "map");
    assert_eq!(poses.poses.len(), 3);
    for (p, s) in poses.poses.iter().zip(sources) {
        assert!((p.position.x - f(&s["x"])).abs() < 1e-12, "{p:?} {s}");
        assert!((p.position.y - f(&s["y"])).abs() < 1e-12, "{p:?} {s}");
    }
}

/// `/iasm/sources`: a DELETEALL, then per source of the JSON a sphere, its 2-sigma
/// ellipse and a label.
fn markers_are_the_jsons(data: &[u8], sources: &[serde_json::Value]) {
    let markers = MarkerArray::from_cdr(data).unwrap().markers;
    assert_eq!(markers[0].action, Marker::DELETEALL);
    for (k, s) in sources.iter().enumerate() {
        let find = |ns: &str| {
            markers
                .iter()
                .find(|m| m.ns == ns && m.id == k as i32)
                .unwrap_or_else(|| panic!("{ns} {k}"))
        };
        let (x, y) = (f(&s["x"]), f(&s["y"]));
        let sphere = find("sources");
        assert_eq!(
            (sphere.kind, sphere.header.frame_id.as_str()),
            (Marker::SPHERE, "map")
        );
        assert!((sphere.pose.position.x - x).abs() < 1e-12);
        assert!((sphere.pose.position.y - y).abs() < 1e-12);
        // The label names the source, its DoAs and, for one silent at the end, since when;
        // a silent source's sphere is grey.
        let label = find("labels");
        let mut text = format!("s{}: {} DoAs", k + 1, s["observations"]);
        if s["state"] == "silent" {
            text += &format!(", silent since stop {}", s["since"]);
        }
        assert_eq!(label.text, text);
        assert_eq!(s["state"] == "silent", sphere.color.r < 0.6, "{s}");
        // The ellipse's diameters are 4 sigma along its axes: R diag((a/4)², (b/4)²) Rᵀ is
        // the JSON's covariance.
        let e = find("ellipses");
        assert_eq!(e.kind, Marker::CYLINDER);
        let phi = e.pose.orientation.to_yaw();
        let (a, b) = ((e.scale.x / 4.0).powi(2), (e.scale.y / 4.0).powi(2));
        let (c, sn) = (phi.cos(), phi.sin());
        let cov = [
            [a * c * c + b * sn * sn, (a - b) * c * sn],
            [(a - b) * c * sn, a * sn * sn + b * c * c],
        ];
        let want = &s["covariance"];
        for i in 0..2 {
            for j in 0..2 {
                let w = f(&want[i][j]);
                assert!(
                    (cov[i][j] - w).abs() <= 1e-9 * (1.0 + w.abs()),
                    "{k}: {cov:?} {want}"
                );
            }
        }
    }
}

/// `/iasm/path`: the pose table's stops, with headings, a second apart.
fn path_is_the_pose_tables(data: &[u8]) {
    let path = RosPath::from_cdr(data).unwrap();
    let stops = drive();
    assert_eq!(path.poses.len(), stops.len());
    for (k, (p, &(x, y, th))) in path.poses.iter().zip(&stops).enumerate() {
        assert_eq!((p.pose.position.x, p.pose.position.y), (x, y));
        assert!(ssl::wrap_deg(p.pose.orientation.to_yaw().to_degrees() - th).abs() < 1e-9);
        assert_eq!(p.header.stamp.ns(), k as i64 * 1_000_000_000);
    }
}

/// `/iasm/doas`: per stop, one segment per DoA from the robot, 5 m long, pointing at a
/// true source (the table's DoAs are the exact bearings).
fn rays_point_at_the_truth(data: &[u8]) {
    let stops = drive();
    let rays = MarkerArray::from_cdr(data).unwrap().markers;
    assert_eq!(rays.len(), stops.len());
    for (k, (m, &(x, y, _))) in rays.iter().zip(&stops).enumerate() {
        assert_eq!(
            (m.kind, m.id, m.ns.as_str()),
            (Marker::LINE_LIST, k as i32, "doas")
        );
        assert_eq!(m.points.len(), 2 * TRUTH.len());
        for (pair, s) in m.points.chunks(2).zip(&TRUTH) {
            assert_eq!((pair[0].x, pair[0].y), (x, y));
            let (dx, dy) = (pair[1].x - x, pair[1].y - y);
            assert!((dx.hypot(dy) - 5.0).abs() < 1e-9);
            let miss =
                ssl::wrap_deg(dy.atan2(dx).to_degrees() - (s[1] - y).atan2(s[0] - x).to_degrees());
            assert!(miss.abs() < 0.01, "stop {k}: {miss}");
        }
    }
}

#[test]
fn a_replays_mcap_grows_the_map_one_stamped_update_per_stop() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let (out, file) = (path(&dir, "w.json"), path(&dir, "w.mcap"));
    let o = iasm(&[
        "watch",
        arg(&root),
        "--replay",
        "--num",
        "2",
        "--seed",
        "3",
        "--out",
        arg(&out),
        "--mcap",
        arg(&file),
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let msgs = read_mcap(&file);
    // The grid once; every other topic once per stop and once for the final map.
    assert_eq!(msgs.iter().filter(|m| m.topic == "/map").count(), 1);
    let paths: Vec<&Read> = msgs.iter().filter(|m| m.topic == "/iasm/path").collect();
    assert_eq!(paths.len(), 21);
    for (k, m) in paths.iter().enumerate() {
        assert_eq!(m.log_time, k as u64 * 1_000_000_000);
        let p = RosPath::from_cdr(&m.data).unwrap();
        assert_eq!(p.poses.len(), (k + 1).min(20));
    }
    // The last update is the final map the JSON holds.
    let fin = json_file(&out);
    assert_eq!(fin["frame_id"], "map");
    let last = msgs
        .iter()
        .rev()
        .find(|m| m.topic == "/iasm/source_poses")
        .unwrap();
    let poses = PoseArray::from_cdr(&last.data).unwrap();
    let want = sources_of(&fin);
    assert_eq!(poses.poses.len(), want.len());
    for (p, s) in poses.poses.iter().zip(&want) {
        // serde_json's float reading may differ in the last bit.
        assert!((p.position.x - s[0]).abs() < 1e-12 && (p.position.y - s[1]).abs() < 1e-12);
    }
}

#[test]
fn an_mcap_that_cannot_be_written_is_a_clear_error() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    mapping_dataset(&root, &TRUTH, &drive());
    let o = iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--doas",
        arg(&root.join("doas.csv")),
        "--mcap",
        arg(&root),
    ]);
    assert_clear_error(&o, &["is a folder"]);
}

/// The robot run of `fixtures/bags/sim_run.mcap` (six stops past two talkers, recorded as
/// a ROS 2 robot records it) fed to the live mapper message by message, as the node
/// receives them: each stop is mapped once the robot has left it (the last when the run
/// ends), and the final map is the one `iasm bag --out` then `iasm map` makes of the same
/// stops with the same seed.
#[test]
fn the_live_mapper_fed_a_bag_maps_what_bag_then_map_maps() {
    let bag_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags/sim_run.mcap");
    let mut live = iasm::live::LiveMapper::new(
        iasm::settings::Settings::default(),
        bag::ReadOptions::default(),
        bag::StopOptions::default(),
        5,
    )
    .unwrap();
    let mut mapped_at = Vec::new();
    bag::ros2::scan_files(&bag_path, |m| {
        assert_eq!(
            live.push(
                &m.connection.topic,
                &m.connection.msg_type,
                m.time_ns,
                m.data
            ),
            None
        );
        let (updates, _) = live.step(false);
        mapped_at.extend(updates.iter().map(|u| (u.record.stop, m.time_ns)));
        Ok(())
    })
    .unwrap();
    // Stops 1-5 while recording, each before the robot reached the next (1.5 s apart).
    assert_eq!(
        mapped_at.iter().map(|s| s.0).collect::<Vec<_>>(),
        [1, 2, 3, 4, 5]
    );
    let (last, warnings) = live.step(true);
    assert_eq!(last.len(), 1, "{warnings:?}");
    let fin = live.finish().unwrap();
    assert!(live.notes().is_empty(), "{:?}", live.notes());

    let dir = tempdir();
    let ds = path(&dir, "ds");
    let o = iasm(&["bag", arg(&bag_path), "--out", arg(&ds)]);
    assert!(o.status.success(), "{}", show(&o));
    let batch = json(&iasm(&[
        "map",
        "--dataset",
        arg(&ds),
        "--seed",
        "5",
        "--json",
    ]));
    let want = sources_of(&batch);
    assert_eq!(fin.sources.len(), 2);
    assert_eq!(want.len(), 2);
    for (s, w) in fin.sources.iter().zip(&want) {
        assert!((s.x - w[0]).hypot(s.y - w[1]) < 1e-9, "{s:?} {w:?}");
    }
    // The stops are the bag's: the pose table `iasm bag` wrote.
    let poses = std::fs::read_to_string(ds.join("pose/poses.csv")).unwrap();
    assert_eq!(live.stops().len(), poses.lines().count() - 1);
    // And both are near the talkers the scene placed at (2.0, 4.0) and (4.5, 1.0).
    let truth = [[2.0, 4.0], [4.5, 1.0]];
    for t in truth {
        assert!(
            fin.sources
                .iter()
                .any(|s| (s.x - t[0]).hypot(s.y - t[1]) < 0.1),
            "{:?}",
            fin.sources
        );
    }
}

/// A prior map (`iasm ros2 --prior`): every map of the run is compared with it. The bag's
/// talkers stand at (2.0, 4.0) and (4.5, 1.0); the prior has the first where it is, the
/// second 2 m north (so it moved), and a third at (0.5, 0.5) that the run does not hear
/// (removed). The JSON lists the changes and the messages carry them as markers.
#[test]
fn a_live_mapper_with_a_prior_says_what_changed_against_it() {
    let bag_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags/sim_run.mcap");
    let dir = tempdir();
    let prior_path = path(&dir, "prior.json");
    std::fs::write(&prior_path, PRIOR_MAP).unwrap();
    let prior = iasm::mapfile::MapFile::read(&prior_path).unwrap();
    let mut live = iasm::live::LiveMapper::new(
        iasm::settings::Settings::default(),
        bag::ReadOptions::default(),
        bag::StopOptions::default(),
        5,
    )
    .unwrap()
    .with_prior(prior);
    bag::ros2::scan_files(&bag_path, |m| {
        live.push(
            &m.connection.topic,
            &m.connection.msg_type,
            m.time_ns,
            m.data,
        );
        live.step(false);
        Ok(())
    })
    .unwrap();
    live.step(true);
    let fin = live.finish().unwrap();
    let report = serde_json::to_value(live.report(&fin, true)).unwrap();
    assert_eq!(report["prior"], arg(&prior_path));
    let kinds: Vec<(&str, u64)> = report["changes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["kind"].as_str().unwrap(),
                c["before"].as_u64().unwrap_or(99),
            )
        })
        .collect();
    assert_eq!(
        kinds,
        [("kept", 0), ("moved", 1), ("removed", 2)],
        "{report:#}"
    );
    let moved = &report["changes"][1];
    assert!(
        (moved["distance_m"].as_f64().unwrap() - 2.0).abs() < 0.15,
        "{moved}"
    );
    let m = live.messages(&fin, 7).unwrap();
    let markers = m.changes.expect("the changes' markers").markers;
    let ns = |n: &str| markers.iter().filter(|k| k.ns == n).count();
    assert_eq!(
        (
            ns("kept"),
            ns("moved"),
            ns("removed"),
            ns("added"),
            ns("change_arrows")
        ),
        (1, 1, 1, 0, 1)
    );
    let removed = markers.iter().find(|k| k.ns == "removed").unwrap();
    assert_eq!(
        (removed.pose.position.x, removed.pose.position.y),
        (0.5, 0.5)
    );
    assert!(markers.iter().all(|k| k.header.frame_id == "map"));
}

/// The prior map of the tests above (frame `map`).
const PRIOR_MAP: &str = r#"{"frame_id": "map", "sources": [
    {"x": 2.0, "y": 4.0, "covariance": [[0.004, 0.0], [0.0, 0.004]]},
    {"x": 4.5, "y": 3.0, "covariance": [[0.004, 0.0], [0.0, 0.004]]},
    {"x": 0.5, "y": 0.5, "covariance": [[0.004, 0.0], [0.0, 0.004]]}]}"#;

/// Whether this process may make a network namespace of its own (root, or a user namespace
/// allowed): the DDS tests run only inside one, so that no packet leaves the machine.
#[cfg(feature = "ros2")]
fn own_network_namespace() -> Result<(), String> {
    match std::process::Command::new("unshare")
        .args(["--net", "true"])
        .output()
    {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(String::from_utf8_lossy(&o.stderr).trim().to_owned()),
        Err(e) => Err(format!("unshare: {e}")),
    }
}

/// Whether a DDS test may run here: only in a network namespace of its own, so that no
/// packet leaves the machine. Where none can be made it says `skipped:`, unless
/// IASM_REQUIRE_ROS2_TEST is set (CI runs as root and must run them: there, a skip is a
/// failure).
#[cfg(feature = "ros2")]
fn may_run_dds() -> bool {
    let Err(why) = own_network_namespace() else {
        return true;
    };
    assert!(
        std::env::var_os("IASM_REQUIRE_ROS2_TEST").is_none(),
        "IASM_REQUIRE_ROS2_TEST is set but no network namespace can be made here ({why})"
    );
    eprintln!(
        "skipped: no network namespace of its own can be made here ({why}); DDS must not reach the host's network"
    );
    false
}

/// The node on a robot: inside a network namespace of its own (only `lo`, multicast on it),
/// `iasm ros2-play` publishes `fixtures/bags/sim_run.mcap` as the robot published it
/// (AudioStamped, Odometry, a transient-local OccupancyGrid; stamps moved to now), `iasm
/// ros2` maps it live and, on Ctrl-C, publishes and writes its final map; the player,
/// subscribed to `/iasm/source_poses`, hears sources within 0.02 m of what `iasm bag --out`
/// then `iasm map` make of the same bag with the same seed.
#[cfg(feature = "ros2")]
#[test]
fn ros2_node_maps_a_robot_run_live_as_map_maps_the_bag() {
    if !may_run_dds() {
        return;
    }
    let dir = tempdir();
    let bag_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags/sim_run.mcap");
    // With a prior map: every update also says what changed against it.
    std::fs::write(dir.path().join("prior.json"), PRIOR_MAP).unwrap();
    let logs = run_node_and_player(dir.path(), &bag_path);

    let ds = path(&dir, "ds");
    let o = iasm(&["bag", arg(&bag_path), "--out", arg(&ds)]);
    assert!(o.status.success(), "{}", show(&o));
    let want = sources_of(&json(&iasm(&[
        "map",
        "--dataset",
        arg(&ds),
        "--seed",
        "5",
        "--json",
    ])));
    assert_eq!(want.len(), 2);
    let close = |got: &[[f64; 2]], what: &str| {
        assert_eq!(got.len(), want.len(), "{what}: {got:?}\n{logs}");
        for (g, w) in got.iter().zip(&want) {
            let d = (g[0] - w[0]).hypot(g[1] - w[1]);
            assert!(d < 0.02, "{what}: {g:?} is {d} m from {w:?}\n{logs}");
        }
    };
    close(
        &sources_of(&json_file(&dir.path().join("heard.json"))),
        "heard on /iasm/source_poses",
    );
    let node = json_file(&dir.path().join("node.json"));
    assert_eq!(
        (node["final_map"].as_bool(), node["frame_id"].as_str()),
        (Some(true), Some("map"))
    );
    close(&sources_of(&node), "the node's final map JSON");
    // The MCAP of the live run: one update per stop and the final map, all in frame map.
    let msgs = read_mcap(&dir.path().join("node.mcap"));
    let updates: Vec<&Read> = msgs
        .iter()
        .filter(|m| m.topic == "/iasm/source_poses")
        .collect();
    assert_eq!(updates.len(), 7, "{logs}");
    let changes: Vec<&Read> = msgs.iter().filter(|m| m.topic == "/iasm/changes").collect();
    assert_eq!(changes.len(), 7, "{logs}");
    let last_changes = MarkerArray::from_cdr(&changes[6].data).unwrap();
    let ns: Vec<&str> = last_changes
        .markers
        .iter()
        .filter(|k| k.kind == Marker::SPHERE && k.action == Marker::ADD)
        .map(|k| k.ns.as_str())
        .collect();
    assert_eq!(ns, ["kept", "moved", "removed"], "{logs}");
    let kinds: Vec<&str> = node["changes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["kept", "moved", "removed"], "{logs}");
    let last = PoseArray::from_cdr(&updates[6].data).unwrap();
    assert_eq!(last.header.frame_id, "map");
    close(
        &last
            .poses
            .iter()
            .map(|p| [p.position.x, p.position.y])
            .collect::<Vec<_>>(),
        "the MCAP's last update",
    );
}

/// A `--ros-args` block the node cannot take is refused before any DDS starts, with what
/// is wrong in it: a parameter that is no setting (the list of those that are), a value
/// the setting's flag refuses, a parameters file that is not there, an option rcl has
/// and iasm does not read, the block given to a command that is no node, and a prior map
/// that is not there.
#[cfg(feature = "ros2")]
#[test]
fn a_ros_args_block_the_node_cannot_take_is_refused_with_its_reason() {
    for (args, says) in [
        (
            &["ros2", "--ros-args", "-p", "nonesuch:=1"][..],
            "still_radius",
        ),
        (
            &["ros2", "--ros-args", "-p", "method:=nonesuch"],
            "nonesuch",
        ),
        (
            &["ros2", "--ros-args", "--params-file", "/nonexistent/p.yaml"],
            "/nonexistent/p.yaml",
        ),
        (&["ros2", "--ros-args", "-x"], "\"-x\""),
        (
            &["ros2", "--prior", "/nonexistent/prior.json"],
            "/nonexistent/prior.json",
        ),
        (
            &["map", "--ros-args", "-r", "a:=b"],
            "iasm ros2, ros2-merge and ros2-play only",
        ),
    ] {
        let o = iasm(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", show(&o));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

/// The node as ROS users run it: in a namespace under another name (`--ros-args -r
/// __ns:=/robot1 -r __node:=mapper`), its audio topic remapped (`-r audio:=mic/audio`),
/// settings from a ROS 2 parameters file and `-p`, on the bag's time (`use_sim_time`,
/// the player publishing /clock and keeping the bag's stamps, as `ros2 bag play --clock`
/// does). While the bag plays, the method set through the parameter services takes effect
/// at the next stop and a setting read at start is refused with its reason; the services
/// save the map to the path a parameter gives, return it, and clear it.
#[cfg(feature = "ros2")]
#[test]
fn ros2_node_runs_with_ros_args_parameters_services_and_the_bags_clock() {
    if !may_run_dds() {
        return;
    }
    let dir = tempdir();
    let work = dir.path();
    std::fs::write(
        work.join("params.yaml"),
        "/**:\n  ros__parameters:\n    seed: 5\n\
         /robot1/mapper:\n  ros__parameters:\n    method: gcc-phat\n    audio_topic: audio\n\
         /robot2/mapper:\n  ros__parameters:\n    method: music\n",
    )
    .unwrap();
    let script = r#"
set -u
ip link set lo up multicast on
ip route add 224.0.0.0/4 dev lo
cd "$WORK"
"$IASM" ros2 --out node.json --mcap node.mcap --ros-args -r __ns:=/robot1 -r __node:=mapper \
    -r audio:=mic/audio --params-file params.yaml -p use_sim_time:=true -p save_to:=saved.json \
    > node.log 2> node.err &
NODE=$!
"$IASM" ros2-play "$BAG" --clock --listen heard.json --linger 120 \
    --ros-args -r __ns:=/robot1 -r audio:=mic/audio > play.log 2> play.err &
PLAY=$!
for i in $(seq 1 600); do grep -q '^stop   2' node.log && break; sleep 0.1; done
"$IASM" ros2-call /robot1/mapper set method mvdr > set.log 2>&1; echo "set $?"
"$IASM" ros2-call /robot1/mapper set audio_topic /elsewhere > refused.log 2>&1; echo "refused $?"
"$IASM" ros2-call /robot1/mapper get method > get.log 2>&1; echo "get $?"
for i in $(seq 1 600); do grep -q '^played' play.log && break; sleep 0.1; done
sleep 0.5
"$IASM" ros2-call /robot1/mapper save_map > save.log 2>&1; echo "save $?"
"$IASM" ros2-call /robot1/mapper get_map > map.json 2> get_map.err; echo "get_map $?"
"$IASM" ros2-call /robot1/mapper clear_map > clear.log 2>&1; echo "clear $?"
kill -INT $NODE
wait $NODE; echo "node $?"
kill -INT $PLAY
wait $PLAY; echo "play $?"
"#;
    let bag_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags/sim_run.mcap");
    let (o, logs) = in_own_network(
        script,
        work,
        &bag_path,
        &["set.log", "refused.log", "save.log"],
    );
    let read = |n: &str| std::fs::read_to_string(work.join(n)).unwrap_or_default();
    let out = String::from_utf8_lossy(&o.stdout);
    for step in [
        "set 0",
        "refused 2",
        "get 0",
        "save 0",
        "get_map 0",
        "clear 0",
        "node 0",
        "play 0",
    ] {
        assert!(out.contains(step), "{step}\n{logs}");
    }
    // The namespace and the remap: the robot's audio, on /robot1/mic/audio, is the node's
    // /robot1/audio; the player heard the node's sources in the namespace.
    assert!(
        read("node.err").contains("subscribed to /robot1/mic/audio as /robot1/audio"),
        "{logs}"
    );
    assert!(
        read("play.log").contains("on /robot1/iasm/source_poses"),
        "{logs}"
    );
    // The method set while the bag played: GCC-PHAT (the file's) before, MVDR after.
    assert!(read("refused.log").contains("restart the node"), "{logs}");
    assert_eq!(read("get.log").trim(), "method: mvdr", "{logs}");
    let saved = json_file(&work.join("saved.json"));
    let methods: Vec<&str> = saved["stops"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["method"].as_str().unwrap())
        .collect();
    assert_eq!(methods.len(), 5, "{methods:?}\n{logs}");
    assert_eq!(&methods[..2], ["gcc-phat", "gcc-phat"], "{logs}");
    assert_eq!(methods[4], "mvdr", "{logs}");
    assert_eq!(saved["seed"].as_u64(), Some(5));
    // The map returned by get_map: both talkers of the scene (fixtures/bags/sim).
    let got = sources_of(&json_file(&work.join("map.json")));
    let truth = [[2.0, 4.0], [4.5, 1.0]];
    assert_eq!(got.len(), 2, "{got:?}\n{logs}");
    for t in truth {
        let d = got
            .iter()
            .map(|g| (g[0] - t[0]).hypot(g[1] - t[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(d < 0.15, "{t:?}: nearest source {d} m off\n{logs}");
    }
    // clear_map forgot the five stops: the final map holds the sixth alone.
    assert!(read("clear.log").contains("5 stops forgotten"), "{logs}");
    assert_eq!(
        json_file(&work.join("node.json"))["stops"]
            .as_array()
            .map(Vec::len),
        Some(1),
        "{logs}"
    );
    // The node's time was the bag's (/clock), not the wall clock: every update of the
    // MCAP is stamped within the bag's 8.6 s.
    let first_ns = 1_700_000_000_000_000_000u64;
    for m in read_mcap(&work.join("node.mcap")) {
        assert!(
            (first_ns..first_ns + 10_000_000_000).contains(&m.log_time),
            "{} at {}\n{logs}",
            m.topic,
            m.log_time
        );
    }
}

/// Two robots, one building, live: robot 1 (`/robot1`, the hall of
/// `fixtures/buildings`) and robot 2 (`/robot2`, the wing) each map their own run and
/// publish their stops on `~/stops`; `iasm ros2-merge` merges them. Robot 2 joins three
/// seconds late, and robot 1 leaves the network as soon as its run is played, before robot
/// 2 ends. The merged map keeps robot 1's stops and adds robot 2's; it holds every talker,
/// within 0.02 m of `iasm map --dataset A --dataset B` on the two bags' data sets, and
/// each robot's own map misses the talker only the other robot heard.
#[cfg(feature = "ros2")]
#[test]
fn ros2_merge_maps_two_robots_live_as_map_maps_their_union() {
    if !may_run_dds() {
        return;
    }
    let dir = tempdir();
    let work = dir.path();
    let script = r#"
set -u
ip link set lo up multicast on
ip route add 224.0.0.0/4 dev lo
cd "$WORK"
"$IASM" ros2-merge --seed 5 --map-topic /robot1/map --out merged.json > merge.log 2> merge.err &
MERGE=$!
"$IASM" ros2 --seed 5 --out r1.json --ros-args -r __ns:=/robot1 > r1.log 2> r1.err &
R1=$!
"$IASM" ros2-play "$BAG/building_west.mcap" --ros-args -r __ns:=/robot1 > play.log 2> play.err &
P1=$!
sleep 3
"$IASM" ros2 --seed 5 --out r2.json --ros-args -r __ns:=/robot2 > node.log 2> node.err &
R2=$!
"$IASM" ros2-play "$BAG/building_wing.mcap" --ros-args -r __ns:=/robot2 > p2.log 2> p2.err &
P2=$!
wait $P1; echo "p1 $?"
sleep 0.5
kill -INT $R1; wait $R1; echo "r1 $?"
wait $P2; echo "p2 $?"
sleep 0.5
kill -INT $R2; wait $R2; echo "r2 $?"
sleep 1
kill -INT $MERGE; wait $MERGE; echo "merge $?"
"#;
    let bags = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags");
    let (o, logs) = in_own_network(
        script,
        work,
        &bags,
        &["merge.log", "merge.err", "r1.log", "r1.err"],
    );
    let out = String::from_utf8_lossy(&o.stdout);
    for step in ["p1 0", "r1 0", "p2 0", "r2 0", "merge 0"] {
        assert!(out.contains(step), "{step}\n{logs}");
    }
    let merged = json_file(&work.join("merged.json"));
    assert_eq!(merged["final_map"].as_bool(), Some(true), "{logs}");
    assert_eq!(merged["runs"]["/robot1/iasm"].as_u64(), Some(5), "{logs}");
    assert_eq!(merged["runs"]["/robot2/iasm"].as_u64(), Some(5), "{logs}");
    // The offline union of the same runs.
    let mut args = vec!["map".to_owned()];
    for (bag, ds) in [
        ("building_west.mcap", "west"),
        ("building_wing.mcap", "wing"),
    ] {
        let d = work.join(ds);
        let o = iasm(&["bag", arg(&bags.join(bag)), "--out", arg(&d)]);
        assert!(o.status.success(), "{}", show(&o));
        args.extend(["--dataset".to_owned(), d.display().to_string()]);
    }
    args.extend(["--seed", "5", "--json"].map(str::to_owned));
    let union = sources_of(&json(&iasm(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    )));
    let got = sources_of(&merged);
    assert_eq!(got.len(), union.len(), "{got:?} {union:?}\n{logs}");
    assert_eq!(union.len(), 3, "{union:?}");
    for (g, w) in got.iter().zip(&union) {
        let d = (g[0] - w[0]).hypot(g[1] - w[1]);
        assert!(d < 0.02, "{g:?} is {d} m from {w:?}\n{logs}");
    }
    // Each robot's own map misses the other's talker; the merged map has it.
    let near = |map: &[[f64; 2]], p: [f64; 2]| {
        map.iter()
            .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
            .fold(f64::INFINITY, f64::min)
    };
    let (hall, wing) = ([1.2, 2.5], [7.3, 7.2]);
    let r1 = sources_of(&json_file(&work.join("r1.json")));
    let r2 = sources_of(&json_file(&work.join("r2.json")));
    assert!(
        near(&r1, wing) > 0.5 && near(&r2, hall) > 0.5,
        "{r1:?} {r2:?}"
    );
    assert!(
        near(&got, wing) < 0.25 && near(&got, hall) < 0.25,
        "{got:?}"
    );
}

/// A node that never hears a message ends after `--until-idle`, counted from its start,
/// with its (empty) map, instead of waiting for ever.
// See: issue 71 (`node_and_player.sh -`)
#[cfg(feature = "ros2")]
#[test]
fn r71_a_node_that_hears_nothing_ends_after_until_idle() {
    if !may_run_dds() {
        return;
    }
    let script = r#"
set -u
ip link set lo up multicast on
ip route add 224.0.0.0/4 dev lo
timeout 30 "$IASM" ros2 --until-idle 1
echo "node $?"
"#;
    let o = std::process::Command::new("unshare")
        .args(["--net", "bash", "-c", script])
        .env("IASM", env!("CARGO_BIN_EXE_iasm"))
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(out.contains("node 0"), "{}", show(&o));
    assert!(err.contains("no message at all in 1 s"), "{}", show(&o));
}

/// Runs the bash `script` in a network namespace of its own (`$IASM` the binary, `$BAG`
/// `bag`, `$WORK` `work`); its output, and the logs of the node, the player and the files
/// `extra` of `work`, for the assertions' messages.
fn in_own_network(
    script: &str,
    work: &Path,
    bag: &Path,
    extra: &[&str],
) -> (std::process::Output, String) {
    let o = std::process::Command::new("unshare")
        .args(["--net", "bash", "-c", script])
        .env("IASM", env!("CARGO_BIN_EXE_iasm"))
        .env("BAG", bag)
        .env("WORK", work)
        .output()
        .unwrap();
    let read = |n: &str| std::fs::read_to_string(work.join(n)).unwrap_or_default();
    let mut logs = format!(
        "{}\nnode:\n{}{}\nplay:\n{}{}",
        show(&o),
        read("node.log"),
        read("node.err"),
        read("play.log"),
        read("play.err")
    );
    for f in extra {
        logs += &format!("\n{f}: {}", read(f));
    }
    (o, logs)
}

/// Runs `iasm ros2` and `iasm ros2-play BAG --listen` side by side in this network
/// namespace, in `work`, until the player has played the bag, then stops both with Ctrl-C;
/// both must exit cleanly, the node having mapped every stop. Returns their logs.
fn run_node_and_player(work: &Path, bag: &Path) -> String {
    let script = r#"
set -u
ip link set lo up multicast on
ip route add 224.0.0.0/4 dev lo
cd "$WORK"
PRIOR=""; [ -f prior.json ] && PRIOR="--prior prior.json"
"$IASM" ros2 --seed 5 --out node.json --mcap node.mcap $PRIOR > node.log 2> node.err &
NODE=$!
"$IASM" ros2-play "$BAG" --listen heard.json --linger 120 > play.log 2> play.err &
PLAY=$!
for i in $(seq 1 600); do grep -q '^played' play.log && break; sleep 0.1; done
sleep 0.5
kill -INT $NODE
wait $NODE; echo "node $?"
kill -INT $PLAY
wait $PLAY; echo "play $?"
"#;
    let (o, logs) = in_own_network(script, work, bag, &[]);
    let read = |n: &str| std::fs::read_to_string(work.join(n)).unwrap_or_default();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("node 0") && out.contains("play 0"), "{logs}");
    // Every stop mapped live, the last on Ctrl-C.
    assert_eq!(
        read("node.log")
            .lines()
            .filter(|l| l.starts_with("stop "))
            .count(),
        6,
        "{logs}"
    );
    logs
}

/// What a robot gets wrong is a warning and a note, never the end of the run: a message
/// that is not its type, audio at another sample rate, a second of audio lost in the
/// middle of a stop. The run goes on and the talkers are mapped from the stops left.
#[test]
fn the_live_mapper_warns_of_bad_messages_and_maps_on() {
    let bag_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bags/sim_run.mcap");
    let mut live = iasm::live::LiveMapper::new(
        iasm::settings::Settings::default(),
        bag::ReadOptions::default(),
        bag::StopOptions::default(),
        5,
    )
    .unwrap();
    let mut warnings = Vec::new();
    let mut audio = 0usize;
    let mut first_ns = None;
    bag::ros2::scan_files(&bag_path, |m| {
        let t0 = *first_ns.get_or_insert(m.time_ns);
        let t = (m.time_ns - t0) as f64 * 1e-9;
        let (topic, ty) = (m.connection.topic.as_str(), m.connection.msg_type.as_str());
        if ty.ends_with("AudioStamped") {
            audio += 1;
            // Stop 3 listens from 3.3 to 3.9 s: a second lost from 3.0 s (a gap).
            if (3.0..4.0).contains(&t) {
                return Ok(());
            }
            if audio == 20 {
                // The same buffer at another rate (the AudioStamped's rate field: after the
                // header's stamp and frame "mic", format and channels).
                let mut other = m.data.to_vec();
                let at = 4 + 8 + 4 + 4 + 4 + 4;
                other[at..at + 4].copy_from_slice(&44_100i32.to_le_bytes());
                warnings.extend(live.push(topic, ty, m.time_ns, &other));
                return Ok(());
            }
        }
        if ty.ends_with("Odometry") && (t * 20.0).round() as i64 % 37 == 0 {
            // Garbage on the pose topic.
            warnings.extend(live.push(topic, ty, m.time_ns, &[0, 1, 0, 0, 7, 7, 7]));
        }
        warnings.extend(live.push(topic, ty, m.time_ns, m.data));
        warnings.extend(live.step(false).1);
        Ok(())
    })
    .unwrap();
    warnings.extend(live.step(true).1);
    let fin = live.finish().unwrap();
    let notes = live.notes();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("/odom") && n.contains("times")),
        "{notes:?}"
    );
    assert!(
        notes
            .iter()
            .any(|n| n.contains("/audio") && n.contains("44100")),
        "{notes:?}"
    );
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("/odom (nav_msgs/msg/Odometry) dropped")),
        "{warnings:?}"
    );
    // Stop 3's window crosses the gap: not a stop of 0.5 s of audio; the other five mapped.
    assert_eq!(live.stops().len(), 5, "{warnings:?}");
    assert!(live.stops().iter().all(|s| (s.pose.x - 2.6).abs() > 0.1));
    for t in [[2.0, 4.0], [4.5, 1.0]] {
        assert!(
            fin.sources
                .iter()
                .any(|s| (s.x - t[0]).hypot(s.y - t[1]) < 0.15),
            "{:?}",
            fin.sources
        );
    }
}
