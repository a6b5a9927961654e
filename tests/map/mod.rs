//! `iasm map` and `iasm eval` through the binary: maps from DoA tables and from raw audio,
//! the picture and tables they write, and bad input. The data set they share is here.

mod audio;
mod eval;
mod inputs;
mod runs;
mod tables;

use std::path::Path;

use crate::util::*;

pub(super) const TRUTH: [[f64; 2]; 3] = [[1.5, 1.5], [4.0, -1.2], [5.5, 2.0]];

pub(super) fn dataset(dir: &tempfile::TempDir) -> std::path::PathBuf {
    let root = path(dir, "ds");
    mapping_dataset(&root, &TRUTH, &drive());
    root
}

/// `iasm CMD --dataset ROOT --method mvdr --num 2 --json`.
pub(super) fn mvdr_n2(root: &Path, cmd: &str) -> std::process::Output {
    iasm(&[
        cmd,
        "--dataset",
        arg(root),
        "--method",
        "mvdr",
        "--num",
        "2",
        "--json",
    ])
}

pub(super) fn map_with(root: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["map", "--dataset", arg(root), "--num", "3"];
    args.extend_from_slice(extra);
    iasm(&args)
}
