//! Finding the next complete recording and its pose in a folder that a recorder is still
//! writing: the recordings taken in name order, each once, each stop given its row, and a
//! recorder's faults (late, missing, half-written or garbage files, rows cut or
//! rewritten) costing no more than their own stop.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Result;
use asm::Pose;
use ssl::Audio;

use crate::dataset::{file_name, list_files};

/// What [`Follower::poll`] found.
pub enum Next {
    /// The next stop: its recording, read whole, and its pose.
    Ready {
        /// The WAV file.
        file: PathBuf,
        /// Its samples.
        audio: Audio,
        /// The robot's pose there.
        pose: Pose,
    },
    /// The next stop cannot be used (a recording that is not one, a pose row that is not
    /// a pose): it is passed over, with its recording and its pose row, and why.
    Skipped {
        /// The WAV file.
        file: PathBuf,
        /// Why, naming the file or the row.
        reason: String,
    },
    /// Nothing to do yet, and why.
    Waiting(String),
}

/// Follows a data set folder that a recorder is writing: `audio/*.wav`, one per stop, and
/// a pose table with a row per stop (`pose/*.csv` or the file given).
///
/// **Pairing.** Each recording is taken once, by its name, in the order the recordings
/// appear (those that appear together, or are there at the start, in natural name order:
/// `stop2` before `stop10`); the n-th taken is stop n and is paired with the table's row
/// n. A recorder that writes a recording and then its row, stop after stop, is followed
/// exactly, whatever it names its files. What could break the pairing is named in
/// [`Follower::take_warnings`], never absorbed: a recording that appears after one that
/// sorts after it (it is taken next all the same), a taken recording deleted (its stop
/// stays), a table cut shorter than the rows already used, a used row rewritten (the map
/// keeps the pose it was given).
///
/// A recording is taken when it reads whole: a WAV whose header declares more samples than
/// the file holds yet (or none, as a recorder that patches the header at the end leaves
/// it), or that is not yet a WAV at all, is retried at the next call. One that is not a
/// recording (not a RIFF/WAVE file once it holds a header's bytes, or unreadable and
/// unchanged for `give_up`) is skipped with its pose row; so is a stop whose row is not a
/// pose (a NaN). Rows are read from complete lines only; a table that lags behind the
/// recordings is waited for.
pub struct Follower {
    root: PathBuf,
    poses: Option<PathBuf>,
    theta_in_radians: bool,
    /// The recordings taken (mapped or skipped), in order: stop n is `taken[n - 1]`.
    taken: Vec<PathBuf>,
    /// The pose row each taken stop was paired with (`None`: skipped for its row).
    rows_used: Vec<Option<Pose>>,
    give_up: Duration,
    /// For the recording being waited on: its size and when that size was first seen.
    seen: HashMap<PathBuf, (u64, Instant)>,
    /// The next stop's recording, once seen and until taken: if it vanishes before it is
    /// taken (deleted while it waited for its pose row), its stop is passed over, so that
    /// the recordings after it keep their rows.
    pending: Option<PathBuf>,
    /// Warnings not yet taken, and every one said (each is said once).
    warnings: Vec<String>,
    said: std::collections::HashSet<String>,
}

impl Follower {
    /// Follows `root`: its `audio/` and, unless `poses` is given, the first table in its
    /// `pose/` (found when it appears). Theta is in degrees unless `theta_in_radians`.
    pub fn new(
        root: &Path,
        poses: Option<PathBuf>,
        theta_in_radians: bool,
        give_up: Duration,
    ) -> Self {
        Self {
            root: root.to_owned(),
            poses,
            theta_in_radians,
            taken: Vec::new(),
            rows_used: Vec::new(),
            give_up,
            seen: HashMap::new(),
            pending: None,
            warnings: Vec::new(),
            said: std::collections::HashSet::new(),
        }
    }

    /// Stops taken so far (mapped or skipped).
    pub fn done(&self) -> usize {
        self.taken.len()
    }

    /// The folder followed for recordings.
    pub fn audio_dir(&self) -> PathBuf {
        self.root.join("audio")
    }

