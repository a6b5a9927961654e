#!/usr/bin/env python3
"""Does a spherical-wave (near-field) steering model sharpen the DoAs of near sources?

Issue 9 asked whether the far-field plane-wave model is what puts 4-5 degrees of error on
the sources within 1.5 m of arrangement II. Two hand-run checks (no test or CI uses
Python; the figures are in BENCHMARKS.md):

    python3 scripts/nearfield_check.py ring OUT.toml SOURCE_Z
        writes a scene for `iasm simulate`: one white-noise source at (5, 4, SOURCE_Z) in a
        10 x 8 x 3 m room (RT60 0.2 s, 40 dB SNR, 48 kHz), the iasm6 array 0.8 m up at 80
        stops 0.5-3 m from it, all around it, at assorted headings.

    python3 scripts/nearfield_check.py refine DATASET SSL_JSON [TRUTH]
        for every DoA of `iasm ssl --dataset DATASET --json` (SSL_JSON) within 10 degrees of
        a true bearing, searches +-4 degrees of azimuth (0.25-degree steps) at elevations
        -60..60 (10-degree steps) for the highest SRP-PHAT: far field (plane waves), and
        near field (spherical waves from ranges 0.4-5 m, and the plane wave). Once over
        every frame of the recording, once over the quarter of its 4-frame blocks where the
        DoA's direction is strongest. Prints the mean |error| by the source's distance.
        TRUTH: a truth file as `iasm map --write-aligned-truth` writes it (default: the
        data set's own). Reads `pose/poses.csv` or `pose/pose_theta.xlsx` (openpyxl).

Needs numpy and scipy.
"""
import csv
import glob
import json
import math
import os
import re
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy.io import wavfile

MICS = np.array([
    [0.1200, 0.0, 0.1040], [-0.0600, 0.1039, 0.1040], [-0.0600, -0.1039, 0.1040],
    [-0.0606, -0.0350, 0.2080], [0.0606, -0.0350, 0.2080], [0.0000, 0.0700, 0.2080],
])
PAIRS = [(i, j) for i in range(6) for j in range(i + 1, 6)]
RANGES = [0.4, 0.5, 0.6, 0.7, 0.85, 1.0, 1.25, 1.5, 2.0, 3.0, 5.0, math.inf]
C = 343.0
BANDS = [(0, 1), (1, 1.5), (1.5, 2.5), (2.5, 4), (4, math.inf)]


def ring(out, z):
    src = (5.0, 4.0)
    poses = []
    k = 0
    for r in [0.5, 0.6, 0.7, 0.8, 1.0, 1.2, 1.5, 2.0, 2.5, 3.0]:
        for a in [10, 55, 100, 145, 190, 235, 280, 325]:
            ang = math.radians(a + 7 * k)
            poses.append((src[0] - r * math.cos(ang), src[1] - r * math.sin(ang), (37 * k) % 360 - 180))
            k += 1
    rows = ", ".join(f"[{x:.4f}, {y:.4f}, {t:.1f}]" for x, y, t in poses)
    with open(out, "w") as f:
        f.write(f"""name = "nearfield_ring"
seed = 11
fs = 48000
clip_s = 0.5
snr_db = 40.0
[room]
dims = [10.0, 8.0, 3.0]
rt60 = 0.2
[array]
preset = "iasm6"
height = 0.8
[[sources]]
pos = [{src[0]}, {src[1]}, {z}]
signal = "white_noise"
[trajectory]
poses = [{rows}]
""")


def read_poses(ds):
    path = os.path.join(ds, "pose", "poses.csv")
    if os.path.exists(path):
        return [(float(r["x"]), float(r["y"]), float(r["theta_deg"])) for r in csv.DictReader(open(path))]
    import openpyxl
    ws = openpyxl.load_workbook(os.path.join(ds, "pose", "pose_theta.xlsx")).active
    return [tuple(float(c.value) for c in r[:3]) for r in ws.iter_rows()]


def read_truth(ds, path):
    if path is None:
        found = glob.glob(os.path.join(ds, "src_gt*"))
        path = found[0]
    if path.endswith(".csv"):
        return [(float(r["x"]), float(r["y"])) for r in csv.DictReader(open(path))]
    return [tuple(float(v) for v in re.findall(r"[-\d.]+", line)[1:3]) for line in open(path) if line.strip()]


