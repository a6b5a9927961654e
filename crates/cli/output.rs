//! Writing outputs safely: a file is written under a temporary name beside its place and
//! renamed into it, and a data set folder is built beside its place and swapped in whole,
//! so that a crash or an error never leaves half a file, or a folder that mixes two runs,
//! where a good one was.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

/// The file that marks a folder as written by `iasm simulate` or `iasm bag` (and so safe to
/// replace).
pub const SIMULATE_MARKER: &str = ".iasm-simulate";

/// `path`'s sibling `.NAME.TAG-PID`.
fn sibling(path: &Path, tag: &str) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.{tag}-{}", std::process::id()))
}

/// Writes `bytes` to `path` through a temporary file beside it and a rename.
///
/// Only a regular file is replaced so: a path that names something else (a device such as
/// `/dev/null` or `/dev/stdout`, a named pipe) is written in place, since a rename would
/// put a plain file where the device was (run as root, `--out /dev/null` once replaced
/// the machine's `/dev/null`); a symbolic link is followed, and the file it points to is
/// replaced, not the link.
///
/// # Errors
/// If `path` is a folder, or the temporary file cannot be written or renamed; the message
/// names `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let resolved;
    let path = match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => bail!("{} is a folder, not a file", path.display()),
        Ok(m) if !m.is_file() => {
            return std::fs::write(path, bytes)
                .with_context(|| format!("writing {}", path.display()));
        }
        Ok(_) if path.is_symlink() => {
            resolved = std::fs::canonicalize(path)
                .with_context(|| format!("following the link {}", path.display()))?;
            resolved.as_path()
        }
        _ => path,
    };
    let tmp = sibling(path, "tmp");
    let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written.with_context(|| format!("writing {}", path.display()))
}

