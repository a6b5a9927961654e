//! Reading the files of a recorded data set: WAVs in natural order, pose and DoA tables
//! (CSV or `.xlsx`; the `table` and `poses` modules), and ground-truth source positions.
//!
//! The published layout (`audio/`, `pose/`, `azimuth/`, `map/`, `src_gt*.txt`) is what
//! [`Dataset::open`] understands.

mod poses;
mod table;

use std::cmp::Ordering;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, ensure};
use asm::map::OccupancyMap;
use ssl::Audio;

pub use poses::{read_named_poses, read_pose_rows_so_far, read_poses, read_timed_poses};
pub use table::{MAX_TABLE_CELLS, Table, read_table};

/// Compares file names the way a person counts: `sub2` before `sub10`.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, _) => return Ordering::Less,
            (_, None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let da = a.iter().take_while(|c| c.is_ascii_digit()).count();
                let db = b.iter().take_while(|c| c.is_ascii_digit()).count();
                let (na, nb) = (trim_zeros(&a[..da]), trim_zeros(&b[..db]));
                let ord = na.len().cmp(&nb.len()).then_with(|| na.cmp(nb));
                if ord != Ordering::Equal {
                    return ord;
                }
                (a, b) = (&a[da..], &b[db..]);
            }
            (Some(x), Some(y)) => {
                let ord = x.to_ascii_lowercase().cmp(&y.to_ascii_lowercase());
                if ord != Ordering::Equal {
                    return ord;
                }
                (a, b) = (&a[1..], &b[1..]);
            }
        }
    }
}

fn trim_zeros(d: &[u8]) -> &[u8] {
    let k = d.iter().take_while(|&&c| c == b'0').count();
    &d[k.min(d.len().saturating_sub(1))..]
}

/// A file's name for messages and titles: its last component, or the whole path when it
/// has none (`..`, `/`).
pub fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The files in `dir` with extension `ext` (case-insensitive), in natural name order.
///
/// # Errors
/// If `dir` cannot be read.
pub fn list_files(dir: &Path, ext: &str) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading folder {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)))
        .collect();
    files.sort_by(|a, b| {
        natural_cmp(
            &a.file_name().unwrap_or_default().to_string_lossy(),
            &b.file_name().unwrap_or_default().to_string_lossy(),
        )
    });
    Ok(files)
}

/// Reads ground-truth source positions (m): a CSV of x, y[, z] rows, or the published text
/// format with one `name [x, y, z]` per line.
///
/// # Errors
/// If the file cannot be read or holds no position.
pub fn read_sources(path: &Path) -> Result<Vec<[f64; 2]>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading ground truth {}", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let bracketed = match (line.find('['), line.find(']')) {
            (Some(a), Some(b)) if a < b => Some(&line[a + 1..b]),
            _ => None,
        };
        let inner = bracketed.unwrap_or(line);
        let tokens: Vec<&str> = inner
            .split([',', ' ', '\t', ';'])
            .filter(|s| !s.is_empty())
            .collect();
        let nums: Vec<f64> = tokens.iter().map_while(|s| s.parse::<f64>().ok()).collect();
        // A header or a line of prose (the published format opens with one) holds no
        // position; a line that starts as one, or a bracketed one, must be one whole.
        if bracketed.is_none() && nums.is_empty() {
            continue;
        }
        ensure!(
            nums.len() >= 2 && nums.len() == tokens.len() && nums.iter().all(|v| v.is_finite()),
            "{}: line {}: {:?} is not a source position (x, y[, z] in metres)",
            path.display(),
            i + 1,
            line.trim()
        );
        out.push([nums[0], nums[1]]);
    }
    ensure!(
        !out.is_empty(),
        "{}: no source position found",
        path.display()
    );
    Ok(out)
}

/// The first file in `dir` with extension `ext`, in natural name order.
///
/// # Errors
/// If `dir` cannot be read or holds no such file.
pub fn first_with_ext(dir: &Path, ext: &str) -> Result<PathBuf> {
    list_files(dir, ext)?
        .into_iter()
        .next()
        .with_context(|| format!("no .{ext} file in {}", dir.display()))
}

/// Reads a ROS map; when the image the YAML names is missing and the YAML's folder holds
/// exactly one PGM, reads that one instead and says so on stderr.
///
/// # Errors
/// If the map cannot be read.
pub fn load_map(yaml: &Path) -> Result<OccupancyMap> {
    let named = OccupancyMap::image_path(yaml)?;
    let image = if named.exists() {
        None
    } else {
        let dir = yaml.parent().unwrap_or(Path::new("."));
        let pgms = list_files(dir, "pgm")?;
        match pgms.as_slice() {
            [only] => {
                eprintln!(
                    "warning: {} names the image {}, which does not exist; using {}, the only PGM beside it",
                    yaml.display(),
                    named.display(),
                    only.display()
                );
                Some(only.clone())
            }
            _ => None,
        }
    };
    Ok(OccupancyMap::load_with_image(yaml, image.as_deref())?)
}

/// A data set folder in the published layout.
#[derive(Clone, Debug)]
pub struct Dataset {
    /// The folder.
    pub root: PathBuf,
    /// `audio/*.wav`, natural order.
    pub audio: Vec<PathBuf>,
    /// The pose table, if one is present in `pose/`.
    pub poses: Option<PathBuf>,
    /// The ground-truth file (`src_gt*.txt` or `.csv`), if present.
    pub sources: Option<PathBuf>,
    /// Published DoA tables in `azimuth/` (e.g. `azEst_MVDR.xlsx`), if any.
    pub doa_tables: Vec<PathBuf>,
}

