//! Reading the files of a recorded data set: WAVs in natural order, pose and DoA tables
//! (CSV or `.xlsx`), and ground-truth source positions.
//!
//! The published layout (`audio/`, `pose/`, `azimuth/`, `map/`, `src_gt*.txt`) is what
//! [`Dataset::open`] understands.

use std::cmp::Ordering;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail, ensure};
use asm::Pose;
use asm::map::OccupancyMap;
use ssl::Audio;

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

/// A table of numbers: rows of cells, `None` where a cell is empty, `NaN` or missing.
pub type Table = Vec<Vec<Option<f64>>>;

/// Reads a numeric table from a CSV file (comma, semicolon, tab or space separated) or an
/// `.xlsx`/`.xls`/`.ods` workbook (its first sheet). A first row with a non-numeric cell
/// is taken as a header and skipped; a non-numeric cell anywhere else is an error.
///
/// # Errors
/// If the file cannot be read or holds a non-numeric cell below the header.
pub fn read_table(path: &Path) -> Result<Table> {
    read_table_from(path, None)
}

/// Whether `path` names a workbook (read with calamine) rather than a CSV text.
fn is_workbook(path: &Path) -> bool {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    matches!(ext.as_str(), "xlsx" | "xls" | "xlsm" | "ods")
}

