//! `iasm scenes generate`: scenes drawn at random ([`sim::draw`]) written as scene files.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::Outcome;
use crate::generated::DrawOptions;

/// The talkers of a draw: the folder given, else `fixtures/audio` when it is there, else
/// none (speech-shaped noise; said on stderr, so that a draw without voices is not taken
/// for one with them).
///
/// # Errors
/// A folder given that cannot be read or holds no WAV.
pub fn talkers(dir: Option<&Path>) -> Result<Vec<PathBuf>> {
    match dir {
        Some(d) => crate::generated::talkers_in(d),
        None if Path::new("fixtures/audio").is_dir() => {
            crate::generated::talkers_in(Path::new("fixtures/audio"))
        }
        None => {
            eprintln!(
                "note: no fixtures/audio here and no --talkers: talkers are speech-shaped noise"
            );
            Ok(Vec::new())
        }
    }
}

/// Runs `iasm scenes generate`.
///
/// # Errors
/// A folder that cannot be written, or talkers that cannot be read.
pub fn generate(opts: &DrawOptions, out: &Path) -> Result<Outcome> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    // The talkers are copied beside the scenes and named by file name, so that the folder
    // can be moved as a whole.
    for t in &opts.talkers {
        let name = t.file_name().context("a talker without a file name")?;
        std::fs::copy(t, out.join(name))
            .with_context(|| format!("copying {} to {}", t.display(), out.display()))?;
    }
    let config = opts.draw_config();
    for seed in opts.seeds.clone() {
        let mut d = sim::draw::draw(seed, &config)?;
        for s in &mut d.scene.sources {
            if let Some(w) = &mut s.wav {
                *w = PathBuf::from(w.file_name().unwrap_or_default());
            }
        }
        let kinds: Vec<String> = d
            .kinds
            .iter()
            .map(|k| format!("{k:?}").to_lowercase())
            .collect();
        let change = d
            .change
            .as_ref()
            .map_or(String::new(), |c| format!(" Changes: {c}."));
        let text = format!(
            "# Drawn by `iasm scenes generate` from seed {seed}: a {} plan, {} sources ({}), \
             {} of them hidden from the first stop.{change}\n{}\n[expect]\nnum = {}\n",
            d.family.name(),
            kinds.len(),
            kinds.join(", "),
            d.hidden_from_start,
            toml::to_string(&d.scene)?,
            d.num
        );
        let path = out.join(format!("{}.toml", d.scene.name));
        crate::output::write_atomic(&path, text.as_bytes())?;
    }
    println!(
        "{} scenes (seeds {}..{}) written to {}",
        opts.seeds.end - opts.seeds.start,
        opts.seeds.start,
        opts.seeds.end,
        out.display()
    );
    Ok(Outcome::Success)
}
