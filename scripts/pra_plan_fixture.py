#!/usr/bin/env python3
"""Writes fixtures/pra/rir_lshape.json: an L-shaped room by pyroomacoustics
(`Room.from_corners(...).extrude(...)`), reduced to the numbers the `sim` crate's
cross-check test compares against (crates/sim/tests/pra_plan_crosscheck.rs). Hand-run
only; the test reads the JSON, never Python.

    pip install pyroomacoustics==0.10.1
    python3 scripts/pra_plan_fixture.py > fixtures/pra/rir_lshape.json

Two parts:

- `ism`: image sources only, up to order 3, for a talker in the wing and two
  microphones in the hall, one of them around the corner from it. Per microphone: the
  images pyroomacoustics finds visible (position, order, damping), the energy of the
  direct path and first reflections in windows around their arrivals, and the energy
  decay curve. The test asks `sim::plan` for the same images to the sample and the same
  decay within 1 dB.
- `hybrid`: the same room with uniform absorption, image sources to order 3 and ray
  tracing for the rest (pyroomacoustics' default for such rooms), 8 draws of its rays:
  the decay curve's mean in dB at 20-ms steps and the T20 it measures. The test
  compares the decay of `sim::plan`'s exact images and diffuse tail with it.

pyroomacoustics' high-pass filter is switched off and its 40-sample filter delay removed.
Its amplitudes are `damping / d`, without the `1 / (4 pi)` of `sim`'s responses.
"""
import json

import numpy as np
import pyroomacoustics as pra

CORNERS = [[0.0, 0.0], [8.0, 0.0], [8.0, 7.0], [5.0, 7.0], [5.0, 3.0], [0.0, 3.0]]
HEIGHT = 3.0
WALL_ABSORPTION = [0.1, 0.2, 0.3, 0.15, 0.25, 0.35]
FLOOR, CEILING = 0.4, 0.2
SRC = [6.5, 6.0, 1.5]
MICS = [[4.0, 1.5, 1.0], [2.0, 2.0, 1.2]]  # the second hears the talker only by reflection
FS = 16000
C = 343.0
MAX_ORDER = 3
WINDOW = 4
EDC_STEP = 80
HYBRID_ABSORPTION = 0.2
HYBRID_DRAWS = 8
HYBRID_STEP = 320  # 20 ms
HYBRID_LEN = 8000  # 0.5 s


def room(absorption, floor, ceiling, ray_tracing):
    mats = [pra.Material(a) for a in absorption]
    r = pra.Room.from_corners(np.array(CORNERS).T, fs=FS, max_order=MAX_ORDER,
                              materials=mats, ray_tracing=ray_tracing, air_absorption=False)
    r.extrude(HEIGHT, materials={"floor": pra.Material(floor), "ceiling": pra.Material(ceiling)})
    r.add_source(SRC)
    r.add_microphone_array(np.array(MICS).T)
    return r


def edc_db(h):
    e = np.cumsum((h ** 2)[::-1])[::-1]
    return 10 * np.log10(np.maximum(e / e[0], 1e-30))


def ism_part():
    r = room(WALL_ABSORPTION, FLOOR, CEILING, False)
    r.compute_rir()
    delay = pra.constants.get("frac_delay_length") // 2
    src = r.sources[0]
    out = []
    for m, mic in enumerate(MICS):
        h = np.asarray(r.rir[m][0], dtype=np.float64)[delay:]
        vis = np.flatnonzero(r.visibility[0][m])
        images = [{
            "image": [round(float(v), 6) for v in src.images[:, i]],
            "order": int(src.orders[i]),
            "damping": round(float(src.damping[0, i]), 9),
        } for i in vis]
        arrivals = []
        for i in vis:
            if src.orders[i] > 1:
                continue
            t = float(np.linalg.norm(src.images[:, i] - np.array(mic)) / C * FS)
            k = int(round(t))
            arrivals.append({"t_samples": round(t, 4), "order": int(src.orders[i]),
                             "window_energy": float(np.sum(h[k - WINDOW:k + WINDOW + 1] ** 2))})
        out.append({"mic": mic, "length_samples": int(len(h)), "images": images,
                    "arrivals": arrivals,
                    "edc_db": [round(float(v), 4) for v in edc_db(h)[::EDC_STEP]]})
    return out


def hybrid_part():
    curves, t20 = [], []
    for draw in range(HYBRID_DRAWS):
        np.random.seed(draw)
        r = room([HYBRID_ABSORPTION] * len(CORNERS), HYBRID_ABSORPTION, HYBRID_ABSORPTION, True)
        r.compute_rir()
        delay = pra.constants.get("frac_delay_length") // 2
        per_mic = []
        for m in range(len(MICS)):
            h = np.asarray(r.rir[m][0], dtype=np.float64)[delay:delay + HYBRID_LEN]
            per_mic.append(edc_db(h)[::HYBRID_STEP])
            t20.append(float(pra.experimental.measure_rt60(r.rir[m][0], fs=FS, decay_db=20)))
        curves.append(per_mic)
    mean = np.mean(np.array(curves), axis=0)
    return {"absorption": HYBRID_ABSORPTION, "draws": HYBRID_DRAWS,
            "step_samples": HYBRID_STEP, "length_samples": HYBRID_LEN,
            "edc_db": [[round(float(v), 3) for v in row] for row in mean],
            "t20_mean_s": round(float(np.mean(t20)), 4)}


def main():
    pra.constants.set("rir_hpf_enable", False)
    pra.constants.set("c", C)
    fixture = {
        "about": "pyroomacoustics impulse responses of an L-shaped room, reduced by "
                 "scripts/pra_plan_fixture.py (parameters below)",
        "pyroomacoustics": pra.__version__,
        "params": {"corners": CORNERS, "height": HEIGHT, "wall_absorption": WALL_ABSORPTION,
                   "floor": FLOOR, "ceiling": CEILING, "src": SRC, "fs": FS, "c": C,
                   "max_order": MAX_ORDER, "window_half_samples": WINDOW,
                   "edc_step_samples": EDC_STEP, "high_pass": False,
                   "amplitude": "damping / d (no 1 / (4 pi))"},
        "ism": ism_part(),
        "hybrid": hybrid_part(),
    }
    print(json.dumps(fixture, indent=1))


if __name__ == "__main__":
    main()