/// [`read_table`], with the CSV's text given instead of read when `text` is `Some`.
fn read_table_from(path: &Path, text: Option<&str>) -> Result<Table> {
    let raw: Vec<Vec<String>> = if is_workbook(path) {
        read_workbook(path)?
    } else if let Some(text) = text {
        csv_lines(text).map(split_cells).collect()
    } else {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading table {}", path.display()))?;
        csv_lines(&text).map(split_cells).collect()
    };
    let mut rows = Vec::with_capacity(raw.len());
    for (r, line) in raw.iter().enumerate() {
        let parsed: Vec<Result<Option<f64>, &String>> = line.iter().map(parse_cell).collect();
        if r == 0 && parsed.iter().any(Result::is_err) {
            continue; // a header
        }
        let mut row = Vec::with_capacity(parsed.len());
        for (c, cell) in parsed.into_iter().enumerate() {
            match cell {
                Ok(v) => row.push(v),
                Err(s) => bail!(
                    "{}: row {}, column {}: {s:?} is not a number",
                    path.display(),
                    r + 1,
                    c + 1
                ),
            }
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The lines of a CSV text that hold data or a header (not blank, not `#` comments).
fn csv_lines(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
}

/// A line's cells: comma, semicolon, tab or space separated (the first that occurs).
fn split_cells(l: &str) -> Vec<String> {
    let sep: &[char] = if l.contains(',') {
        &[',']
    } else if l.contains(';') {
        &[';']
    } else if l.contains('\t') {
        &['\t']
    } else {
        &[' ']
    };
    l.split(sep)
        .filter(|c| sep != [' '] || !c.is_empty())
        .map(|c| c.trim().to_owned())
        .collect()
}

fn parse_cell(s: &String) -> Result<Option<f64>, &String> {
    let t = s.trim();
    if t.is_empty() || t.eq_ignore_ascii_case("nan") {
        return Ok(None);
    }
    t.parse::<f64>()
        .map(|v| v.is_finite().then_some(v))
        .map_err(|_| s)
}

/// The most cells a table's first sheet may span (from its first used cell to its last):
/// a million stops of four columns. A workbook names its cells (`XFD1048576`), so a file of
/// a few kilobytes could otherwise claim a grid of billions.
pub const MAX_TABLE_CELLS: u64 = 1 << 22;

fn read_workbook(path: &Path) -> Result<Vec<Vec<String>>> {
    use calamine::{Data, Reader, Sheets, open_workbook_auto};
    // calamine's messages already hold their causes: said once (as a context chain, each
    // cause would be said again after it), with the file.
    let said =
        |what: &str, e: &dyn std::fmt::Display| anyhow::anyhow!("{what} {}: {e}", path.display());
    ensure!(
        !path.is_dir(),
        "{}: a folder, not a workbook",
        path.display()
    );
    let mut wb = open_workbook_auto(path).map_err(|e| said("reading workbook", &e))?;
    let text = |c: Data| match c {
        Data::Empty => String::new(),
        Data::Float(v) => v.to_string(),
        Data::Int(v) => v.to_string(),
        other => other.to_string(),
    };
    let Some(first) = wb.sheet_names().first().cloned() else {
        bail!("{}: the workbook has no sheet", path.display());
    };
    let Sheets::Xlsx(xlsx) = &mut wb else {
        // Older formats (.xls at most 65536 x 256 cells; .ods): as calamine reads them.
        let range = wb
            .worksheet_range(&first)
            .map_err(|e| said("reading the first sheet of", &e))?;
        return Ok(range
            .rows()
            .map(|row| row.iter().cloned().map(text).collect())
            .collect());
    };
    // An xlsx sheet cell by cell: its extent checked before a grid of it is made.
    let mut reader = xlsx
        .worksheet_cells_reader(&first)
        .map_err(|e| said("reading the first sheet of", &e))?;
    let mut cells = Vec::new();
    while let Some(c) = reader
        .next_cell()
        .map_err(|e| said("reading the first sheet of", &e))?
    {
        let value = Data::from(c.get_value().clone());
        if value != Data::Empty {
            cells.push((c.get_position(), value));
        }
    }
    let Some(((r0, c0), (r1, c1))) = cells.iter().fold(None, |b, &((r, c), _)| match b {
        None => Some(((r, c), (r, c))),
        Some(((r0, c0), (r1, c1))) => Some(((r0.min(r), c0.min(c)), (r1.max(r), c1.max(c)))),
    }) else {
        return Ok(Vec::new());
    };
    let (rows, cols) = (u64::from(r1 - r0) + 1, u64::from(c1 - c0) + 1);
    if rows * cols > MAX_TABLE_CELLS {
        bail!(
            "{}: its first sheet spans {rows} rows x {cols} columns (cell {}), more than a \
             table of poses or DoAs can hold ({MAX_TABLE_CELLS} cells); remove the stray cells",
            path.display(),
            cell_name(r1, c1)
        );
    }
    let mut grid = vec![vec![String::new(); cols as usize]; rows as usize];
    for ((r, c), v) in cells {
        grid[(r - r0) as usize][(c - c0) as usize] = text(v);
    }
    Ok(grid)
}

/// A cell's name in a sheet: row 0, column 0 is `A1`; column 16383 is `XFD`.
fn cell_name(row: u32, col: u32) -> String {
    let mut letters = Vec::new();
    let mut c = col + 1;
    while c > 0 {
        c -= 1;
        letters.push(b'A' + (c % 26) as u8);
        c /= 26;
    }
    letters.reverse();
    format!(
        "{}{}",
        String::from_utf8_lossy(&letters),
        u64::from(row) + 1
    )
}

/// How a pose table with a header gives the heading.
enum Heading {
    /// A column of angles, in radians or not.
    Angle { col: usize, radians: bool },
    /// A quaternion's x, y, z, w columns (a ROS `geometry_msgs/Pose` orientation).
    Quaternion([usize; 4]),
}

/// A pose table whose header names its columns, as ROS tools export them: `x`, `y` (or
/// any name ending in `position.x`, `position.y`), and a heading: `yaw` or `theta_rad`
/// (radians), `theta_deg` or `yaw_deg` (degrees), `theta` (in the unit `theta_in_radians`
/// says), or a quaternion `qx, qy, qz, qw` (or names ending in `orientation.x` ... `.w`).
/// Other columns (a time stamp, a frame id) are ignored. `None` when the file is a workbook
/// or its first line is not such a header (plain x, y, theta columns).
///
/// # Errors
/// A header that names some columns but lacks x, y or a heading (the message names the
/// missing column and the header), or a row whose named cells are not numbers.
pub fn read_named_poses(path: &Path, theta_in_radians: bool) -> Result<Option<Vec<Pose>>> {
    if is_workbook(path) {
        return Ok(None);
    }
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading table {}", path.display()))?;
    named_poses_from(path, &text, theta_in_radians)
}

/// [`read_named_poses`] on the text of `path`.
fn named_poses_from(path: &Path, text: &str, theta_in_radians: bool) -> Result<Option<Vec<Pose>>> {
    let mut lines = csv_lines(text);
    let Some(first) = lines.next() else {
        return Ok(None);
    };
    let header: Vec<String> = split_cells(first)
        .iter()
        .map(|c| c.to_ascii_lowercase())
        .collect();
    if header.iter().all(|c| parse_cell(c).is_ok()) {
        return Ok(None); // no header: plain columns
    }
    let find = |names: &[&str], suffix: &str| {
        header.iter().position(|h| {
            names.contains(&h.as_str()) || (!suffix.is_empty() && h.ends_with(suffix))
        })
    };
    let (x, y) = (find(&["x"], "position.x"), find(&["y"], "position.y"));
    let angle = [
        (&["yaw", "yaw_rad", "theta_rad"][..], Some(true)),
        (&["theta_deg", "yaw_deg"][..], Some(false)),
        (&["theta"][..], None),
    ]
    .iter()
    .find_map(|(names, rad)| {
        find(names, "").map(|col| Heading::Angle {
            col,
            radians: rad.unwrap_or(theta_in_radians),
        })
    });
    let quat = [
        find(&["qx"], "orientation.x"),
        find(&["qy"], "orientation.y"),
        find(&["qz"], "orientation.z"),
        find(&["qw"], "orientation.w"),
    ];
    let heading = angle.or_else(|| {
        quat.iter()
            .all(Option::is_some)
            .then(|| Heading::Quaternion(quat.map(|c| c.unwrap_or(0))))
    });
    let named = x.is_some() || y.is_some() || heading.is_some();
    if !named {
        return Ok(None); // a header of other names: read as plain columns
    }
    let missing = |what: &str| {
        anyhow::anyhow!(
            "{}: the header names no {what} column (header: {}; expected x, y and yaw, \
             theta_rad, theta_deg, theta or qx, qy, qz, qw)",
            path.display(),
            header.join(", ")
        )
    };
    let (x, y) = (
        x.ok_or_else(|| missing("x"))?,
        y.ok_or_else(|| missing("y"))?,
    );
    let heading = heading.ok_or_else(|| missing("heading (yaw, theta or quaternion)"))?;
    let poses: Vec<Pose> = lines
        .enumerate()
        .map(|(r, line)| {
            let cells = split_cells(line);
            let get = |c: usize| -> Result<f64> {
                cells
                    .get(c)
                    .and_then(|v| v.parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .with_context(|| {
                        format!(
                            "{}: row {}, column {} ({}): not a finite number",
                            path.display(),
                            r + 2,
                            c + 1,
                            header[c]
                        )
                    })
            };
            let theta = match heading {
                Heading::Angle { col, radians: true } => get(col)?,
                Heading::Angle { col, .. } => get(col)?.to_radians(),
                Heading::Quaternion([qx, qy, qz, qw]) => {
                    let (qx, qy, qz, qw) = (get(qx)?, get(qy)?, get(qz)?, get(qw)?);
                    // The rotation about z of a unit quaternion (ZYX yaw).
                    (2.0 * (qw * qz + qx * qy)).atan2(1.0 - 2.0 * (qy * qy + qz * qz))
                }
            };
            Ok(Pose::new(get(x)?, get(y)?, theta))
        })
        .collect::<Result<_>>()?;
    ensure!(
        !poses.is_empty(),
        "{}: the pose table is empty",
        path.display()
    );
    Ok(Some(poses))
}

/// Reads a pose table: x, y, theta per row; theta in degrees unless `theta_in_radians`.
/// A header that names the columns (see [`read_named_poses`]) is honoured, so tables
/// exported from ROS read as they are.
///
/// # Errors
/// If the table cannot be read or a row lacks a finite x, y or theta.
pub fn read_poses(path: &Path, theta_in_radians: bool) -> Result<Vec<Pose>> {
    if let Some(poses) = read_named_poses(path, theta_in_radians)? {
        return Ok(poses);
    }
    poses_from_rows(path, read_table(path)?, theta_in_radians)
}

/// The pose rows of a table that may still be growing (a robot appending a row per stop),
/// row by row: each complete row's pose, or why it is not one (a NaN, a missing cell), so
/// that one bad row costs one stop and not the run. For a CSV, only its complete lines (up
/// to the last newline: a recorder may be writing the next one), and no row for a table
/// with none yet or only a header; a workbook is read whole (one error for all of it).
///
/// # Errors
/// A table that cannot be read, or a header that names no x, y or heading column.
pub fn read_pose_rows_so_far(
    path: &Path,
    theta_in_radians: bool,
) -> Result<Vec<std::result::Result<Pose, String>>> {
    if is_workbook(path) {
        return Ok(read_poses(path, theta_in_radians)?
            .into_iter()
            .map(Ok)
            .collect());
    }
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading table {}", path.display()))?;
    let complete = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
    let mut lines = csv_lines(complete).peekable();
    let header = match lines.peek() {
        Some(l) if split_cells(l).iter().any(|c| parse_cell(c).is_err()) => lines.next(),
        _ => None,
    };
    if let Some(h) = header {
        // A header that names columns must name them all: checked once, on no row.
        named_poses_from(path, &format!("{h}\n"), theta_in_radians)?;
    }
    Ok(lines
        .enumerate()
        .map(|(r, line)| {
            let one = format!(
                "{}{line}\n",
                header.map_or(String::new(), |h| format!("{h}\n"))
            );
            let pose = match named_poses_from(path, &one, theta_in_radians) {
                Ok(Some(p)) => Ok(p),
                Ok(None) => read_table_from(path, Some(&one))
                    .and_then(|rows| poses_from_rows(path, rows, theta_in_radians)),
                Err(e) => Err(e),
            };
            match pose {
                Ok(p) if p.len() == 1 => Ok(p[0]),
                _ => Err(format!(
                    "pose row {} ({:?}) is not a pose: x, y and a heading as finite numbers",
                    r + 1,
                    line.trim()
                )),
            }
        })
        .collect())
}

/// Reads a pose table with a time stamp per row, for a continuous recording: plain columns
/// `t, x, y, theta` (t in seconds from the recording's start; theta in degrees unless
/// `theta_in_radians`), or a CSV whose header names a time column (`t`, `time`, `stamp`,
/// `timestamp` or `%time`) beside the pose columns [`read_named_poses`] knows.
///
/// # Errors
/// A table that cannot be read, a row without a finite time or pose (named), or times
/// that go backwards.
pub fn read_timed_poses(path: &Path, theta_in_radians: bool) -> Result<Vec<(f64, Pose)>> {
    let named = if is_workbook(path) {
        None
    } else {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading table {}", path.display()))?;
        named_poses_from(path, &text, theta_in_radians)?.map(|poses| (text, poses))
    };
    let timed: Vec<(f64, Pose)> = if let Some((text, poses)) = named {
        let mut lines = csv_lines(&text);
        let header: Vec<String> = lines
            .next()
            .map(split_cells)
            .unwrap_or_default()
            .iter()
            .map(|c| c.to_ascii_lowercase())
            .collect();
        let col = header
            .iter()
            .position(|h| matches!(h.as_str(), "t" | "time" | "stamp" | "timestamp" | "%time"))
            .with_context(|| {
                format!(
                    "{}: the header names no time column (t, time, stamp, timestamp or %time; header: {})",
                    path.display(),
                    header.join(", ")
                )
            })?;
        lines
            .zip(poses)
            .enumerate()
            .map(|(r, (line, pose))| {
                let t = split_cells(line)
                    .get(col)
                    .and_then(|v| v.parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .with_context(|| {
                        format!(
                            "{}: row {}: the time is not a finite number",
                            path.display(),
                            r + 2
                        )
                    })?;
                Ok((t, pose))
            })
            .collect::<Result<_>>()?
    } else {
        let rows = read_table(path)?;
        rows.iter()
            .enumerate()
            .map(|(r, row)| {
                let get = |c: usize, what: &str| {
                    row.get(c).copied().flatten().with_context(|| {
                        format!(
                            "{}: row {}: {what} is missing or not a finite number (a timed pose \
                             table has t, x, y, theta)",
                            path.display(),
                            r + 1
                        )
                    })
                };
                let (t, x, y, th) = (get(0, "t")?, get(1, "x")?, get(2, "y")?, get(3, "theta")?);
                Ok((
                    t,
                    if theta_in_radians {
                        Pose::new(x, y, th)
                    } else {
                        Pose::from_degrees(x, y, th)
                    },
                ))
            })
            .collect::<Result<_>>()?
    };
    ensure!(
        !timed.is_empty(),
        "{}: the pose table is empty",
        path.display()
    );
    if let Some(r) = timed.windows(2).position(|w| w[1].0 < w[0].0) {
        bail!(
            "{}: the time goes backwards at pose {} ({} s after {} s)",
            path.display(),
            r + 2,
            timed[r + 1].0,
            timed[r].0
        );
    }
    Ok(timed)
}

/// Poses from a table's rows of x, y, theta.
fn poses_from_rows(path: &Path, rows: Table, theta_in_radians: bool) -> Result<Vec<Pose>> {
    ensure!(
        !rows.is_empty(),
        "{}: the pose table is empty",
        path.display()
    );
    rows.iter()
        .enumerate()
        .map(|(r, row)| {
            let get = |c: usize, what: &str| {
                row.get(c).copied().flatten().with_context(|| {
                    format!(
                        "{}: row {}: {what} is missing or not a finite number",
                        path.display(),
                        r + 1
                    )
                })
            };
            let theta = get(2, "theta")?;
            let (x, y) = (get(0, "x")?, get(1, "y")?);
            Ok(if theta_in_radians {
                Pose::new(x, y, theta)
            } else {
                Pose::from_degrees(x, y, theta)
            })
        })
        .collect()
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
    fn a_broken_workbook_is_named_and_its_cause_said_once() {
        // calamine's message holds its causes; as a context chain each was said twice
        // ("...: Zip error: i/o error: ...: Zip error: i/o error: ...").
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("poses.xlsx");
        std::fs::write(&p, b"PK\x03\x04 not a zip archive").unwrap();
        let e = format!("{:#}", read_table(&p).unwrap_err());
        assert!(e.contains("poses.xlsx"), "{e}");
        assert_eq!(e.matches("Zip error").count(), 1, "{e}");
        // A folder named like a workbook is said to be a folder.
        let d = dir.path().join("doas.xlsx");
        std::fs::create_dir(&d).unwrap();
        let e = format!("{:#}", read_table(&d).unwrap_err());
        assert!(e.contains("doas.xlsx: a folder, not a workbook"), "{e}");
    }

    #[test]
    fn cells_are_named_as_a_spreadsheet_names_them() {
        assert_eq!(cell_name(0, 0), "A1");
        assert_eq!(cell_name(9, 25), "Z10");
        assert_eq!(cell_name(0, 26), "AA1");
        assert_eq!(cell_name(199_999, 701), "ZZ200000");
        assert_eq!(cell_name(1_048_575, 16_383), "XFD1048576");
    }

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
    fn csv_tables_skip_a_header_and_keep_gaps() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, "a,b,c\n1,2,3\n4,,NaN\n").unwrap();
        let t = read_table(&p).unwrap();
        assert_eq!(
            t,
            vec![
                vec![Some(1.0), Some(2.0), Some(3.0)],
                vec![Some(4.0), None, None]
            ]
        );
        std::fs::write(&p, "1,2,3\n4,x,6\n").unwrap();
        let e = read_table(&p).unwrap_err().to_string();
        assert!(e.contains("row 2, column 2") && e.contains("t.csv"), "{e}");
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

    #[test]
    fn named_columns_and_quaternions_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("poses.csv");
        // A ROS-like export: stamp and frame id columns, position and orientation (yaw 90
        // and -45 degrees as quaternions about z).
        let h = std::f64::consts::FRAC_PI_4;
        let (s8, c8) = (std::f64::consts::PI / 8.0).sin_cos();
        std::fs::write(
            &p,
            format!(
                "stamp,frame_id,pose.position.x,pose.position.y,pose.position.z,\
                 pose.orientation.x,pose.orientation.y,pose.orientation.z,pose.orientation.w\n\
                 1.5,map,1.0,2.0,0.0,0,0,{},{}\n2.5,map,3.0,-1.0,0.0,0,0,{},{}\n",
                h.sin(),
                h.cos(),
                -s8,
                c8
            ),
        )
        .unwrap();
        let poses = read_poses(&p, false).unwrap();
        assert_eq!(poses.len(), 2);
        assert_eq!((poses[0].x, poses[0].y), (1.0, 2.0));
        assert!((poses[0].theta - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((poses[1].theta + std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        // yaw is radians; theta_deg degrees; a column order of our own.
        std::fs::write(&p, "yaw,y,x\n1.0,2.0,3.0\n").unwrap();
        let q = read_poses(&p, false).unwrap();
        assert_eq!((q[0].x, q[0].y, q[0].theta), (3.0, 2.0, 1.0));
        std::fs::write(&p, "x,y,theta_deg\n0,0,90\n").unwrap();
        assert!(
            (read_poses(&p, true).unwrap()[0].theta - std::f64::consts::FRAC_PI_2).abs() < 1e-12
        );
        // A missing column is named, with the header.
        std::fs::write(&p, "x,y,qz,qw\n0,0,0,1\n").unwrap();
        let e = format!("{:#}", read_poses(&p, false).unwrap_err());
        assert!(e.contains("heading") && e.contains("x, y, qz, qw"), "{e}");
    }

    #[test]
    fn a_pose_row_without_theta_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("poses.csv");
        std::fs::write(&p, "0,0,0\n1,2\n").unwrap();
        let e = read_poses(&p, false).unwrap_err().to_string();
        assert!(e.contains("row 2") && e.contains("theta"), "{e}");
    }
}
