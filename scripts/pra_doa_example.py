#!/usr/bin/env python3
"""Fixture for issue 52: pyroomacoustics' DOA example, and its TOPS, CSSM and WAVES answers.

The scene of pyroomacoustics' `examples/doa_algorithms.py`: a 2-D anechoic room 10 m x 10 m,
a hexagonal array of radius 37.5 mm with a seventh microphone at its centre, one
white-noise source 3 m away at 61 degrees, SNR 0 dB, 16 kHz, nfft 256 with half overlap,
FFT bins 5-59. Writes fixtures/pra/doa_example.wav (7 channels, 16-bit, 1 s) and
doa_example.json (the array, the truth, the bins and each method's azimuth as
pyroomacoustics' own class finds it on that very file). Hand-run only; the Rust test
`crates/ssl/tests/pra_doa_example.rs` reads the committed files.

    pip install pyroomacoustics
    python3 scripts/pra_doa_example.py
"""
import json
import os

import numpy as np
import pyroomacoustics as pra
from scipy.io import wavfile

FS, NFFT, C = 16000, 256, 343.0
AZIMUTH, DISTANCE, SNR = 61.0, 3.0, 0.0
FREQ_BINS = np.arange(5, 60)
OUT = os.path.join(os.path.dirname(__file__), "..", "fixtures", "pra")


def main():
    rng = np.random.default_rng(61)
    room_dim = np.r_[10.0, 10.0]
    echo = pra.circular_2D_array(center=room_dim / 2, M=6, phi0=0, radius=37.5e-3)
    echo = np.concatenate((echo, np.array(room_dim / 2, ndmin=2).T), axis=1)
    az = np.radians(AZIMUTH)
    source = room_dim / 2 + DISTANCE * np.r_[np.cos(az), np.sin(az)]
    sigma2 = 10 ** (-SNR / 10) / (4.0 * np.pi * DISTANCE) ** 2
    room = pra.ShoeBox(room_dim, fs=FS, max_order=0, sigma2_awgn=sigma2)
    room.add_source(source, signal=rng.standard_normal(FS))
    room.add_microphone_array(pra.MicrophoneArray(echo, FS))
    room.simulate()
    sig = room.mic_array.signals[:, :FS]
    pcm = np.round(sig / np.abs(sig).max() * 0.9 * 32767).astype(np.int16)
    os.makedirs(OUT, exist_ok=True)
    wavfile.write(os.path.join(OUT, "doa_example.wav"), FS, pcm.T)
    # pyroomacoustics' answers on the file as written (16-bit), as its example runs them.
    x = pcm.astype(np.float64) / 32768.0
    X = np.array([pra.transform.stft.analysis(ch, NFFT, NFFT // 2).T for ch in x])
    mics = echo - room_dim[:, None] / 2  # the array frame: its centre at the origin
    found = {}
    for name in ["SRP", "MUSIC", "NormMUSIC", "TOPS", "CSSM", "WAVES"]:
        doa = pra.doa.algorithms[name](mics, FS, NFFT, c=C, num_src=1, max_four=4)
        doa.locate_sources(X, freq_bins=FREQ_BINS)
        found[name] = round(float(np.degrees(doa.azimuth_recon[0])), 3)
        print(f"{name}: {found[name]} degrees")
    json.dump({
        "fs": FS, "nfft": NFFT, "hop": NFFT // 2, "c": C,
        "freq_bins": [int(FREQ_BINS[0]), int(FREQ_BINS[-1])],
        "azimuth_deg": AZIMUTH,
        "mics": [[round(float(p[0]), 6), round(float(p[1]), 6), 0.0] for p in mics.T],
        "pyroomacoustics": pra.__version__,
        "azimuths_deg": found,
    }, open(os.path.join(OUT, "doa_example.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
