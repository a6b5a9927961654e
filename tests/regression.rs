//! The synthetic-room regression suite (`fixtures/rooms/*.toml`, shoeboxes and three rooms
//! that are not boxes): every scene simulated,
//! localised with every method and mapped, against the thresholds in its `[expect]` table.
//! The same suite runs as `iasm regress`.

#[test]
fn every_scene_meets_its_thresholds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/rooms");
    let report = iasm::suite::run_suite(&dir, &iasm::settings::Settings::default(), None).unwrap();
    println!("{}", report.table());
    assert_eq!(report.rows.len(), 2 * 16, "sixteen scenes, two methods");
    let breaches = report.breaches();
    assert!(
        breaches.is_empty(),
        "\n{}\n{}",
        report.table(),
        breaches.join("\n")
    );
}