    /// What changed in the folder that the pairing cannot follow, since the last call.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn warn(&mut self, w: String) {
        if self.said.insert(w.clone()) {
            self.warnings.push(w);
        }
    }

    fn pose_table(&self) -> Option<PathBuf> {
        if let Some(p) = &self.poses {
            return Some(p.clone());
        }
        let mut v: Vec<PathBuf> = std::fs::read_dir(self.root.join("pose"))
            .ok()?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.is_file()
                    && p.extension().is_some_and(|e| {
                        matches!(e.to_string_lossy().as_ref(), "csv" | "xlsx" | "txt")
                    })
            })
            .collect();
        v.sort();
        v.into_iter().next()
    }

    /// The next recording not yet taken, after naming taken ones that are gone and a new
    /// one that sorts before the last taken.
    fn next_recording(&mut self, dir: &Path) -> Result<Option<PathBuf>> {
        let files = list_files(dir, "wav")?;
        let present: std::collections::HashSet<&PathBuf> = files.iter().collect();
        let gone: Vec<String> = self
            .taken
            .iter()
            .enumerate()
            .filter(|(_, f)| !present.contains(f))
            .map(|(k, f)| {
                format!(
                    "{} (stop {}) was deleted after it was taken; its stop stays, and the \
                     recordings after it keep their pose rows",
                    file_name(f),
                    k + 1
                )
            })
            .collect();
        for w in gone {
            self.warn(w);
        }
        let taken: std::collections::HashSet<&PathBuf> = self.taken.iter().collect();
        let Some(next) = files.iter().find(|f| !taken.contains(f)).cloned() else {
            return Ok(None);
        };
        if let Some(last) = self.taken.last()
            && crate::dataset::natural_cmp(&file_name(&next), &file_name(last)).is_lt()
        {
            let w = format!(
                "{} appeared after {}, which sorts after it, was taken: it is stop {}, \
                 paired with pose row {} (recordings are paired with rows in the order they \
                 appear)",
                file_name(&next),
                file_name(last),
                self.taken.len() + 1,
                self.taken.len() + 1
            );
            self.warn(w);
        }
        Ok(Some(next))
    }

    /// The table's rows, after naming a table cut shorter than the rows used and used rows
    /// rewritten.
    fn rows(&mut self, table: &Path) -> Result<Vec<std::result::Result<Pose, String>>> {
        let rows = crate::dataset::read_pose_rows_so_far(table, self.theta_in_radians)?;
        let used = self.rows_used.len();
        if rows.len() < used {
            self.warn(format!(
                "{} now has {} rows, but {used} stops were paired with its rows: it was cut \
                 or replaced; the stops taken keep their poses, and stop {} waits for row {}",
                table.display(),
                rows.len(),
                used + 1,
                used + 1
            ));
        }
        let changed: Vec<String> = rows
            .iter()
            .zip(&self.rows_used)
            .enumerate()
            .filter_map(|(r, (now, then))| match (now, then) {
                (Ok(p), Some(q)) if !same_pose(p, q) => Some(format!(
                    "{} row {} changed after stop {} was mapped with it ({}, {}, {:.1} deg -> \
                     {}, {}, {:.1} deg): the map keeps the pose it was given",
                    table.display(),
                    r + 1,
                    r + 1,
                    q.x,
                    q.y,
                    q.theta_deg(),
                    p.x,
                    p.y,
                    p.theta_deg()
                )),
                _ => None,
            })
            .collect();
        for w in changed {
            self.warn(w);
        }
        Ok(rows)
    }

    /// Takes `file` as the next stop, paired with `row`.
    fn take(&mut self, file: &Path, row: Option<Pose>) {
        self.seen.remove(file);
        self.pending = None;
        self.taken.push(file.to_owned());
        self.rows_used.push(row);
    }

    /// The next stop if its recording and pose are both complete.
    ///
    /// # Errors
    /// A folder or pose table that cannot be read, or a table header that names no x, y or
    /// heading column; named. A bad recording or row is [`Next::Skipped`], not an error.
    pub fn poll(&mut self) -> Result<Next> {
        let dir = self.audio_dir();
        if !dir.is_dir() {
            return Ok(Next::Waiting(format!(
                "{} does not exist yet",
                dir.display()
            )));
        }
        if let Some(gone) = self.pending.clone().filter(|f| !f.exists()) {
            let k = self.taken.len() + 1;
            self.take(&gone, None);
            return Ok(Next::Skipped {
                file: gone,
                reason: format!(
                    "deleted while stop {k} waited for its pose row: the stop is passed over \
                     with pose row {k}, and the recordings after it keep their rows"
                ),
            });
        }
        let Some(file) = self.next_recording(&dir)? else {
            return Ok(Next::Waiting("no new recording".into()));
        };
        self.pending = Some(file.clone());
        let size = std::fs::metadata(&file).map_or(0, |m| m.len());
        let since = match self.seen.get(&file) {
            Some(&(s, t)) if s == size => t,
            _ => {
                let now = Instant::now();
                self.seen.insert(file.clone(), (size, now));
                now
            }
        };
        // The pose first: reading a recording whose pose has not come yet would be repeated
        // at every look until it does.
        let Some(table) = self.pose_table() else {
            return Ok(Next::Waiting("no pose table yet".into()));
        };
        let rows = self.rows(&table)?;
        let k = self.taken.len();
        let pose = match rows.get(k) {
            None => {
                return Ok(Next::Waiting(format!(
                    "{} has {} poses; waiting for stop {}",
                    table.display(),
                    rows.len(),
                    k + 1
                )));
            }
            Some(Err(why)) => {
                let reason = format!("{}: {why}", table.display());
                self.take(&file, None);
                return Ok(Next::Skipped { file, reason });
            }
            Some(Ok(p)) => *p,
        };
        match ssl::read_wav(&file) {
            Ok(audio) if std::fs::metadata(&file).map_or(0, |m| m.len()) == size => {
                self.take(&file, Some(pose));
                Ok(Next::Ready { file, audio, pose })
            }
            Ok(_) => Ok(Next::Waiting(format!("{} is growing", file.display()))),
            Err(e) => {
                let garbage = !looks_like_wav(&file);
                if garbage || since.elapsed() >= self.give_up {
                    let reason = if garbage {
                        format!("{e} (it does not begin as a WAV file does)")
                    } else {
                        format!(
                            "{e} (unchanged for {:.0} s: not a recording being written)",
                            self.give_up.as_secs_f64()
                        )
                    };
                    self.take(&file, Some(pose));
                    return Ok(Next::Skipped { file, reason });
                }
                Ok(Next::Waiting(format!(
                    "{} is not complete yet",
                    file.display()
                )))
            }
        }
    }
}

