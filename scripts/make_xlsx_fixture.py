#!/usr/bin/env python3
"""Writes fixtures/tables/poses.xlsx: a small workbook in the published pose tables' shape
(a header row, then x (m), y (m), theta (deg) per stop), for the xlsx reader's tests and
its mutation test. Run by hand (needs openpyxl); the tests read the committed file."""
import pathlib

import openpyxl

rows = [(0.3 * k, 0.1 * (k % 3), 9.0 * k - 90.0) for k in range(8)]
wb = openpyxl.Workbook()
ws = wb.active
ws.title = "poses"
ws.append(["x", "y", "theta"])
for r in rows:
    ws.append([round(v, 3) for v in r])
out = pathlib.Path(__file__).resolve().parent.parent / "fixtures" / "tables" / "poses.xlsx"
out.parent.mkdir(parents=True, exist_ok=True)
wb.save(out)
print(out, out.stat().st_size, "bytes")
