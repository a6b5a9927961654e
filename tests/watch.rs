//! `iasm watch` through the binary: a finished data set replayed stop by stop, and a folder
//! that is written while the command follows it (a recording in two halves, a pose table
//! lagging behind the audio).

use std::io::Read;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::util::*;

/// A microphone dead at one stop only (a loose connector) is named on that stop's line.
#[test]
fn a_stop_with_a_dead_microphone_says_so_on_its_line() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    zero_channel(&root.join("audio/sub3.wav"), 3);
    let o = iasm(&["watch", arg(&root), "--replay", "--num", "2"]);
    assert!(o.status.success(), "{}", show(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let flagged: Vec<&str> = stdout
        .lines()
        .filter(|l| l.contains("channel 4 silent, left out"))
        .collect();
    assert_eq!(flagged.len(), 1, "{stdout}");
    assert!(flagged[0].starts_with("stop   3  sub3.wav"), "{stdout}");
}

#[test]
fn a_replay_writes_one_curve_row_per_stop_and_ends_on_the_batch_map() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    audio_dataset(&root, &AUDIO_TRUTH);
    let (curve, out, plot) = (
        path(&dir, "curve.csv"),
        path(&dir, "map.json"),
        path(&dir, "curve.svg"),
    );
    let o = iasm(&[
        "watch",
        arg(&root),
        "--replay",
        "--num",
        "2",
        "--seed",
        "3",
        "--curve",
        arg(&curve),
        "--out",
        arg(&out),
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("stop ")).count(),
        20
    );
    // The curve: a header and 20 rows, stops 1..20 in order, OSPA known at each.
    let text = std::fs::read_to_string(&curve).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 20);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r[0], (k + 1).to_string());
        assert_eq!(r[1], format!("sub{}.wav", k + 1));
        assert!(r[4].parse::<f64>().is_ok(), "{r:?}");
    }
    // The map converges: the last row has both sources, far better than the first.
    let ospa = |r: &Vec<&str>| r[4].parse::<f64>().unwrap();
    assert_eq!(rows[19][3], "2");
    assert!(ospa(&rows[19]) < 0.2 && ospa(&rows[0]) >= 0.9, "{text}");
    // The final map is the batch map of the same DoAs and seed.
    let fin = json_file(&out);
    assert_eq!(fin["final_map"], true);
    assert_eq!(fin["stops"], 20);
    let batch = json(&iasm(&[
        "map",
        "--dataset",
        arg(&root),
        "--num",
        "2",
        "--seed",
        "3",
        "--json",
    ]));
    assert_eq!(fin["sources"], batch["sources"]);
    assert_eq!(fin["ospa"]["total"], batch["ospa"]["total"]);
    // The plot beside the curve, with its axes and title.
    let texts = svg_texts(&plot);
    for want in [
        "stop",
        "OSPA (m)",
        "the map after each stop",
        "a full map taken in",
    ] {
        assert!(
            texts.iter().any(|t| t.contains(want)),
            "{want:?} in {texts:?}"
        );
    }
}

