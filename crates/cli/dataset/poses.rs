//! Pose tables: plain x, y, theta columns, or columns named as ROS tools export them
//! (positions, a heading as an angle or a quaternion, a time stamp beside them).

use std::path::Path;

use anyhow::{Context, Result, bail, ensure};
use asm::Pose;

use super::table::{
    Table, csv_lines, is_workbook, parse_cell, read_table, read_table_from, split_cells,
};

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

#[cfg(test)]
mod tests {
    use super::*;

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
