"""Hand-run benchmark of the Python package (BENCHMARKS.md, "Python"): needs the package
installed (pip install ./crates/python), pyroomacoustics, and the CLI built in release.

1. iasm.doa against pyroomacoustics' own class of the same method on pyroomacoustics'
   DOA example (examples/doa_algorithms.py: 6 + 1 microphones, nfft 256, bins 5-59):
   object made and locate_sources run, medians of interleaved runs, one thread.
2. iasm.locate on 3-s, 48 kHz, 6-channel recordings against `iasm ssl --threads 1` on
   the same files: the CLI's own per-recording time (read and localise) from its
   --timing output, and Python's (read_wav + locate) per recording.

    python scripts/bench_python.py [DATA_SET_FOLDER]   (default: a rendered scene)
"""

import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pyroomacoustics as pra

import iasm

ROOT = Path(__file__).resolve().parents[1]
CLI = os.environ.get("IASM_BIN", str(ROOT / "target" / "release" / "iasm"))
os.environ.setdefault("RAYON_NUM_THREADS", "1")


def pra_example(seed=1):
    np.random.seed(seed)
    azimuth, distance, snr, c, fs, nfft = np.deg2rad(61.0), 3.0, 0.0, 343.0, 16000, 256
    room_dim = np.r_[10.0, 10.0]
    echo = pra.circular_2D_array(center=room_dim / 2, M=6, phi0=0, radius=37.5e-3)
    echo = np.concatenate((echo, np.array(room_dim / 2, ndmin=2).T), axis=1)
    sigma2 = 10 ** (-snr / 10) / (4.0 * np.pi * distance) ** 2
    room = pra.ShoeBox(room_dim, fs=fs, max_order=0, sigma2_awgn=sigma2)
    room.add_source(room_dim / 2 + distance * np.r_[np.cos(azimuth), np.sin(azimuth)],
                    signal=np.random.randn((nfft // 2 + 1) * nfft))
    room.add_microphone_array(pra.MicrophoneArray(echo, room.fs))
    room.simulate()
    X = np.array([pra.transform.stft.analysis(s, nfft, nfft // 2).T for s in room.mic_array.signals])
    return echo, fs, nfft, c, X


def drop_in(runs=31):
    echo, fs, nfft, c, X = pra_example()
    bins = np.arange(5, 60)
    print("| method | pyroomacoustics (ms) | iasm.doa (ms) | ratio | azimuths (pra / iasm) |")
    print("|---|---:|---:|---:|---|")
    for name in ["SRP", "MUSIC", "NormMUSIC", "TOPS", "CSSM", "WAVES"]:
        times = {"pra": [], "iasm": []}
        az = {}
        for _ in range(runs):
            for key, lib in (("pra", pra), ("iasm", iasm)):
                t = time.perf_counter()
                d = lib.doa.algorithms[name](echo, fs, nfft, c=c, num_src=1)
                d.locate_sources(X, freq_bins=bins)
                times[key].append(time.perf_counter() - t)
                az[key] = float(np.rad2deg(d.azimuth_recon[0]))
        a, b = statistics.median(times["pra"]) * 1e3, statistics.median(times["iasm"]) * 1e3
        print(f"| {name} | {a:.2f} | {b:.2f} | {a / b:.1f}x | {az['pra']:.1f} / {az['iasm']:.2f} |")


def per_recording(folder, runs=5):
    ds = iasm.read_dataset(folder)
    files = ds.recordings
    array = str(Path(folder) / "array.toml") if (Path(folder) / "array.toml").exists() else "iasm6"
    x, fs = iasm.read_wav(files[0])
    print(f"\n{len(files)} recordings of {x.shape[1] / fs:.2f} s, {fs} Hz, {x.shape[0]} channels")
    print("| method | CLI ms/recording | Python ms/recording | ratio |")
    print("|---|---:|---:|---:|")
    for method in ["mvdr", "gcc-phat"]:
        cli, py = [], []
        for _ in range(runs):
            t = time.perf_counter()
            subprocess.run([CLI, "ssl", *files, "--array", array, "--method", method, "--threads", "1"],
                           check=True, capture_output=True)
            cli.append((time.perf_counter() - t) / len(files))
            t = time.perf_counter()
            for f in files:
                s, r = iasm.read_wav(f)
                iasm.locate(s, r, array, method)
            py.append((time.perf_counter() - t) / len(files))
        a, b = statistics.median(cli) * 1e3, statistics.median(py) * 1e3
        print(f"| {method} | {a:.1f} | {b:.1f} | {b / a:.2f} |")
    print("(the CLI's time includes its process start, spread over the recordings)")


if __name__ == "__main__":
    drop_in()
    if len(sys.argv) > 1:
        per_recording(sys.argv[1])
    else:
        with tempfile.TemporaryDirectory() as d:
            iasm.simulate(ROOT / "fixtures" / "rooms" / "two_talkers.toml", out=Path(d) / "ds")
            per_recording(Path(d) / "ds")