#[test]
fn in_a_sparse_scene_the_live_map_finds_what_few_stops_hear() {
    // `sparse_ten` (ten sources, 29 stops, each source heard by a handful of them): the
    // live map after the last stop, before the final full map, holds most sources, since
    // the search after each stop ends with the batch mapper's vote (without it: 5 sources,
    // OSPA 0.55 m).
    let dir = tempdir();
    let root = path(&dir, "ds");
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/rooms/sparse_ten.toml"
    );
    let o = iasm(&["simulate", scene, "--out", arg(&root)]);
    assert!(o.status.success(), "{}", show(&o));
    let curve = path(&dir, "curve.csv");
    let o = iasm(&[
        "watch",
        arg(&root),
        "--replay",
        "--method",
        "gcc-phat",
        "--num",
        "4",
        "--seed",
        "0",
        "--curve",
        arg(&curve),
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let text = std::fs::read_to_string(&curve).unwrap();
    let last: Vec<&str> = text.lines().last().unwrap().split(',').collect();
    let (sources, ospa): (usize, f64) = (last[3].parse().unwrap(), last[4].parse().unwrap());
    assert!(sources >= 8 && ospa < 0.3, "{text}");
}

/// Waits until `cond` holds, up to `secs`.
fn wait_for(secs: f64, what: &str, mut cond: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !cond() {
        assert!(
            t0.elapsed().as_secs_f64() < secs,
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The `stops` of the map JSON at `p`, if it is there (it is always whole: written through
/// a temporary file and a rename).
fn stops_in(p: &Path) -> Option<u64> {
    let text = std::fs::read_to_string(p).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).expect("a whole JSON file");
    v["stops"].as_u64()
}

fn spawn_watch(root: &Path, out: &Path, stops: usize) -> Child {
    Command::new(env!("CARGO_BIN_EXE_iasm"))
        .args([
            "watch",
            arg(root),
            "--num",
            "2",
            "--stops",
            &stops.to_string(),
            "--out",
            arg(out),
            "--poll-ms",
            "50",
            "--give-up-s",
            "20",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the iasm binary runs")
}

fn finish(mut child: Child) -> (String, String) {
    let t0 = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if t0.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("iasm watch did not end");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = child.wait().unwrap();
    let (mut out, mut err) = (String::new(), String::new());
    child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut out)
        .unwrap();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert!(status.success(), "{status:?}\n{out}\n{err}");
    (out, err)
}

/// A complete data set to copy from, and an empty folder with only its map and truth.
fn source_and_live(dir: &tempfile::TempDir) -> (std::path::PathBuf, std::path::PathBuf) {
    let src = path(dir, "src");
    audio_dataset(&src, &AUDIO_TRUTH);
    let live = path(dir, "live");
    std::fs::create_dir_all(live.join("map")).unwrap();
    for f in ["map/room.yaml", "map/room.pgm", "src_gt.txt"] {
        std::fs::copy(src.join(f), live.join(f)).unwrap();
    }
    (src, live)
}

/// The complete data set's pose rows, and the followed folder's audio/ and pose/ made.
fn pose_lines(src: &Path, live: &Path) -> Vec<String> {
    std::fs::create_dir_all(live.join("audio")).unwrap();
    std::fs::create_dir_all(live.join("pose")).unwrap();
    std::fs::read_to_string(src.join("pose/poses.csv"))
        .unwrap()
        .lines()
        .map(str::to_owned)
        .collect()
}

#[test]
fn recordings_written_one_by_one_are_mapped_as_they_arrive() {
    let dir = tempdir();
    let (src, live) = source_and_live(&dir);
    let out = path(&dir, "map.json");
    let child = spawn_watch(&live, &out, 20);
    let poses = pose_lines(&src, &live);
    let mut table = String::new();
    for k in 1..=20 {
        table.push_str(&poses[k - 1]);
        table.push('\n');
        std::fs::write(live.join("pose/poses.csv"), &table).unwrap();
        let wav = std::fs::read(src.join(format!("audio/sub{k}.wav"))).unwrap();
        let dest = live.join(format!("audio/sub{k}.wav"));
        if k == 6 {
            // Written in two halves with a pause: the first half is a WAV whose header
            // declares more samples than are there yet, retried rather than refused.
            std::fs::write(&dest, &wav[..wav.len() / 2]).unwrap();
            std::thread::sleep(Duration::from_millis(400));
            assert!(
                stops_in(&out).unwrap_or(0) <= 5,
                "stop 6 must wait for its second half"
            );
            std::fs::write(&dest, &wav).unwrap();
        } else {
            std::fs::write(&dest, &wav).unwrap();
        }
        if k == 4 || k == 12 {
            // The maps that appear follow the recordings.
            wait_for(20.0, &format!("the map after stop {k}"), || {
                stops_in(&out) == Some(k as u64)
            });
        }
    }
    let (stdout, _) = finish(child);
    let lines: Vec<&str> = stdout.lines().filter(|l| l.starts_with("stop ")).collect();
    assert_eq!(lines.len(), 20, "{stdout}");
    for (k, l) in lines.iter().enumerate() {
        assert!(l.contains(&format!("sub{}.wav", k + 1)), "{l}");
    }
    let fin = json_file(&out);
    assert_eq!(
        (fin["stops"].as_u64(), fin["final_map"].as_bool()),
        (Some(20), Some(true))
    );
    assert_eq!(fin["sources"].as_array().unwrap().len(), 2, "{fin}");
    assert!(fin["ospa"]["total"].as_f64().unwrap() < 0.2, "{fin}");
}

#[test]
fn a_pose_table_lagging_one_stop_behind_loses_nothing() {
    let dir = tempdir();
    let (src, live) = source_and_live(&dir);
    let out = path(&dir, "map.json");
    let child = spawn_watch(&live, &out, 12);
    let poses = pose_lines(&src, &live);
    let mut table = String::new();
    for k in 1..=12 {
        // The recording of stop k first; the pose of stop k - 1 only now, and the next
        // pose half-written (no newline yet): it must not be read as a pose.
        std::fs::copy(
            src.join(format!("audio/sub{k}.wav")),
            live.join(format!("audio/sub{k}.wav")),
        )
        .unwrap();
        if k > 1 {
            table.push_str(&poses[k - 2]);
            table.push('\n');
        }
        let partial = &poses[k - 1][..poses[k - 1].len() / 2];
        std::fs::write(live.join("pose/poses.csv"), format!("{table}{partial}")).unwrap();
        std::thread::sleep(Duration::from_millis(120));
        // The map never runs ahead of the complete poses.
        assert!(stops_in(&out).unwrap_or(0) < k as u64);
    }
    table.push_str(&poses[11]);
    table.push('\n');
    std::fs::write(live.join("pose/poses.csv"), &table).unwrap();
    let (stdout, _) = finish(child);
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("stop ")).count(),
        12
    );
    let fin = json_file(&out);
    assert_eq!(fin["stops"], 12);
    // Every stop mapped with its own pose: the same map as the whole data set's first 12.
    let o = iasm(&[
        "watch",
        arg(&src),
        "--replay",
        "--num",
        "2",
        "--stops",
        "12",
        "--out",
        arg(&path(&dir, "replayed.json")),
    ]);
    assert!(o.status.success(), "{}", show(&o));
    let replayed = json_file(&path(&dir, "replayed.json"));
    assert_eq!(fin["sources"], replayed["sources"]);
}

/// Waiting costs no CPU: a watch with nothing arriving sleeps on file-system notifications
/// (or its poll), and its own reading of the folder does not wake it. It used to spend 8
/// of every 10 s of CPU waiting (the access events of its own looks woke it at once).
// See: issue 49
#[cfg(target_os = "linux")]
#[test]
fn r49_an_idle_watch_spends_no_cpu_waiting() {
    let dir = tempdir();
    let root = path(&dir, "ds");
    mapping_dataset(&root, &[[1.0, 1.0]], &[]);
    std::fs::create_dir_all(root.join("audio")).unwrap();
    let mut child = spawn_watch(&root, &path(&dir, "w.json"), 5);
    // CPU time (user + system, clock ticks) of the child, from /proc.
    let cpu = |pid: u32| -> u64 {
        let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
        let after = &stat[stat.rfind(')').unwrap() + 2..];
        let f: Vec<&str> = after.split_whitespace().collect();
        f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap()
    };
    std::thread::sleep(Duration::from_secs(1));
    let before = cpu(child.id());
    std::thread::sleep(Duration::from_secs(3));
    let spent = cpu(child.id()) - before;
    let _ = child.kill();
    let _ = child.wait();
    // Ticks are 10 ms: a busy loop spends about 300 in 3 s; waiting, none or one.
    assert!(spent <= 10, "{spent} ticks of CPU in 3 s of waiting");
}

/// A robot's faults in the folder (a recording of garbage, a pose row of NaN, a recording
/// deleted after it was mapped) cost what they touch and no more: each is a warning naming
/// it, counted in the map's notes; the other stops are mapped with their own poses, and
/// the run ends with its final map (it used to end at the first fault, exit 2, no map).
// See: issue 49
#[test]
fn r49_a_live_run_passes_over_a_robots_faults_and_ends_with_its_final_map() {
    let dir = tempdir();
    let (src, live) = source_and_live(&dir);
    let out = path(&dir, "map.json");
    let poses = pose_lines(&src, &live);
    let mut table = String::new();
    for k in 1..=12 {
        let dest = live.join(format!("audio/sub{k}.wav"));
        if k == 4 {
            std::fs::write(&dest, vec![0x5au8; 40_000]).unwrap();
        } else {
            std::fs::copy(src.join(format!("audio/sub{k}.wav")), &dest).unwrap();
        }
        table.push_str(if k == 7 { "nan,nan,nan" } else { &poses[k - 1] });
        table.push('\n');
    }
    std::fs::write(live.join("pose/poses.csv"), &table).unwrap();
    let child = spawn_watch(&live, &out, 14);
    wait_for(30.0, "the map after ten stops", || {
        stops_in(&out) == Some(10)
    });
    // sub1.wav, mapped as stop 1, goes; two more stops come, their rows appended.
    std::fs::remove_file(live.join("audio/sub1.wav")).unwrap();
    let mut rows = std::fs::OpenOptions::new()
        .append(true)
        .open(live.join("pose/poses.csv"))
        .unwrap();
    for k in 13..=14 {
        std::fs::copy(
            src.join(format!("audio/sub{k}.wav")),
            live.join(format!("audio/sub{k}.wav")),
        )
        .unwrap();
        std::io::Write::write_all(&mut rows, format!("{}\n", poses[k - 1]).as_bytes()).unwrap();
    }
    let (stdout, stderr) = finish(child);
    let lines: Vec<&str> = stdout.lines().filter(|l| l.starts_with("stop ")).collect();
    assert_eq!(lines.len(), 12, "{stdout}");
    for (k, l) in (1..=14).filter(|&k| k != 4 && k != 7).zip(&lines) {
        assert!(l.contains(&format!("sub{k}.wav")), "{l}");
    }
    let fin = json_file(&out);
    assert_eq!(
        (fin["stops"].as_u64(), fin["final_map"].as_bool()),
        (Some(12), Some(true))
    );
    let notes: Vec<&str> = fin["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n.as_str())
        .collect();
    assert_eq!(notes.len(), 3, "{notes:?}");
    assert!(notes[0].contains("stop 4 (sub4.wav) skipped") && notes[0].contains("not a valid WAV"));
    assert!(notes[1].contains("stop 7 (sub7.wav) skipped") && notes[1].contains("pose row 7"));
    assert!(
        notes[2].contains("sub1.wav (stop 1) was deleted"),
        "{notes:?}"
    );
    for n in &notes {
        assert!(stderr.contains(n), "said on stderr too: {n}");
    }
    // The stops that were mapped had their own poses: the sources are where they are.
    assert_eq!(fin["sources"].as_array().unwrap().len(), 2, "{fin}");
    assert!(fin["ospa"]["total"].as_f64().unwrap() < 0.2, "{fin}");
}
