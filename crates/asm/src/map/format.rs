//! The `map_server` files: the YAML of metadata and the PGM image, read and checked with
//! errors that name the file and the problem.

use std::path::{Path, PathBuf};

use super::occupancy::{MAX_CELLS, check_origin, check_resolution};
use crate::error::MapError;

/// The YAML metadata, as read.
pub(super) struct Meta {
    pub(super) image: String,
    pub(super) resolution: f64,
    pub(super) origin: [f64; 3],
    pub(super) negate: bool,
    pub(super) occupied_thresh: f64,
    pub(super) free_thresh: f64,
    pub(super) mode: String,
}

/// An image name from a map YAML, resolved against the YAML's folder unless absolute.
pub(super) fn resolve_image(yaml: &Path, image: &str) -> PathBuf {
    let p = Path::new(image);
    if p.is_absolute() {
        p.to_owned()
    } else {
        yaml.parent().unwrap_or(Path::new(".")).join(p)
    }
}

/// Reads and parses a map YAML, naming it in any error.
pub(super) fn read_meta(yaml: &Path) -> Result<Meta, MapError> {
    let text = std::fs::read_to_string(yaml).map_err(|source| MapError::Io {
        path: yaml.to_owned(),
        source,
    })?;
    parse_yaml(&text).map_err(|message| MapError::Yaml {
        path: yaml.to_owned(),
        message,
    })
}

/// A map YAML's keys as `map_server` writes them; other keys are ignored.
#[derive(serde::Deserialize)]
struct RawMeta {
    image: Option<String>,
    resolution: Option<serde_norway::Value>,
    origin: Option<serde_norway::Value>,
    negate: Option<serde_norway::Value>,
    occupied_thresh: Option<serde_norway::Value>,
    free_thresh: Option<serde_norway::Value>,
    mode: Option<String>,
}

/// A YAML number (or a string holding one, as some tools quote them), named in the error.
fn yaml_number(v: &serde_norway::Value, what: &str) -> Result<f64, String> {
    let n = match v {
        serde_norway::Value::Number(n) => n.as_f64(),
        serde_norway::Value::String(s) => s.trim().parse::<f64>().ok(),
        serde_norway::Value::Bool(b) => Some(f64::from(u8::from(*b))),
        _ => None,
    };
    n.ok_or_else(|| format!("{what} {v:?} is not a number"))
}

/// Parses a ROS map YAML with a YAML parser (quoted values, `#` inside quotes, flow or
/// block lists), then checks what I-ASM needs of it.
pub(super) fn parse_yaml(text: &str) -> Result<Meta, String> {
    let raw: RawMeta = serde_norway::from_str(text).map_err(|e| e.to_string())?;
    let image = raw.image;
    let resolution = raw
        .resolution
        .as_ref()
        .map(|v| yaml_number(v, "resolution"))
        .transpose()?;
    let origin = match &raw.origin {
        None => None,
        Some(serde_norway::Value::Sequence(v)) => {
            let v: Vec<f64> = v
                .iter()
                .map(|x| yaml_number(x, "origin value"))
                .collect::<Result<_, _>>()?;
            if v.len() != 3 {
                return Err(format!(
                    "origin must be [x, y, yaw], got {} values",
                    v.len()
                ));
            }
            Some([v[0], v[1], v[2]])
        }
        Some(other) => return Err(format!("origin must be [x, y, yaw], got {other:?}")),
    };
    let negate = raw
        .negate
        .as_ref()
        .map(|v| yaml_number(v, "negate"))
        .transpose()?
        .is_some_and(|v| v != 0.0);
    let occupied_thresh = raw
        .occupied_thresh
        .as_ref()
        .map_or(Ok(0.65), |v| yaml_number(v, "occupied_thresh"))?;
    let free_thresh = raw
        .free_thresh
        .as_ref()
        .map_or(Ok(0.196), |v| yaml_number(v, "free_thresh"))?;
    let mode = raw.mode.unwrap_or_else(|| "trinary".to_owned());
    let resolution = resolution.ok_or("missing key `resolution`")?;
    check_resolution(resolution)?;
    let origin = origin.ok_or("missing key `origin`")?;
    if !origin[2].is_finite() {
        return Err("origin has a non-finite value".into());
    }
    check_origin([origin[0], origin[1]])?;
    if origin[2] != 0.0 {
        return Err(format!(
            "origin yaw {} is not supported (only 0): rotate the map instead",
            origin[2]
        ));
    }
    if mode != "trinary" {
        return Err(format!("mode {mode:?} is not supported (only trinary)"));
    }
    if !(0.0..=1.0).contains(&free_thresh)
        || !(0.0..=1.0).contains(&occupied_thresh)
        || free_thresh > occupied_thresh
    {
        return Err(format!(
            "thresholds free {free_thresh}, occupied {occupied_thresh} must satisfy 0 <= free <= occupied <= 1"
        ));
    }
    Ok(Meta {
        image: image
            .filter(|i| !i.trim().is_empty())
            .ok_or("missing or empty key `image`")?,
        resolution,
        origin,
        negate,
        occupied_thresh,
        free_thresh,
        mode,
    })
}

