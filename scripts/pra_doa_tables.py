#!/usr/bin/env python3
"""pyroomacoustics' DoA methods on a data set's recordings, as DoA tables that
`iasm compare --table` puts beside iasm's methods (issue 52). Hand-run only.

One CSV per method (SRP, MUSIC, NormMUSIC, TOPS, CSSM, WAVES, or those named), one row per
recording in the audio's natural order, N azimuths in degrees in the array frame,
strongest first: pyroomacoustics' default use (nfft 1024, 200-8000 Hz, one spectrum per
recording, num_src = N). The array is the data set's `array.toml`, else the paper's.

    pip install pyroomacoustics
    OMP_NUM_THREADS=1 python3 scripts/pra_doa_tables.py DATASET OUTDIR [--num 4] [--methods MUSIC,TOPS]
    iasm compare --dataset DATASET --table OUTDIR/pra_MUSIC.csv --table OUTDIR/pra_TOPS.csv
"""
import argparse
import glob
import os
import re
import time
import tomllib

import numpy as np
import pyroomacoustics as pra
from scipy.io import wavfile

IASM6 = [[0.1200, 0.0, 0.1040], [-0.0600, 0.1039, 0.1040], [-0.0600, -0.1039, 0.1040],
         [-0.0606, -0.0350, 0.2080], [0.0606, -0.0350, 0.2080], [0.0000, 0.0700, 0.2080]]
NFFT, BAND = 1024, [200.0, 8000.0]
METHODS = ["SRP", "MUSIC", "NormMUSIC", "TOPS", "CSSM", "WAVES"]


def natural(s):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("out")
    ap.add_argument("--num", type=int, default=4)
    ap.add_argument("--methods", default=",".join(METHODS))
    a = ap.parse_args()
    array_file = os.path.join(a.dataset, "array.toml")
    mics = np.array(tomllib.load(open(array_file, "rb"))["positions"] if os.path.exists(array_file)
                    else IASM6).T
    files = sorted(glob.glob(os.path.join(a.dataset, "audio", "*.wav")), key=natural)
    os.makedirs(a.out, exist_ok=True)
    for name in a.methods.split(","):
        t0, rows = time.perf_counter(), []
        for f in files:
            fs, sig = wavfile.read(f)
            X = np.array([pra.transform.stft.analysis(sig[:, m].astype(np.float64), NFFT, NFFT // 2).T
                          for m in range(sig.shape[1])])
            doa = pra.doa.algorithms[name](mics, fs, NFFT, c=343.0, num_src=a.num, max_four=4)
            doa.locate_sources(X, num_src=a.num, freq_range=BAND)
            az = (np.degrees(doa.azimuth_recon)[: a.num] + 180.0) % 360.0 - 180.0
            rows.append(",".join(f"{v:.2f}" for v in az))
        path = os.path.join(a.out, f"pra_{name}.csv")
        open(path, "w").write("\n".join(rows) + "\n")
        ms = 1e3 * (time.perf_counter() - t0) / len(files)
        print(f"{path}: {len(rows)} rows, {ms:.1f} ms per recording")


if __name__ == "__main__":
    main()
