//! A map as its JSON holds it, read back: the sources' positions, covariances and states
//! from what `iasm map --out`, `iasm watch --out` and the live node write, with errors that
//! name the file and the source at fault.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use asm::diff::Placed;
use serde_json::Value;

/// One source of a map file.
#[derive(Clone, Debug, PartialEq)]
pub struct MapFileSource {
    /// Where it is and how sure (a missing covariance reads as zero: the comparison's floor
    /// is then its only uncertainty).
    pub placed: Placed,
    /// The stop from which it was silent at the end of its run, if it was.
    pub silent_since: Option<usize>,
}

/// A map file read.
#[derive(Clone, Debug)]
pub struct MapFile {
    /// The file.
    pub path: PathBuf,
    /// Its frame, when it names one.
    pub frame_id: Option<String>,
    /// Its sources, in its order.
    pub sources: Vec<MapFileSource>,
}

impl MapFile {
    /// Reads `path`.
    ///
    /// # Errors
    /// A file that cannot be read or is not JSON, one without a `sources` list, or a source
    /// without a finite `x` and `y` or with a covariance that is not a symmetric 2 x 2
    /// matrix with a non-negative diagonal; each named with the file.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading map {}", path.display()))?;
        let json: Value = serde_json::from_str(&text)
            .with_context(|| format!("map {}: not JSON", path.display()))?;
        Self::parse(path, &json).with_context(|| format!("map {}", path.display()))
    }

    fn parse(path: &Path, json: &Value) -> Result<Self> {
        let Some(list) = json.get("sources").and_then(Value::as_array) else {
            bail!("no \"sources\" list (a map JSON of `iasm map --out` holds one)");
        };
        let sources = list
            .iter()
            .enumerate()
            .map(|(i, s)| source(s).with_context(|| format!("source {} (s{})", i, i + 1)))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            path: path.to_owned(),
            frame_id: json
                .get("frame_id")
                .and_then(Value::as_str)
                .map(str::to_owned),
            sources,
        })
    }

    /// The sources' positions, covariances and kinds.
    pub fn placed(&self) -> Vec<Placed> {
        self.sources.iter().map(|s| s.placed.clone()).collect()
    }
}

fn number(v: &Value, what: &str) -> Result<f64> {
    match v.get(what).and_then(Value::as_f64) {
        Some(x) if x.is_finite() => Ok(x),
        Some(x) => bail!("{what} = {x} is not finite"),
        None => bail!("no number {what:?}"),
    }
}

fn source(v: &Value) -> Result<MapFileSource> {
    let (x, y) = (number(v, "x")?, number(v, "y")?);
    let covariance = match v.get("covariance") {
        None | Some(Value::Null) => [[0.0; 2]; 2],
        Some(c) => covariance(c)?,
    };
    let silent_since = match v.get("state").and_then(Value::as_str) {
        Some("silent") => Some(
            v.get("since")
                .and_then(Value::as_u64)
                .context("state \"silent\" without a stop \"since\"")? as usize,
        ),
        Some("active") | None => None,
        Some(other) => bail!("state {other:?} is neither \"active\" nor \"silent\""),
    };
    let kind = v
        .get("signature")
        .and_then(|s| s.get("kind"))
        .and_then(Value::as_str)
        .map(str::to_owned);
    Ok(MapFileSource {
        placed: Placed {
            x,
            y,
            covariance,
            kind,
        },
        silent_since,
    })
}

fn covariance(c: &Value) -> Result<[[f64; 2]; 2]> {
    let bad = || anyhow::anyhow!("covariance {c} is not a 2 x 2 list of numbers");
    let rows = c.as_array().filter(|r| r.len() == 2).ok_or_else(bad)?;
    let mut m = [[0.0; 2]; 2];
    for (i, row) in rows.iter().enumerate() {
        let row = row.as_array().filter(|r| r.len() == 2).ok_or_else(bad)?;
        for (j, x) in row.iter().enumerate() {
            m[i][j] = x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
        }
    }
    let scale = m[0][0].abs().max(m[1][1].abs()).max(1e-12);
    if m[0][0] < 0.0 || m[1][1] < 0.0 || (m[0][1] - m[1][0]).abs() > 1e-9 * scale {
        bail!("covariance {c} is not symmetric with a non-negative diagonal");
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<MapFile> {
        MapFile::parse(Path::new("m.json"), &serde_json::from_str(text).unwrap())
    }

    #[test]
    fn a_map_json_reads_back_with_its_states() {
        let m = parse(
            r#"{"frame_id": "map", "sources": [
                {"x": 1.0, "y": 2.0, "covariance": [[0.01, 0.0], [0.0, 0.02]], "state": "active"},
                {"x": 3.0, "y": 4.0, "state": "silent", "since": 7, "signature": {"kind": "tonal"}}]}"#,
        )
        .unwrap();
        assert_eq!(m.frame_id.as_deref(), Some("map"));
        assert_eq!(m.sources[0].placed.covariance, [[0.01, 0.0], [0.0, 0.02]]);
        assert_eq!(m.sources[1].silent_since, Some(7));
        assert_eq!(m.sources[1].placed.covariance, [[0.0; 2]; 2]);
        assert_eq!(m.sources[1].placed.kind.as_deref(), Some("tonal"));
        assert_eq!(m.sources[0].placed.kind, None);
    }

    #[test]
    fn a_bad_map_names_the_source_and_the_problem() {
        let e = |t: &str| format!("{:#}", parse(t).unwrap_err());
        assert!(e(r#"{"sources": 3}"#).contains("no \"sources\" list"));
        let bad_y = e(r#"{"sources": [{"x": 1, "y": 1}, {"x": 1}]}"#);
        assert!(
            bad_y.contains("source 1 (s2)") && bad_y.contains("\"y\""),
            "{bad_y}"
        );
        let neg = e(r#"{"sources": [{"x": 1, "y": 1, "covariance": [[-1, 0], [0, 1]]}]}"#);
        assert!(neg.contains("non-negative"), "{neg}");
        let state = e(r#"{"sources": [{"x": 1, "y": 1, "state": "asleep"}]}"#);
        assert!(state.contains("asleep"), "{state}");
    }
}
