#!/usr/bin/env python3
"""A subspace method beside pyroomacoustics' twin on simulated scenes (issue 52): hand-run
only.

For each data set folder written by `iasm simulate` (audio/, pose/poses.csv, src_gt.csv,
array.toml), scores pyroomacoustics' method (its default use: nfft 1024, 200-8000 Hz, one
spectrum per recording, num_src = N) and `iasm ssl --method` its twin with the same rule
as `iasm ssl --score`: the first N DoAs, a hit within 5 degrees of a true bearing. The
method is MUSIC unless PRA_METHOD names another of pyroomacoustics' (TOPS, CSSM, WAVES,
NormMUSIC, SRP). With PRA_ONCE=1 both are scored with each source counted at most once per
recording (pyroomacoustics' N DoAs often hold one talker twice, a few degrees apart,
where iasm's peaks keep a minimum separation): hits are the sources some DoA finds.

    pip install pyroomacoustics
    for f in fixtures/rooms/*.toml fixtures/heldout/*.toml; do
        iasm simulate $f --out /tmp/scenes/$(basename $f .toml); done
    OMP_NUM_THREADS=1 python3 scripts/pra_music_scenes.py target/release/iasm /tmp/scenes/*
    PRA_METHOD=TOPS OMP_NUM_THREADS=1 python3 scripts/pra_music_scenes.py ...
"""
import csv
import glob
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import tomllib

import numpy as np
import pyroomacoustics as pra
from scipy.io import wavfile

N, TOL, NFFT, BAND = 4, 5.0, 1024, [200.0, 8000.0]
PRA = os.environ.get("PRA_METHOD", "MUSIC")
ONCE = os.environ.get("PRA_ONCE") == "1"
IASM = {"MUSIC": "music", "NormMUSIC": "normmusic", "SRP": "srp-phat", "TOPS": "tops",
        "CSSM": "cssm", "WAVES": "waves"}[PRA]


def natural(s):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


def wrap(a):
    return (a + 180.0) % 360.0 - 180.0


def truth(root):
    """The data set's poses (x, y, theta in degrees) and true sources (x, y)."""
    poses = [(float(r["x"]), float(r["y"]), float(r["theta_deg"]))
             for r in csv.DictReader(open(os.path.join(root, "pose", "poses.csv")))]
    srcs = [(float(r["x"]), float(r["y"])) for r in csv.DictReader(open(os.path.join(root, "src_gt.csv")))]
    return poses, srcs


def pra_score(root):
    mics = np.array(tomllib.load(open(os.path.join(root, "array.toml"), "rb"))["positions"]).T
    files = sorted(glob.glob(os.path.join(root, "audio", "*.wav")), key=natural)
    poses, srcs = truth(root)
    hits = 0
    for f, (x, y, th) in zip(files, poses):
        fs, sig = wavfile.read(f)
        X = np.array([pra.transform.stft.analysis(sig[:, m].astype(np.float64), NFFT, NFFT // 2).T
                      for m in range(sig.shape[1])])
        doa = pra.doa.algorithms[PRA](mics, fs, NFFT, c=343.0, num_src=N, max_four=4)
        try:
            doa.locate_sources(X, num_src=N, freq_range=BAND)
        except (IndexError, ValueError) as e:
            # TOPS with num_src = N = M (a 4-microphone array) has no noise subspace.
            print(f"  pyroomacoustics' {PRA} fails on {root}: {e!r}", file=sys.stderr)
            return None
        hits += count_hits(np.degrees(doa.azimuth_recon)[:N], (x, y, th), srcs)
    return hits / (N * len(files))


def count_hits(azimuths, pose, srcs):
    """The DoAs (array frame, degrees) within TOL of a true bearing; with ONCE, the sources
    that some DoA finds."""
    x, y, th = pose
    bearings = [math.degrees(math.atan2(sy - y, sx - x)) for sx, sy in srcs]
    err = [[abs(wrap(wrap(az + th) - b)) for b in bearings] for az in azimuths]
    if ONCE:
        return sum(any(e[s] <= TOL for e in err) for s in range(len(srcs)))
    return sum(min(e) <= TOL for e in err)


def iasm_score(iasm, root):
    if not ONCE:
        out = subprocess.run([iasm, "ssl", "--dataset", root, "--method", IASM, "--num",
                              str(N), "--score", "--json"],
                             capture_output=True, text=True, check=True).stdout
        return json.loads(out)["ours"]["score"]
    with tempfile.TemporaryDirectory() as tmp:
        table = os.path.join(tmp, "doas.csv")
        subprocess.run([iasm, "ssl", "--dataset", root, "--method", IASM, "--num", str(N),
                        "--out", table], capture_output=True, text=True, check=True)
        rows = [[float(v) for v in line.strip().split(",") if v] for line in open(table)]
    poses, srcs = truth(root)
    return sum(count_hits(r[:N], p, srcs) for r, p in zip(rows, poses)) / (N * len(rows))


def main(iasm, roots):
    print(f"{PRA}: {'scene':32s} {'iasm':>6s} {'pra':>6s}")
    both = []
    for root in roots:
        ours = iasm_score(iasm, root)
        theirs = pra_score(root)
        if theirs is None:
            print(f"{os.path.basename(root):32s} {ours:6.3f}  fails", flush=True)
            continue
        both.append((ours, theirs))
        print(f"{os.path.basename(root):32s} {ours:6.3f} {theirs:6.3f}", flush=True)
    n = len(both)
    print(f"{'mean':32s} {sum(o for o, _ in both) / n:6.3f} {sum(t for _, t in both) / n:6.3f}; "
          f"iasm at least pyroomacoustics on {sum(o >= t for o, t in both)} of {n}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
