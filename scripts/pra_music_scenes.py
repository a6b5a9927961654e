#!/usr/bin/env python3
"""MUSIC beside pyroomacoustics' on simulated scenes (issue 52): hand-run only.

For each data set folder written by `iasm simulate` (audio/, pose/poses.csv, src_gt.csv,
array.toml), scores pyroomacoustics' MUSIC (its default use: nfft 1024, 200-8000 Hz, one
spectrum per recording, num_src = N) and `iasm ssl --method music` with the same rule as
`iasm ssl --score`: the first N DoAs, a hit within 5 degrees of a true bearing.

    pip install pyroomacoustics
    for f in fixtures/rooms/*.toml fixtures/heldout/*.toml; do
        iasm simulate $f --out /tmp/scenes/$(basename $f .toml); done
    OMP_NUM_THREADS=1 python3 scripts/pra_music_scenes.py target/release/iasm /tmp/scenes/*
"""
import csv
import glob
import json
import math
import os
import re
import subprocess
import sys
import tomllib

import numpy as np
import pyroomacoustics as pra
from scipy.io import wavfile

N, TOL, NFFT, BAND = 4, 5.0, 1024, [200.0, 8000.0]


def natural(s):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


def wrap(a):
    return (a + 180.0) % 360.0 - 180.0


def pra_score(root):
    mics = np.array(tomllib.load(open(os.path.join(root, "array.toml"), "rb"))["positions"]).T
    files = sorted(glob.glob(os.path.join(root, "audio", "*.wav")), key=natural)
    poses = [(float(r["x"]), float(r["y"]), float(r["theta_deg"]))
             for r in csv.DictReader(open(os.path.join(root, "pose", "poses.csv")))]
    srcs = [(float(r["x"]), float(r["y"])) for r in csv.DictReader(open(os.path.join(root, "src_gt.csv")))]
    hits = 0
    for f, (x, y, th) in zip(files, poses):
        fs, sig = wavfile.read(f)
        X = np.array([pra.transform.stft.analysis(sig[:, m].astype(np.float64), NFFT, NFFT // 2).T
                      for m in range(sig.shape[1])])
        doa = pra.doa.algorithms["MUSIC"](mics, fs, NFFT, c=343.0, num_src=N)
        doa.locate_sources(X, num_src=N, freq_range=BAND)
        for az in np.degrees(doa.azimuth_recon)[:N]:
            b = wrap(az + th)
            if min(abs(wrap(b - math.degrees(math.atan2(sy - y, sx - x)))) for sx, sy in srcs) <= TOL:
                hits += 1
    return hits / (N * len(files))


def iasm_score(iasm, root):
    out = subprocess.run([iasm, "ssl", "--dataset", root, "--method", "music", "--num", str(N),
                          "--score", "--json"], capture_output=True, text=True, check=True).stdout
    v = json.loads(out)
    return v["ours"]["score"]


def main(iasm, roots):
    print(f"{'scene':32s} {'iasm':>6s} {'pra':>6s}")
    for root in roots:
        ours = iasm_score(iasm, root)
        theirs = pra_score(root)
        print(f"{os.path.basename(root):32s} {ours:6.3f} {theirs:6.3f}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