/// Writes `channels` (one slice of samples per channel, all as long as the first) as a
/// 32-bit float WAV at `fs` Hz: the data sets iasm writes (`simulate`, `bag`) keep every
/// sample of a float or integer source exactly enough.
///
/// # Errors
/// More than 65535 channels, or the file cannot be written; the message names `path`.
pub fn write_float_wav<T: Copy + Into<f64>>(
    path: &Path,
    channels: &[impl AsRef<[T]>],
    fs: u32,
) -> Result<()> {
    let spec = hound::WavSpec {
        channels: u16::try_from(channels.len()).context("more than 65535 channels")?,
        sample_rate: fs,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let ctx = || format!("writing {}", path.display());
    let mut w = hound::WavWriter::create(path, spec).with_context(ctx)?;
    for t in 0..channels.first().map_or(0, |c| c.as_ref().len()) {
        for ch in channels {
            w.write_sample(ch.as_ref()[t].into() as f32)
                .with_context(ctx)?;
        }
    }
    w.finalize().with_context(ctx)
}

/// Builds a data set folder at `out` with `fill`, which writes into the folder it is given:
/// a temporary folder beside `out`, marked with [`SIMULATE_MARKER`] and renamed into place
/// when `fill` succeeds. An existing `out` is replaced whole when it is empty, an earlier
/// output (it holds the marker), or `force` is set; any other folder or file is refused.
///
/// # Errors
/// A refused `out`, or what `fill` or the file system says.
pub fn replace_dir(out: &Path, force: bool, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    if out.exists() {
        if !out.is_dir() {
            bail!("{} exists and is not a folder", out.display());
        }
        let empty = std::fs::read_dir(out)
            .with_context(|| format!("reading folder {}", out.display()))?
            .next()
            .is_none();
        if !empty && !out.join(SIMULATE_MARKER).exists() && !force {
            bail!(
                "{} is not empty and is not an earlier output of iasm (simulate, bag): give another \
                 folder, or --force to replace it whole",
                out.display()
            );
        }
    }
    remove_stale_siblings(out);
    let tmp = sibling(out, "tmp");
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).with_context(|| format!("removing {}", tmp.display()))?;
    }
    std::fs::create_dir_all(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
    let built = fill(&tmp).and_then(|()| {
        std::fs::write(tmp.join(SIMULATE_MARKER), "written by iasm\n")
            .with_context(|| format!("writing {}", tmp.join(SIMULATE_MARKER).display()))
    });
    if let Err(e) = built {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    let old = sibling(out, "old");
    if out.exists() {
        std::fs::rename(out, &old).with_context(|| format!("moving {} aside", out.display()))?;
    }
    std::fs::rename(&tmp, out).with_context(|| format!("renaming into {}", out.display()))?;
    if old.exists() {
        std::fs::remove_dir_all(&old).with_context(|| format!("removing {}", old.display()))?;
    }
    Ok(())
}

/// Removes the temporary and set-aside folders (`.NAME.tmp-PID`, `.NAME.old-PID`) that a
/// run killed before its rename left beside `out`, when no process of that PID runs (on
/// systems without `/proc`, only this process's own).
fn remove_stale_siblings(out: &Path) {
    let (Some(parent), Some(name)) = (out.parent(), out.file_name()) else {
        return;
    };
    let parent = if parent.as_os_str().is_empty() {
        Path::new(".")
    } else {
        parent
    };
    let name = name.to_string_lossy();
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&format!(".{name}.")) else {
            continue;
        };
        let Some(pid) = rest
            .strip_prefix("tmp-")
            .or_else(|| rest.strip_prefix("old-"))
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        let alive = pid == std::process::id()
            || (Path::new("/proc/self").exists() && Path::new(&format!("/proc/{pid}")).exists());
        if !alive && e.path().is_dir() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_killed_runs_temporary_folder_is_removed_by_the_next() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("ds");
        // A PID no process has (above the kernel's pid_max of 2^22).
        let stale = dir.path().join(".ds.tmp-4999999");
        std::fs::create_dir_all(stale.join("audio")).unwrap();
        let other = dir.path().join(".other.tmp-4999999");
        std::fs::create_dir_all(&other).unwrap();
        replace_dir(&out, false, |d| {
            std::fs::write(d.join("a"), "x")?;
            Ok(())
        })
        .unwrap();
        assert!(!stale.exists());
        assert!(
            other.exists(),
            "another output's temporary is not ours to remove"
        );
        assert_eq!(std::fs::read_to_string(out.join("a")).unwrap(), "x");
    }

    #[test]
    fn a_file_is_replaced_whole_and_no_temporary_is_left() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.json");
        std::fs::write(&p, "old, longer content").unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn a_device_is_written_in_place_and_a_link_is_followed() {
        use std::os::unix::fs::FileTypeExt;
        // `--out /dev/null`: the device stays a device (a rename would replace it).
        let null = Path::new("/dev/null");
        if std::fs::metadata(null).is_ok_and(|m| m.file_type().is_char_device()) {
            write_atomic(null, b"discarded").unwrap();
            let m = std::fs::metadata(null).unwrap();
            assert!(
                m.file_type().is_char_device(),
                "/dev/null is no longer a device"
            );
        }
        // A link to a file: the file gets the bytes, the link stays a link.
        let dir = tempfile::tempdir().unwrap();
        let (target, link) = (dir.path().join("t.csv"), dir.path().join("l.csv"));
        std::fs::write(&target, "old").unwrap();
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(link.is_symlink());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
        // A folder is refused by name.
        let e = write_atomic(dir.path(), b"x").unwrap_err();
        assert!(format!("{e:#}").contains("is a folder"), "{e:#}");
    }

    #[test]
    fn a_failed_fill_leaves_the_old_folder_as_it_was() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("ds");
        replace_dir(&out, false, |d| Ok(std::fs::write(d.join("a"), "1")?)).unwrap();
        let e = replace_dir(&out, false, |d| {
            std::fs::write(d.join("b"), "2")?;
            bail!("render failed")
        })
        .unwrap_err();
        assert!(e.to_string().contains("render failed"));
        assert_eq!(std::fs::read_to_string(out.join("a")).unwrap(), "1");
        assert!(!out.join("b").exists());
        // Only the output folder remains: no temporary beside it.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
