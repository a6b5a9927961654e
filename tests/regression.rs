//! The synthetic-room regression suite (`fixtures/rooms/*.toml`, shoeboxes and three rooms
//! that are not boxes): every scene simulated,
//! localised with every method and mapped, against the thresholds in its `[expect]` table.
//! The same suite runs as `iasm regress`.

/// The suite of the scenes in `fixtures/<folder>`, run with the default settings; panics
/// with the table and every breach when a scene misses its thresholds, or when the folder
/// does not hold `scenes` scenes.
fn suite_holds(folder: &str, scenes: usize) -> iasm::suite::SuiteReport {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(folder);
    let report = iasm::suite::run_suite(&dir, &iasm::settings::Settings::default(), None).unwrap();
    println!("{}", report.table());
    assert_eq!(
        report.rows.len(),
        2 * scenes,
        "{scenes} scenes, two methods"
    );
    let breaches = report.breaches();
    assert!(
        breaches.is_empty(),
        "\n{}\n{}",
        report.table(),
        breaches.join("\n")
    );
    report
}

#[test]
fn every_scene_meets_its_thresholds() {
    let report = suite_holds("rooms", 16);
    // None of the suite's scenes changes while the robot drives.
    assert!(report.rows.iter().all(|r| r.ospa_now.is_none()));
}

/// The scenes that change while the robot drives (`fixtures/changes`: a talker who moves,
/// a source that stops and one that starts, a machine that runs for the first third; a box
/// and an L of each): every place mapped, and the map's time fields judged against the
/// changes the scene file states (`iasm::changes`: the active sources against those
/// sounding at the last stop, and each change dated within two stops), against each
/// scene's thresholds.
#[test]
fn every_change_scene_meets_its_thresholds() {
    let report = suite_holds("changes", 6);
    for r in &report.rows {
        assert!(
            r.ospa_now.is_some() && r.changes_found.is_some(),
            "{}",
            r.scene
        );
    }
}

/// The generated benchmark's small draw (`iasm regress --generated --count 6 --seed 0
/// --map-seeds 2`): one scene of each plan family, each rendered twice, mapped twice per
/// method and from true bearings. The bounds are distribution bounds measured on it (the
/// figures of the full draws are in BENCHMARKS.md): from true bearings the mapper places
/// the sources of five of the six plans exactly (the T's floor loses two of six, the
/// mapper's own loss); from raw audio no method maps a source outside the walls, and each
/// stays within its measured mean, 90th percentile and right count.
#[test]
fn the_generated_small_draw_holds_its_distribution() {
    use iasm::generated::{Distribution, DrawOptions, DrawThresholds, TRUE_BEARINGS, run_draw};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let opts = DrawOptions {
        seeds: 0..6,
        renderings: 2,
        map_seeds: 2,
        talkers: iasm::generated::talkers_in(&root.join("fixtures/audio")).unwrap(),
        floor_only: false,
        changes: false,
    };
    let report = run_draw(&opts, &iasm::settings::Settings::default()).unwrap();
    // The report names the talkers it played: another folder, or none, draws other scenes.
    assert_eq!(report.talkers, ["talker_a.wav", "talker_b.wav"]);
    println!("{}", report.scenes_table());
    println!("{}", report.table());
    // Six families, each once: 6 scenes x 2 renderings x 2 maps per method.
    // And as many from the bearings each method heard, placed exactly.
    for g in report.group("all") {
        assert_eq!(g.maps.maps, 24, "{}", g.method);
        assert_eq!(g.heard.maps, 24, "{}", g.method);
    }
    for f in sim::draw::Family::ALL {
        assert!(report.group(f.name()).next().is_some(), "{f:?}");
    }
    let floor = Distribution::of(report.maps.iter().filter(|m| m.method == TRUE_BEARINGS));
    assert!(floor.mean <= 0.07 && floor.right_count >= 0.8, "{floor:?}");
    let breaches = report.breaches(&DrawThresholds {
        max_mean: Some(0.68),
        max_p90: Some(0.95),
        min_right_count: Some(0.10),
        max_outside: Some(0),
    });
    assert!(
        breaches.is_empty(),
        "\n{}\n{}",
        report.table(),
        breaches.join("\n")
    );
}
