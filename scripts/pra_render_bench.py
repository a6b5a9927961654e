#!/usr/bin/env python3
"""Baseline beside `iasm simulate`: pyroomacoustics renders the same scene file.

Hand-run benchmark only (no test or CI uses Python). Reads a scene TOML (the same file
`iasm simulate` renders: room, RT60, sources, array preset iasm6, waypoints, fs, clip),
builds one pyroomacoustics ShoeBox per stop the way its documentation does for a target
RT60 (`inverse_sabine` gives the wall absorption and the image order), and times
`room.simulate()` per stop: image sources, impulse responses, convolution, sensor noise.
Source signals are white noise (their content does not change the work). Nothing is
written to disk, while `iasm simulate` also writes its WAV files.

    pip install pyroomacoustics
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python3 scripts/pra_render_bench.py \
        fixtures/bench/arrangement_i.toml [--stops K] [--threads T]
"""
import argparse
import math
import time
import tomllib

import numpy as np
import pyroomacoustics as pra

IASM6 = [
    [0.1200, 0.0000, 0.1040], [-0.0600, 0.1039, 0.1040], [-0.0600, -0.1039, 0.1040],
    [-0.0606, -0.0350, 0.2080], [0.0606, -0.0350, 0.2080], [0.0000, 0.0700, 0.2080],
]


def stops(traj):
    """The same walk as the Rust scene loader: a stop every `spacing` m along the polyline."""
    if "poses" in traj:
        return [(x, y, math.radians(t)) for x, y, t in traj["poses"]]
    w, spacing = traj["waypoints"], traj["spacing"]
    out, carry = [], 0.0
    for a, b in zip(w, w[1:]):
        length = math.hypot(b[0] - a[0], b[1] - a[1])
        heading = math.atan2(b[1] - a[1], b[0] - a[0])
        s = carry
        while s <= length + 1e-9:
            f = s / length if length > 0 else 0.0
            out.append((a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), heading))
            s += spacing
        carry = s - length
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--stops", type=int, default=None, help="render only the first K stops")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    with open(args.scene, "rb") as f:
        sc = tomllib.load(f)
    pra.constants.set("num_threads", args.threads)
    fs, c = sc["fs"], sc.get("speed_of_sound", 343.0)
    pra.constants.set("c", c)
    dims = sc["room"]["dims"]
    e_abs, max_order = pra.inverse_sabine(sc["room"]["rt60"], dims, c=c)
    n = round(sc["clip_s"] * fs)
    rng = np.random.default_rng(sc.get("seed", 0))
    signals = [rng.standard_normal(n) for _ in sc["sources"]]
    height = sc["array"]["height"]
    poses = stops(sc["trajectory"])[: args.stops]
    print(f"pyroomacoustics {pra.__version__}: absorption {e_abs:.3f}, max_order {max_order}, "
          f"{len(sc['sources'])} sources, {len(poses)} stops, {n} samples at {fs} Hz")
    times = []
    for k, (x, y, th) in enumerate(poses):
        t0 = time.perf_counter()
        room = pra.ShoeBox(dims, fs=fs, materials=pra.Material(e_abs), max_order=max_order)
        for s, sig in zip(sc["sources"], signals):
            room.add_source(s["pos"], signal=sig)
        cs, sn = math.cos(th), math.sin(th)
        mics = np.array([[x + cs * p[0] - sn * p[1], y + sn * p[0] + cs * p[1], height + p[2]]
                         for p in IASM6]).T
        room.add_microphone_array(mics)
        room.simulate(snr=sc.get("snr_db"))
        times.append(time.perf_counter() - t0)
        rir_len = max(len(r) for row in room.rir for r in row)
        print(f"stop {k + 1}: {times[-1]:.2f} s (longest response {rir_len / fs:.2f} s)", flush=True)
    print(f"total {sum(times):.1f} s, {np.mean(times):.2f} s per stop "
          f"(min {min(times):.2f}, max {max(times):.2f})")


if __name__ == "__main__":
    main()