/// Whether two poses of a table are the same row (to the table's printed precision).
fn same_pose(a: &Pose, b: &Pose) -> bool {
    (a.x - b.x).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9 && (a.theta - b.theta).abs() < 1e-9
}

/// Whether `file` could still become a WAV: fewer bytes than a RIFF header's first twelve,
/// or those bytes are `RIFF`/`RF64`/`RIFX` ... `WAVE` (a recorder writes its header first).
fn looks_like_wav(file: &Path) -> bool {
    let mut head = Vec::new();
    let _ = std::fs::File::open(file)
        .and_then(|f| std::io::Read::read_to_end(&mut std::io::Read::take(f, 12), &mut head));
    head.len() < 12 || (matches!(&head[..4], b"RIFF" | b"RF64" | b"RIFX") && &head[8..] == b"WAVE")
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A folder as a recorder writes it: `audio/` and `pose/p.csv`.
    pub(super) struct Folder(pub(super) tempfile::TempDir);

    impl Folder {
        pub(super) fn new() -> Self {
            let d = tempfile::tempdir().unwrap();
            std::fs::create_dir_all(d.path().join("audio")).unwrap();
            std::fs::create_dir_all(d.path().join("pose")).unwrap();
            std::fs::write(d.path().join("pose/p.csv"), "").unwrap();
            Self(d)
        }
        /// A recording of `n` samples (two channels): its length tells which it is.
        pub(super) fn wav(&self, name: &str, n: usize) {
            let spec = hound::WavSpec {
                channels: 2,
                sample_rate: 16000,
                bits_per_sample: 16,
                sample_format: hound::SampleFormat::Int,
            };
            let p = self.0.path().join("audio").join(name);
            let mut w = hound::WavWriter::create(&p, spec).unwrap();
            for _ in 0..2 * n {
                w.write_sample(0i16).unwrap();
            }
            w.finalize().unwrap();
        }
        pub(super) fn row(&self, row: &str) {
            let p = self.0.path().join("pose/p.csv");
            let mut t = std::fs::read_to_string(&p).unwrap();
            t.push_str(row);
            t.push('\n');
            std::fs::write(p, t).unwrap();
        }
        pub(super) fn follower(&self) -> Follower {
            Follower::new(self.0.path(), None, false, Duration::from_secs(3600))
        }
    }

    /// What the next poll gives: the file and its samples and x, or the skipped file, or
    /// waiting.
    fn next(f: &mut Follower) -> String {
        match f.poll().unwrap() {
            Next::Ready { file, audio, pose } => {
                format!(
                    "{} n={} x={}",
                    file_name(&file),
                    audio.num_samples(),
                    pose.x
                )
            }
            Next::Skipped { file, reason } => format!("skip {} ({reason})", file_name(&file)),
            Next::Waiting(_) => "wait".into(),
        }
    }

    #[test]
    fn recordings_are_paired_with_rows_in_the_order_they_appear() {
        let d = Folder::new();
        let mut f = d.follower();
        // At the start, two recordings in natural name order: stop2 before stop10.
        d.wav("stop10.wav", 20);
        d.wav("stop2.wav", 10);
        d.row("1,0,0");
        d.row("2,0,0");
        assert_eq!(next(&mut f), "stop2.wav n=10 x=1");
        assert_eq!(next(&mut f), "stop10.wav n=20 x=2");
        assert_eq!(next(&mut f), "wait");
        assert!(f.take_warnings().is_empty());
        // stop9 appears after stop10 was taken: it is the third stop, with the third row,
        // and the order is named.
        d.wav("stop9.wav", 30);
        assert_eq!(next(&mut f), "wait"); // its row is not written yet
        d.row("3,0,0");
        assert_eq!(next(&mut f), "stop9.wav n=30 x=3");
        let w = f.take_warnings();
        assert!(
            w.len() == 1 && w[0].contains("stop9.wav appeared after stop10.wav"),
            "{w:?}"
        );
        // Each recording once: nothing is taken again.
        assert_eq!(next(&mut f), "wait");
        assert_eq!(f.done(), 3);
    }

    /// See: issue 71 (`watch_deleted_pending.sh`). A recording deleted while it waits for
    /// its pose row is its stop passed over with that row: the next recording is paired
    /// with the next row, not with the deleted one's.
    #[test]
    fn r71_a_recording_deleted_before_its_row_shifts_nothing() {
        let d = Folder::new();
        let mut f = d.follower();
        d.wav("stop01.wav", 10);
        d.row("1,0,0");
        assert_eq!(next(&mut f), "stop01.wav n=10 x=1");
        d.wav("stop02.wav", 20);
        assert_eq!(next(&mut f), "wait"); // row 2 not yet written
        std::fs::remove_file(d.0.path().join("audio/stop02.wav")).unwrap();
        d.row("2,0,0");
        d.wav("stop03.wav", 30);
        d.row("3,0,0");
        let skipped = next(&mut f);
        assert!(
            skipped.starts_with("skip stop02.wav") && skipped.contains("pose row 2"),
            "{skipped}"
        );
        assert_eq!(next(&mut f), "stop03.wav n=30 x=3");
        assert_eq!(f.done(), 3);
    }

    #[test]
    fn a_deleted_recording_keeps_its_stop_and_shifts_nothing() {
        let d = Folder::new();
        let mut f = d.follower();
        d.wav("a1.wav", 10);
        d.row("1,0,0");
        assert_eq!(next(&mut f), "a1.wav n=10 x=1");
        std::fs::remove_file(d.0.path().join("audio/a1.wav")).unwrap();
        d.wav("a2.wav", 20);
        d.row("2,0,0");
        // a2 is stop 2 with row 2, not stop 1 again with row 1.
        assert_eq!(next(&mut f), "a2.wav n=20 x=2");
        let w = f.take_warnings();
        assert!(
            w.len() == 1 && w[0].contains("a1.wav (stop 1) was deleted"),
            "{w:?}"
        );
        // Said once, not at every look.
        assert_eq!(next(&mut f), "wait");
        assert!(f.take_warnings().is_empty());
    }

    #[test]
    fn a_garbage_recording_or_a_nan_row_costs_its_stop_and_the_run_goes_on() {
        let d = Folder::new();
        let mut f = d.follower();
        d.wav("s1.wav", 10);
        std::fs::write(d.0.path().join("audio/s2.wav"), vec![7u8; 5000]).unwrap();
        d.wav("s3.wav", 30);
        d.wav("s4.wav", 40);
        d.row("1,0,0");
        d.row("2,0,0");
        d.row("nan,nan,nan");
        d.row("4,0,0");
        assert_eq!(next(&mut f), "s1.wav n=10 x=1");
        // Not a WAV at all, and not the start of one: skipped at once, with its row.
        let s = next(&mut f);
        assert!(
            s.starts_with("skip s2.wav") && s.contains("s2.wav: not a valid WAV"),
            "{s}"
        );
        let s = next(&mut f);
        assert!(
            s.starts_with("skip s3.wav") && s.contains("pose row 3"),
            "{s}"
        );
        assert_eq!(next(&mut f), "s4.wav n=40 x=4");
        assert_eq!(f.done(), 4);
    }

    #[test]
    fn a_recording_being_written_is_waited_for_not_skipped() {
        let d = Folder::new();
        let mut f = d.follower();
        d.row("1,0,0");
        // The first 30 bytes of a WAV (its header cut short), then the whole file.
        d.wav("w.wav", 10);
        let p = d.0.path().join("audio/w.wav");
        let whole = std::fs::read(&p).unwrap();
        std::fs::write(&p, &whole[..30]).unwrap();
        assert_eq!(next(&mut f), "wait");
        std::fs::write(&p, &whole[..6]).unwrap();
        assert_eq!(next(&mut f), "wait");
        std::fs::write(&p, &whole).unwrap();
        assert_eq!(next(&mut f), "w.wav n=10 x=1");
    }

    #[test]
    fn a_table_cut_short_or_rewritten_is_named_and_the_poses_given_are_kept() {
        let d = Folder::new();
        let mut f = d.follower();
        for k in 1..=3 {
            d.wav(&format!("s{k}.wav"), 10 * k);
            d.row(&format!("{k},0,0"));
        }
        for k in 1..=3 {
            assert_eq!(next(&mut f), format!("s{k}.wav n={} x={k}", 10 * k));
        }
        // The table cut to its first row: named once, and stop 4 waits for row 4.
        std::fs::write(d.0.path().join("pose/p.csv"), "1,0,0\n").unwrap();
        d.wav("s4.wav", 40);
        assert_eq!(next(&mut f), "wait");
        assert_eq!(next(&mut f), "wait");
        let w = f.take_warnings();
        assert!(
            w.len() == 1 && w[0].contains("now has 1 rows, but 3 stops"),
            "{w:?}"
        );
        // Rewritten: row 2 is another pose now; row 4 comes. Stop 4 is mapped with row 4,
        // and the change of row 2 is named.
        std::fs::write(
            d.0.path().join("pose/p.csv"),
            "1,0,0\n2.5,0,0\n3,0,0\n4,0,0\n",
        )
        .unwrap();
        assert_eq!(next(&mut f), "s4.wav n=40 x=4");
        let w = f.take_warnings();
        assert!(
            w.len() == 1 && w[0].contains("row 2 changed after stop 2 was mapped"),
            "{w:?}"
        );
    }
}