impl Dataset {
    /// Finds the parts of a data set under `root`; any part may be missing.
    ///
    /// # Errors
    /// If `root` is not a folder.
    pub fn open(root: &Path) -> Result<Self> {
        ensure!(
            root.is_dir(),
            "data set folder {} does not exist",
            root.display()
        );
        let audio_dir = root.join("audio");
        let audio = if audio_dir.is_dir() {
            list_files(&audio_dir, "wav")?
        } else {
            Vec::new()
        };
        let first = |dir: &Path, pred: &dyn Fn(&str) -> bool| -> Option<PathBuf> {
            let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
                .ok()?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.is_file() && pred(&p.file_name().unwrap_or_default().to_string_lossy())
                })
                .collect();
            v.sort();
            v.into_iter().next()
        };
        let is_table = |n: &str| {
            let n = n.to_ascii_lowercase();
            n.ends_with(".csv") || n.ends_with(".xlsx") || n.ends_with(".txt")
        };
        let poses = first(&root.join("pose"), &is_table);
        let sources = first(root, &|n: &str| {
            n.to_ascii_lowercase().starts_with("src_gt") && is_table(n)
        });
        let az_dir = root.join("azimuth");
        let mut doa_tables: Vec<PathBuf> = std::fs::read_dir(&az_dir)
            .map(|rd| {
                rd.filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| {
                        p.is_file()
                            && is_table(&p.file_name().unwrap_or_default().to_string_lossy())
                    })
                    .collect()
            })
            .unwrap_or_default();
        doa_tables.sort();
        Ok(Self {
            root: root.to_owned(),
            audio,
            poses,
            sources,
            doa_tables,
        })
    }
}

/// An array file (`ssl::MicArray::from_file`) for a data set's `array.toml`: the array's
/// name and its microphones' positions in channel order, serialised by `toml` (which quotes
/// the name and writes each coordinate so that it reads back exactly).
///
/// # Errors
/// If `toml` cannot serialise them.
pub fn array_file_toml(name: &str, positions: &[[f64; 3]]) -> Result<String> {
    #[derive(serde::Serialize)]
    struct ArrayFile<'a> {
        name: &'a str,
        positions: &'a [[f64; 3]],
    }
    Ok(format!(
        "# The microphones that recorded audio/ (m, array frame: x the robot's heading, z up),\n# channel order. iasm reads this file when no --array or settings file names an array.\n{}",
        toml::to_string(&ArrayFile { name, positions }).context("writing array.toml")?
    ))
}

/// Reads the WAV at `path`, keeping its channels `channels` (counted from 1, in that
/// order: [`Settings::channels`](crate::settings::Settings::channels)) when given.
///
/// # Errors
/// An unreadable file, or a channel it does not have; named.
pub fn read_recording(path: &Path, channels: Option<&[usize]>) -> Result<Audio> {
    let audio = ssl::read_wav(path)?;
    match channels {
        None => Ok(audio),
        Some(c) => pick_channels(&audio, c).with_context(|| path.display().to_string()),
    }
}

/// The channels `channels` of `audio` (counted from 1, in that order:
/// [`Settings::channels`](crate::settings::Settings::channels)).
///
/// # Errors
/// A channel `audio` does not have.
pub fn pick_channels(audio: &Audio, channels: &[usize]) -> Result<Audio> {
    let from0: Vec<usize> = channels.iter().map(|&c| c.saturating_sub(1)).collect();
    audio
        .select(&from0)
        .with_context(|| format!("the channels {channels:?}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_counts_numbers() {
        let mut v = vec![
            "sub10.wav",
            "sub2.wav",
            "sub01.wav",
            "Sub3.wav",
            "sub1a.wav",
        ];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            v,
            vec![
                "sub01.wav",
                "sub1a.wav",
                "sub2.wav",
                "Sub3.wav",
                "sub10.wav"
            ]
        );
    }

    #[test]
    fn published_ground_truth_parses() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("src_gt.txt");
        std::fs::write(
            &p,
            "Position ground truth, unit: meter\n\ns1 [1.25,   0.6,  0]\n\ns2 [1.25,  -0.6, 0]\n",
        )
        .unwrap();
        assert_eq!(read_sources(&p).unwrap(), vec![[1.25, 0.6], [1.25, -0.6]]);
    }

    #[test]
    fn a_ground_truth_row_that_is_not_a_position_is_named_not_skipped() {
        // Skipping it would score every map against a truth one source short.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("src_gt.csv");
        std::fs::write(&p, "x,y,z\n1.5,0.6,0.3\n2.5,-0.6,0.3\n").unwrap();
        assert_eq!(read_sources(&p).unwrap(), vec![[1.5, 0.6], [2.5, -0.6]]);
        for (bad, line) in [
            ("x,y,z\n1.5,0.6,0.3\n2.5,abc,0.3\n", "line 3"),
            ("x,y,z\nNaN,0.6,0.3\n", "line 2"),
            ("x,y\n1.5\n", "line 2"),
            ("s1 [1.5, 0.6, 0]\ns2 [2.5 -0.6]\ns3 [oops]\n", "line 3"),
        ] {
            std::fs::write(&p, bad).unwrap();
            let e = format!("{:#}", read_sources(&p).unwrap_err());
            assert!(e.contains(line) && e.contains("src_gt.csv"), "{bad:?}: {e}");
        }
    }
}