def wrap(a):
    return (a + 180.0) % 360.0 - 180.0


def delays(az, el_deg, r):
    e = math.radians(el_deg)
    u = np.stack([math.cos(e) * np.cos(az), math.cos(e) * np.sin(az), np.full_like(az, math.sin(e))], 1)
    if math.isinf(r):
        return -(u @ MICS.T) / C
    return np.linalg.norm(r * u[:, None, :] - MICS[None, :, :], axis=2) / C


def srp(cross, freqs, d):
    total = 0.0
    for (a, b) in PAIRS:
        total = total + np.real(cross[(a, b)] @ np.exp(2j * np.pi * np.outer(d[:, a] - d[:, b], freqs)).T)
    return total


def best_azimuth(cross, freqs, az, ranges):
    best, at = -np.inf, None
    for el in range(-60, 61, 10):
        for r in ranges:
            v = srp(cross, freqs, delays(az, el, r))[0]
            i = int(np.argmax(v))
            if v[i] > best:
                best, at = v[i], math.degrees(az[i])
    return at


def one_stop(args):
    entry, pose, truth = args
    fs, x = wavfile.read(entry["file"])
    x = x.astype(float).T
    n = 1 << math.ceil(math.log2(0.02 * fs))
    hop = n // 2
    w = np.hanning(n)
    frames = (x.shape[1] - n) // hop + 1
    spec = np.stack([np.fft.rfft(x[:, i * hop:i * hop + n] * w, axis=1) for i in range(frames)])
    freqs = np.fft.rfftfreq(n, 1 / fs)
    band = (freqs >= 200) & (freqs <= 8000)
    freqs = freqs[band]
    unit = spec[:, :, band] / np.maximum(np.abs(spec[:, :, band]), 1e-12)
    per_frame = {p: unit[:, p[0]] * np.conj(unit[:, p[1]]) for p in PAIRS}
    blocks = frames // 4
    per_block = {p: v[:blocks * 4].reshape(blocks, 4, -1).mean(1) for p, v in per_frame.items()}
    px, py, th = pose
    out = []
    for doa in entry["doas"]:
        az0 = doa["azimuth_deg"]
        bearings = []
        for tx, ty in truth:
            dx, dy = tx - px, ty - py
            bearings.append((wrap(math.degrees(math.atan2(dy, dx)) - th), math.hypot(dx, dy)))
        b, dist = min(bearings, key=lambda t: abs(wrap(az0 - t[0])))
        if abs(wrap(az0 - b)) > 10:
            continue
        az = np.radians(az0 + np.arange(-4, 4.01, 0.25))
        at_doa = srp(per_block, freqs, delays(az, doa["elevation_deg"], math.inf))
        centre = int(np.argmin(np.abs(np.degrees(az) - az0)))
        top = np.argsort(-at_doa[:, centre])[:max(2, blocks // 4)]
        errors = {"ssl": abs(wrap(az0 - b))}
        for name, cross in [
            ("all frames", {p: v.mean(0)[None, :] for p, v in per_frame.items()}),
            ("top blocks", {p: v[top].mean(0)[None, :] for p, v in per_block.items()}),
        ]:
            for model, ranges in [("far", [math.inf]), ("near", RANGES)]:
                errors[f"{name}, {model}"] = abs(wrap(best_azimuth(cross, freqs, az, ranges) - b))
        out.append((dist, errors))
    return out


def refine(ds, ssl_json, truth_path):
    files = json.load(open(ssl_json))["files"]
    poses = read_poses(ds)
    truth = read_truth(ds, truth_path)
    with ProcessPoolExecutor() as ex:
        rows = [r for stop in ex.map(one_stop, [(f, p, truth) for f, p in zip(files, poses)]) for r in stop]
    keys = list(rows[0][1])
    print("distance  DoAs  " + "  ".join(f"{k:>18}" for k in keys))
    for lo, hi in BANDS:
        sel = [e for d, e in rows if lo <= d < hi]
        if sel:
            print(f"{lo}-{hi} m".ljust(10) + f"{len(sel):4d}  " + "  ".join(
                f"{np.mean([e[k] for e in sel]):17.2f}°" for k in keys))


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "ring":
        ring(sys.argv[2], float(sys.argv[3]))
    elif len(sys.argv) >= 4 and sys.argv[1] == "refine":
        refine(sys.argv[2], sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else None)
    else:
        sys.exit(__doc__)
