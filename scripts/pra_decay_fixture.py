#!/usr/bin/env python3
"""Fixture for issue 9: two white-noise sources that stop, rendered by pyroomacoustics.

pyroomacoustics' `room.simulate()` keeps the room's decay after the sources stop (its
output is the signal plus the impulse response's length), the case in which max pooling
let reverberation-only blocks outvote the sources. Writes fixtures/pra/decay_rt03.wav and
decay_rt05.wav (6 channels, the iasm6 array, 16 kHz, 16-bit) and decay.json (the true
azimuths in the array frame). Hand-run only; the Rust tests read the committed files.

    pip install pyroomacoustics
    python3 scripts/pra_decay_fixture.py
"""
import json
import os

import numpy as np
import pyroomacoustics as pra
from scipy.io import wavfile

FS = 16000
MICS = np.array([
    [0.1200, 0.0, 0.1040], [-0.0600, 0.1039, 0.1040], [-0.0600, -0.1039, 0.1040],
    [-0.0606, -0.0350, 0.2080], [0.0606, -0.0350, 0.2080], [0.0000, 0.0700, 0.2080],
])
CENTER = np.array([3.0, 2.5, 1.0])   # the array frame's origin; heading +x
AZIMUTHS = [40.0, -160.0]            # degrees, array frame
DIST, HEIGHT, ACTIVE_S = 1.5, 1.1, 0.5
OUT = os.path.join(os.path.dirname(__file__), "..", "fixtures", "pra")


def main():
    rng = np.random.default_rng(9)
    sources = [
        CENTER[:2] + DIST * np.array([np.cos(np.radians(a)), np.sin(np.radians(a))])
        for a in AZIMUTHS
    ]
    signals = [rng.standard_normal(int(ACTIVE_S * FS)) for _ in sources]
    for rt60, name in [(0.3, "decay_rt03.wav"), (0.5, "decay_rt05.wav")]:
        dims = [6.0, 5.0, 3.0]
        absorption, max_order = pra.inverse_sabine(rt60, dims)
        room = pra.ShoeBox(dims, fs=FS, materials=pra.Material(absorption),
                           max_order=max_order)
        for s, x in zip(sources, signals):
            room.add_source([s[0], s[1], HEIGHT], signal=x)
        room.add_microphone_array((MICS + CENTER).T)
        room.simulate()
        y = room.mic_array.signals
        y = y / np.abs(y).max() * 0.9
        wavfile.write(os.path.join(OUT, name), FS, (y.T * 32767).astype(np.int16))
        print(name, y.shape, f"{y.shape[1] / FS:.2f} s")
    with open(os.path.join(OUT, "decay.json"), "w") as f:
        json.dump({
            "fs": FS, "azimuths_deg": AZIMUTHS, "distance_m": DIST, "active_s": ACTIVE_S,
            "room": [6.0, 5.0, 3.0], "array_center": CENTER.tolist(), "source_height": HEIGHT,
            "generator": f"pyroomacoustics {pra.__version__}, inverse_sabine, simulate()",
        }, f, indent=1)


if __name__ == "__main__":
    main()
