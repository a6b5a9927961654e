#!/usr/bin/env python3
"""Baseline beside `iasm ssl`: pyroomacoustics' DoA methods on the same recordings.

Hand-run cross-check only (no test or CI uses Python). Scores each method with the same
rule as `iasm ssl --score` (first N DoAs, hit within TOL degrees of a true bearing) and
times it per recording, single thread, file read included.

    pip install pyroomacoustics openpyxl
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python3 scripts/pra_baseline.py DATASET_DIR
"""
import glob
import os
import re
import sys
import time

import numpy as np
import openpyxl
import pyroomacoustics as pra
from scipy.io import wavfile

MICS = np.array([
    [0.1200, 0.0, 0.1040], [-0.0600, 0.1039, 0.1040], [-0.0600, -0.1039, 0.1040],
    [-0.0606, -0.0350, 0.2080], [0.0606, -0.0350, 0.2080], [0.0000, 0.0700, 0.2080],
]).T
N, TOL, NFFT, BAND = 4, 5.0, 1024, [200.0, 8000.0]


def natural(s):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


def wrap(a):
    return (a + 180.0) % 360.0 - 180.0


def main(root):
    files = sorted(glob.glob(os.path.join(root, "audio", "*.wav")), key=natural)
    ws = openpyxl.load_workbook(glob.glob(os.path.join(root, "pose", "*.xlsx"))[0]).active
    poses = [tuple(float(c) for c in row[:3]) for row in ws.iter_rows(values_only=True)]
    text = open(glob.glob(os.path.join(root, "src_gt*.txt"))[0]).read()
    srcs = [tuple(float(v) for v in m.split(",")[:2]) for m in re.findall(r"\[([^\]]+)\]", text)]
    for name in ["NormMUSIC", "SRP", "MUSIC", "TOPS"]:
        hits, t0 = 0, time.perf_counter()
        for f, (x, y, th) in zip(files, poses):
            fs, sig = wavfile.read(f)
            X = np.array([pra.transform.stft.analysis(sig[:, m].astype(np.float64), NFFT, NFFT // 2).T
                          for m in range(sig.shape[1])])
            doa = pra.doa.algorithms[name](MICS, fs, NFFT, c=343.0, num_src=N, max_four=4)
            doa.locate_sources(X, num_src=N, freq_range=BAND)
            for az in np.degrees(doa.azimuth_recon)[:N]:
                b = wrap(az + th)
                if min(abs(wrap(b - np.degrees(np.arctan2(sy - y, sx - x)))) for sx, sy in srcs) <= TOL:
                    hits += 1
        dt = (time.perf_counter() - t0) / len(files)
        print(f"{name:10s} score {hits / (N * len(files)):.3f}  {1e3 * dt:7.1f} ms per recording")


if __name__ == "__main__":
    main(sys.argv[1])
