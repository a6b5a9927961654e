//! Numeric tables from CSV text or a spreadsheet workbook (calamine): a header row
//! skipped, empty cells kept as gaps, and every other cell a number or an error that
//! names its file and cell.

use std::path::Path;

use anyhow::{Context, Result, bail, ensure};

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
pub(super) fn is_workbook(path: &Path) -> bool {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    matches!(ext.as_str(), "xlsx" | "xls" | "xlsm" | "ods")
}

/// [`read_table`], with the CSV's text given instead of read when `text` is `Some`.
pub(super) fn read_table_from(path: &Path, text: Option<&str>) -> Result<Table> {
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
pub(super) fn csv_lines(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
}

/// A line's cells: comma, semicolon, tab or space separated (the first that occurs).
pub(super) fn split_cells(l: &str) -> Vec<String> {
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

pub(super) fn parse_cell(s: &String) -> Result<Option<f64>, &String> {
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
}