#[cfg(test)]
mod mutations {
    //! `watch`'s folder mutated as a robot's recorder and its faults would: seeded random
    //! runs of recordings arriving late, out of order, half-written, garbage or deleted,
    //! and pose rows NaN, cut or rewritten. The follower never errs, takes the recordings
    //! by its rule (the first in name order of those there), each once, gives each stop
    //! its row and loses none.

    use super::tests::Folder;
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    #[test]
    fn the_follower_keeps_its_pairing_through_a_recorders_faults() {
        for seed in 0..200u64 {
            let mut rng = StdRng::seed_from_u64(seed);
            let d = Folder::new();
            let mut f = d.follower();
            // rows[k]: the pose row of stop k + 1 as the recorder wrote it (x = k + 1; a
            // NaN row is None); files in the order written, each with its sample count.
            let mut rows: Vec<Option<f64>> = Vec::new();
            let mut written: Vec<(String, usize, bool)> = Vec::new();
            let mut taken: Vec<String> = Vec::new();
            let mut present: Vec<String> = Vec::new();
            let write_table = |rows: &[Option<f64>], upto: usize| {
                let t: String = rows[..upto]
                    .iter()
                    .map(|r| r.map_or("nan,nan,nan\n".into(), |x| format!("{x},0,0\n")))
                    .collect();
                std::fs::write(d.0.path().join("pose/p.csv"), t).unwrap();
            };
            // The rule: the next recording taken is the first in name order of those there
            // and not yet taken; stop k is paired with row k.
            let poll = |f: &mut Follower,
                        rows: &[Option<f64>],
                        present: &[String],
                        taken: &mut Vec<String>| {
                let k = f.done();
                let expected = present
                    .iter()
                    .filter(|n| !taken.contains(n))
                    .min_by(|a, b| crate::dataset::natural_cmp(a, b))
                    .cloned();
                let got = match f
                    .poll()
                    .expect("a follower never errs on a recorder's faults")
                {
                    Next::Ready { file, audio, pose } => {
                        let name = file_name(&file);
                        assert_eq!(Some(pose.x), rows[k], "seed {seed}: {name}");
                        let n: usize = name[1..name.len() - 4].parse().unwrap();
                        assert_eq!(audio.num_samples(), n, "seed {seed}: {name}'s samples");
                        name
                    }
                    Next::Skipped { file, .. } => file_name(&file),
                    Next::Waiting(_) => return,
                };
                assert_eq!(
                    Some(&got),
                    expected.as_ref(),
                    "seed {seed}: taken out of turn"
                );
                taken.push(got);
            };
            for _ in 0..rng.random_range(4..14) {
                // A recording, its name's number random (so out of order at times), its
                // sample count that number; then its row.
                let id = rng.random_range(1..500usize);
                let name = format!("r{id}.wav");
                if written.iter().any(|w| w.0 == name) {
                    continue;
                }
                let garbage = rng.random_bool(0.1);
                if garbage {
                    std::fs::write(d.0.path().join("audio").join(&name), vec![9u8; 300]).unwrap();
                } else if rng.random_bool(0.2) {
                    // Half-written first: polled, then completed.
                    d.wav(&name, id);
                    let p = d.0.path().join("audio").join(&name);
                    let whole = std::fs::read(&p).unwrap();
                    std::fs::write(&p, &whole[..whole.len() / 2]).unwrap();
                    present.push(name.clone());
                    poll(&mut f, &rows, &present, &mut taken);
                    std::fs::write(&p, &whole).unwrap();
                } else {
                    d.wav(&name, id);
                }
                if !present.contains(&name) {
                    present.push(name.clone());
                }
                written.push((name, id, garbage));
                rows.push(if rng.random_bool(0.1) {
                    None
                } else {
                    Some(rows.len() as f64 + 1.0)
                });
                write_table(&rows, rows.len());
                // Faults between stops.
                match rng.random_range(0..10) {
                    0 if !taken.is_empty() => {
                        let gone = taken[rng.random_range(0..taken.len())].clone();
                        let _ = std::fs::remove_file(d.0.path().join("audio").join(&gone));
                        present.retain(|n| *n != gone);
                    }
                    1 => write_table(&rows, rng.random_range(0..=rows.len())),
                    _ => {}
                }
                for _ in 0..rng.random_range(0..3) {
                    poll(&mut f, &rows, &present, &mut taken);
                }
            }
            // The table whole again: every recording is taken, once; none is lost.
            write_table(&rows, rows.len());
            for _ in 0..3 * written.len() + 3 {
                poll(&mut f, &rows, &present, &mut taken);
            }
            let mut all: Vec<&String> = written.iter().map(|w| &w.0).collect();
            let mut got: Vec<&String> = taken.iter().collect();
            all.sort();
            got.sort();
            assert_eq!(got, all, "seed {seed}: every recording once");
            assert_eq!(f.done(), written.len());
        }
    }
}
