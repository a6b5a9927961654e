#!/usr/bin/env python3
"""Drawn scenes (`iasm scenes generate`) rendered by pyroomacoustics: the generated
benchmark on another simulator's tails, so that the mapper is not fitted to ours.

For each scene file in SCENES: `iasm simulate` writes the data set (poses, occupancy map,
truth, the array's positions in `array.toml`); its audio is then replaced by
pyroomacoustics' rendering of the same room (`Room.from_corners(...).extrude(...)`,
image sources to order 3 and ray tracing for the rest, absorption from the scene's RT60
by `inverse_sabine`), the same sources (the same recordings for talkers; white, pink,
speech-shaped noise and a harmonic hum drawn here), the same stops and array, with white
sensor noise at the scene's SNR. Each data set is then mapped with `iasm eval` per method
(three maps) and its mean OSPA and right count printed, then the distribution.

Hand-run only (no test or CI uses Python); the figures it gave are in BENCHMARKS.md.

    pip install pyroomacoustics scipy
    iasm scenes generate --seed 1000 --count 12 --out /tmp/drawn
    python3 scripts/pra_generated.py /tmp/drawn /tmp/drawn-pra [IASM_BINARY]
"""
import json
import os
import subprocess
import sys

import numpy as np
import pyroomacoustics as pra
import tomllib
from scipy.io import wavfile

C = 343.0


def signal(src, n, fs, rng, base):
    """Unit-power source signal of `n` samples, as the scene names it."""
    if "wav" in src:
        rate, x = wavfile.read(os.path.join(base, src["wav"]))
        assert rate == fs, f"{src['wav']} is at {rate} Hz"
        x = x.astype(np.float64)
        x = np.resize(x, n)
    else:
        kind = src.get("signal", "speech_shaped")
        spec = np.fft.rfft(rng.normal(0.0, 1.0, n))
        f = np.fft.rfftfreq(n, 1.0 / fs)
        if kind == "pink_noise":
            spec /= np.sqrt(np.maximum(f, 20.0))
        elif kind == "speech_shaped":
            shape = np.where(f < 100, f / 100, np.where(f < 500, 1.0, 500 / np.maximum(f, 1)))
            spec *= shape
        elif kind == "voiced":
            f0 = src.get("f0", 140.0)
            t = np.arange(n) / fs
            x = sum(np.sin(2 * np.pi * h * f0 * t + rng.uniform(0, 2 * np.pi)) / h
                    for h in range(1, int(min(8000, fs / 2) / f0)))
            return x / np.sqrt(np.mean(x ** 2))
        x = np.fft.irfft(spec, n)
    return x / np.sqrt(np.mean(x ** 2))


def render(scene, base, ds, seed):
    fs = scene.get("fs", 16000)
    n = int(round(scene.get("clip_s", 1.0) * fs))
    rng = np.random.default_rng(seed)
    np.random.seed(seed)  # pyroomacoustics' ray tracing draws from numpy's global generator
    room = scene["room"]
    corners = np.array(room["plan"]).T
    height = room["height"]
    area = 0.5 * abs(np.dot(corners[0], np.roll(corners[1], 1)) - np.dot(corners[1], np.roll(corners[0], 1)))
    volume = area * height
    perimeter = np.sum(np.hypot(*(np.roll(corners, -1, axis=1) - corners)))
    surface = 2 * area + perimeter * height
    absorption = min(0.99, 0.161 * volume / (room["rt60"] * surface))  # Sabine
    with open(os.path.join(ds, "array.toml"), "rb") as f:
        mics = np.array(tomllib.load(f)["positions"])
    height_array = scene["array"]["height"]
    poses = np.loadtxt(os.path.join(ds, "pose/poses.csv"), delimiter=",", skiprows=1, ndmin=2)
    signals = [signal(s, n + fs, fs, rng, base) * 10 ** ((s.get("level_db", 65.0) - 65.0) / 20)
               for s in scene["sources"]]
    snr = scene.get("snr_db")
    for k, (x, y, th) in enumerate(poses):
        r = pra.Room.from_corners(corners, fs=fs, max_order=3, materials=pra.Material(absorption),
                                  ray_tracing=True, air_absorption=False)
        r.extrude(height, materials=pra.Material(absorption))
        for s, sig in zip(scene["sources"], signals):
            r.add_source(s["pos"], signal=sig)
        c, sn = np.cos(np.radians(th)), np.sin(np.radians(th))
        rot = np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1]])
        world = (rot @ mics.T) + np.array([[x], [y], [height_array]])
        r.add_microphone_array(world)
        r.simulate()
        audio = r.mic_array.signals[:, :n]
        if snr is not None:
            p = np.mean(audio ** 2)
            audio = audio + rng.normal(0.0, np.sqrt(p / 10 ** (snr / 10)), audio.shape)
        wavfile.write(os.path.join(ds, "audio", f"sub{k + 1:02d}.wav"), fs, audio.T.astype(np.float32))


def main():
    scenes, out = sys.argv[1], sys.argv[2]
    iasm = sys.argv[3] if len(sys.argv) > 3 else "target/release/iasm"
    os.makedirs(out, exist_ok=True)
    rows = []
    for name in sorted(f for f in os.listdir(scenes) if f.endswith(".toml")):
        path = os.path.join(scenes, name)
        with open(path, "rb") as f:
            scene = tomllib.load(f)
        num = scene.get("expect", {}).get("num", 4)
        ds = os.path.join(out, name[:-5])
        subprocess.run([iasm, "simulate", path, "--out", ds, "--force"], check=True, capture_output=True)
        try:
            render(scene, scenes, ds, scene.get("seed", 0))
        except ValueError as e:
            # pyroomacoustics' image sources need one visible image per source and
            # microphone: a source around two corners from a stop has none to order 3.
            print(f"{name[:-5]:<16} not rendered by pyroomacoustics: {e}", flush=True)
            continue
        for method in ["gcc-phat", "mvdr"]:
            o = subprocess.run([iasm, "eval", "--dataset", ds, "--method", method, "--num", str(num),
                                "--runs", "3", "--json"], capture_output=True, text=True)
            if o.returncode != 0:
                print(name, method, "failed:", o.stderr.strip()[-300:])
                continue
            r = json.loads(o.stdout)
            ca = next(v for v in r["variants"] if v["variant"] == "ca")
            rows.append((name[:-5], method, ca["mean"]))
            print(f"{name[:-5]:<16} {method:<9} {ca['mean']:.3f} right {ca['right_count']:.2f}", flush=True)
    for method in ["gcc-phat", "mvdr"]:
        v = np.array([r[2] for r in rows if r[1] == method])
        if len(v):
            print(f"{method}: {len(v)} scenes, mean {v.mean():.3f}, median {np.median(v):.3f}, "
                  f"90th percentile {np.percentile(v, 90):.3f}")


if __name__ == "__main__":
    main()
