#!/usr/bin/env python3
"""Writes fixtures/tables/poses.xlsx: a small workbook in the published pose tables' shape
(a header row, then x (m), y (m), theta (deg) per stop), for the xlsx reader's tests and
its mutation test; and poses_stray_cell.xlsx, the same table with one stray cell at
XFD1048576, the last cell a sheet can have (a 5-KB file that names a grid of 17e9 cells).
Run by hand (needs openpyxl); the tests read the committed files."""
import pathlib

import openpyxl

rows = [(0.3 * k, 0.1 * (k % 3), 9.0 * k - 90.0) for k in range(8)]
wb = openpyxl.Workbook()
ws = wb.active
ws.title = "poses"
ws.append(["x", "y", "theta"])
for r in rows:
    ws.append([round(v, 3) for v in r])
tables = pathlib.Path(__file__).resolve().parent.parent / "fixtures" / "tables"
tables.mkdir(parents=True, exist_ok=True)
out = tables / "poses.xlsx"
wb.save(out)
print(out, out.stat().st_size, "bytes")
ws["XFD1048576"] = 1.0
out = tables / "poses_stray_cell.xlsx"
wb.save(out)
print(out, out.stat().st_size, "bytes")