/// A PGM's header: its magic (`P5` or `P2`), width, height, maxval, and where the pixels
/// begin (the byte after the maxval).
pub(super) fn pgm_header(bytes: &[u8]) -> Result<(String, usize, usize, usize, usize), String> {
    let mut pos = 0;
    let mut token = || -> Result<String, String> {
        loop {
            while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
                pos += 1;
            }
            if pos < bytes.len() && bytes[pos] == b'#' {
                while pos < bytes.len() && bytes[pos] != b'\n' {
                    pos += 1;
                }
                continue;
            }
            break;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err("unexpected end of the header".into());
        }
        Ok(String::from_utf8_lossy(&bytes[start..pos]).into_owned())
    };
    let magic = token()?;
    if magic != "P5" && magic != "P2" {
        return Err(format!(
            "not a PGM image (magic {magic:?}, expected P5 or P2)"
        ));
    }
    let mut dim = |what: &str| -> Result<usize, String> {
        let t = token()?;
        t.parse::<usize>()
            .map_err(|_| format!("{what} {t:?} is not a whole number"))
    };
    let (w, h) = (dim("width")?, dim("height")?);
    let maxval = dim("maxval")?;
    if w == 0 || h == 0 || maxval == 0 || maxval > 65535 {
        return Err(format!("bad header: {w} x {h}, maxval {maxval}"));
    }
    Ok((magic, w, h, maxval, pos))
}

/// Refuses an image of more than [`MAX_CELLS`].
pub(super) fn check_size(w: usize, h: usize) -> Result<(), String> {
    match w.checked_mul(h) {
        Some(n) if n <= MAX_CELLS => Ok(()),
        _ => Err(format!(
            "a {w} x {h} image is more cells than a map may have ({MAX_CELLS}); crop it to \
             the surveyed area or save it at a coarser resolution"
        )),
    }
}

/// Parses a binary (P5) or plain (P2) PGM: width, height, maxval and pixels in row order.
pub(super) fn parse_pgm(bytes: &[u8]) -> Result<(usize, usize, u16, Vec<u16>), String> {
    let (magic, w, h, maxval, pos) = pgm_header(bytes)?;
    check_size(w, h)?;
    let n = w * h;
    // Every pixel takes at least one byte of the file: reserve no more than it holds, so a
    // header declaring a huge image costs nothing before the check below refuses it.
    let mut pixels = Vec::with_capacity(n.min(bytes.len()));
    if magic == "P5" {
        let data = &bytes[(pos + 1).min(bytes.len())..];
        let width = if maxval < 256 { 1 } else { 2 };
        if data.len() < n * width {
            return Err(format!(
                "{w} x {h} image needs {} bytes of pixels but the file holds {}",
                n * width,
                data.len()
            ));
        }
        for k in 0..n {
            pixels.push(if width == 1 {
                u16::from(data[k])
            } else {
                u16::from_be_bytes([data[2 * k], data[2 * k + 1]])
            });
        }
    } else {
        let rest = String::from_utf8_lossy(&bytes[pos..]);
        for t in rest.split_ascii_whitespace() {
            if pixels.len() == n {
                break;
            }
            pixels.push(
                t.parse::<u16>()
                    .map_err(|_| format!("pixel {:?} is not a number", t))?,
            );
        }
        if pixels.len() < n {
            return Err(format!(
                "{w} x {h} image needs {n} pixels but the file holds {}",
                pixels.len()
            ));
        }
    }
    if let Some(v) = pixels.iter().find(|&&v| usize::from(v) > maxval) {
        return Err(format!("pixel value {v} exceeds maxval {maxval}"));
    }
    Ok((w, h, maxval as u16, pixels))
}
