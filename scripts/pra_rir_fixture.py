#!/usr/bin/env python3
"""Writes fixtures/pra/rir_shoebox.json: one room impulse response by pyroomacoustics,
reduced to the few numbers the `sim` crate's cross-check test compares against
(crates/sim/tests/pra_crosscheck.rs). Hand-run only; the test reads the JSON, never Python.

    pip install pyroomacoustics==0.10.1
    python3 scripts/pra_rir_fixture.py > fixtures/pra/rir_shoebox.json

The parameters below are written into the fixture beside the numbers. pyroomacoustics'
high-pass filter is switched off (the test compares with `sim::ism::rir_unfiltered`), and
its responses are delayed by 40 samples (half its 81-tap fractional-delay filter), which
is removed here. Its amplitude convention is `damping / d`, without the `1 / (4 pi)` of
`sim`'s responses; the fixture says so and the test scales.
"""
import json

import numpy as np
import pyroomacoustics as pra

DIMS = [6.0, 4.0, 3.0]
# Energy absorption per wall: x = 0, x = Lx, y = 0, y = Ly, floor, ceiling.
ABSORPTION = [0.1, 0.2, 0.3, 0.15, 0.4, 0.25]
WALLS = ["west", "east", "south", "north", "floor", "ceiling"]
SRC = [1.3, 1.1, 1.4]
MIC = [3.5, 1.9, 2.3]  # chosen so that the seven early arrivals are >= 25 samples apart
FS = 16000
C = 343.0
MAX_ORDER = 15
WINDOW = 4  # arrival windows span round(t) +- WINDOW samples
EDC_STEP = 80  # samples (5 ms) between points of the energy decay curve


def main():
    pra.constants.set("rir_hpf_enable", False)
    pra.constants.set("c", C)
    mats = {w: pra.Material(a) for w, a in zip(WALLS, ABSORPTION)}
    room = pra.ShoeBox(DIMS, fs=FS, materials=mats, max_order=MAX_ORDER)
    room.add_source(SRC)
    room.add_microphone(MIC)
    room.compute_rir()
    delay = pra.constants.get("frac_delay_length") // 2
    h = np.asarray(room.rir[0][0], dtype=np.float64)[delay:]
    src = room.sources[0]
    early = [i for i in np.argsort(src.orders, kind="stable") if src.orders[i] <= 1]
    mic = np.array(MIC)
    arrivals = []
    for i in early:
        pos = src.images[:, i].astype(np.float64)
        t = float(np.linalg.norm(pos - mic) / C * FS)
        k = int(round(t))
        arrivals.append({
            "order": int(src.orders[i]),
            "image": [round(float(v), 6) for v in pos],
            "damping": round(float(src.damping[0, i]), 9),
            "t_samples": round(t, 4),
            "window_energy": float(np.sum(h[k - WINDOW:k + WINDOW + 1] ** 2)),
        })
    times = sorted(a["t_samples"] for a in arrivals)
    gap = min(b - a for a, b in zip(times, times[1:]))
    assert gap >= 2 * WINDOW + 2, f"arrivals only {gap:.1f} samples apart"
    edc = np.cumsum((h ** 2)[::-1])[::-1]
    edc_db = 10 * np.log10(np.maximum(edc / edc[0], 1e-30))
    fixture = {
        "about": "pyroomacoustics impulse response of one shoebox room, source and microphone, "
                 "reduced by scripts/pra_rir_fixture.py (parameters below)",
        "pyroomacoustics": pra.__version__,
        "params": {
            "dims": DIMS, "absorption": ABSORPTION, "src": SRC, "mic": MIC, "fs": FS,
            "c": C, "max_order": MAX_ORDER,
            "frac_delay_length": pra.constants.get("frac_delay_length"),
            "sinc_lut_granularity": pra.constants.get("sinc_lut_granularity"),
            "high_pass": False, "delay_removed_samples": delay,
            "amplitude": "damping / d (no 1 / (4 pi))",
            "window_half_samples": WINDOW, "edc_step_samples": EDC_STEP,
        },
        "image_count": int(src.images.shape[1]),
        "length_samples": int(len(h)),
        "total_energy": float(edc[0]),
        "arrivals": arrivals,
        "edc_db": [round(float(v), 4) for v in edc_db[::EDC_STEP]],
    }
    print(json.dumps(fixture, indent=1))


if __name__ == "__main__":
    main()
