#!/usr/bin/env python3
"""A robot survey rendered by pyroomacoustics: another simulator than ours, for cross-checks.

Five talkers speak real sentences (espeak-ng, resampled to 16 kHz by sox) in a 7.5 x 6 x
2.8 m shoebox room; the iasm6 array (or the ReSpeaker 4-mic), 0.6 m above the floor, stops every 0.5 m along an
L-shaped path, heading along it, and records 2 s at each stop (each talker from a random
point of its sentence), with white sensor noise at SNR_DB. Written in the published layout
without an occupancy map: `audio/subNN.wav` (16-bit), `pose/poses.csv` (x, y, theta_deg),
`src_gt.csv`. Map it with `iasm eval --dataset OUT --method M --runs 20` (the sources are
then searched within `--open-margin` of the stops).

Hand-run only (no test or CI uses Python); the figures it gave are in BENCHMARKS.md.

    pip install pyroomacoustics scipy; apt-get install espeak-ng sox
    python3 scripts/pra_mobile_survey.py OUT [RT60_S] [SNR_DB] [SEED] [iasm6|respeaker4]

`TALKERS=1,3` (environment) keeps only those talkers of the five (0-based), for scenes of
fewer sources (BENCHMARKS.md). `SIGNAL=noise` makes each source a steady
white-noise source (a fan, an air vent) in place of its sentence, for the steady-recording
pooling (`ssl::Pooling::Auto`; BENCHMARKS.md). `FAN_DB=50` puts a fan on the
robot (pink noise at that level in dB SPL at 1 m, the talkers being at 65 dB; 0.2 m behind
and 0.3 m below the array's centre, moving with it) and writes the robot alone (4 s at the
first stop, another stretch of the fan's noise, the same sensor noise level) as
`noise/robot.wav`, for the robot's-noise subtraction (`ssl::noise`; BENCHMARKS.md); every WAV then shares one scale, so that the levels of the stops and of the
robot alone agree.
"""
import os
import subprocess
import sys
import tempfile

import numpy as np
import pyroomacoustics as pra
from scipy.io import wavfile

FS = 16000
ARRAYS = {
    "iasm6": np.array([
        [0.1200, 0.0, 0.1040], [-0.0600, 0.1039, 0.1040], [-0.0600, -0.1039, 0.1040],
        [-0.0606, -0.0350, 0.2080], [0.0606, -0.0350, 0.2080], [0.0000, 0.0700, 0.2080],
    ]),
    # iasm's `respeaker4` preset: radius 32 mm, its channel order.
    "respeaker4": np.array([[-0.032, 0.0, 0.0], [0.0, -0.032, 0.0], [0.032, 0.0, 0.0], [0.0, 0.032, 0.0]]),
}
DIMS = [7.5, 6.0, 2.8]
ARRAY_Z = 0.6
CLIP_S = 2.0
TALKERS_ALL = [
    ("en-us", [1.2, 4.9, 1.5], "Good morning. The meeting starts at nine, so please be on time, and bring the report."),
    ("en-gb+f3", [4.0, 5.2, 1.1], "I think the printer on the second floor is broken again. Could someone call the technician?"),
    ("en-us+m3", [6.6, 3.4, 1.6], "Turn left at the corridor, then walk straight until you see the red door on your right."),
    ("en-gb+f2", [5.2, 0.7, 1.0], "The weather will be cloudy this afternoon with a chance of light rain in the evening."),
    ("en-us+m7", [2.3, 0.9, 1.3], "Numbers one, two, three, four, five. Testing the microphones once more, one more time."),
]
TALKERS = [TALKERS_ALL[i] for i in map(int, os.environ.get("TALKERS", "0,1,2,3,4").split(","))]
WAYPOINTS = [(0.8, 2.6), (5.2, 2.6), (5.2, 4.2)]
SPACING = 0.5


def speech(voice, text, tmp):
    raw, out = os.path.join(tmp, "raw.wav"), os.path.join(tmp, "s.wav")
    subprocess.run(["espeak-ng", "-v", voice, "-s", "150", "-w", raw, text], check=True)
    subprocess.run(["sox", raw, "-r", str(FS), "-c", "1", "-b", "16", out], check=True)
    fs, s = wavfile.read(out)
    s = s.astype(np.float64) / 32768.0
    return s / np.sqrt(np.mean(s[np.abs(s) > 1e-4] ** 2))


def pink(n, rng):
    """Unit-power pink noise (1/f power), shaped in the frequency domain."""
    spec = np.fft.rfft(rng.normal(0.0, 1.0, n))
    f = np.arange(len(spec))
    spec[1:] /= np.sqrt(f[1:])
    spec[0] = 0.0
    x = np.fft.irfft(spec, n)
    return x / np.sqrt(np.mean(x ** 2))


FAN_OFFSET = np.array([-0.2, 0.0, -0.3])
ALONE_S = 4.0


def stops():
    poses = []
    for (x0, y0), (x1, y1) in zip(WAYPOINTS, WAYPOINTS[1:]):
        n = int(round(np.hypot(x1 - x0, y1 - y0) / SPACING))
        th = np.degrees(np.arctan2(y1 - y0, x1 - x0))
        poses += [(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, th) for k in range(n)]
    return poses + [(WAYPOINTS[-1][0], WAYPOINTS[-1][1], poses[-1][2])]


def main():
    out = sys.argv[1]
    rt60 = float(sys.argv[2]) if len(sys.argv) > 2 else 0.5
    snr = float(sys.argv[3]) if len(sys.argv) > 3 else 20.0
    rng = np.random.default_rng(int(sys.argv[4]) if len(sys.argv) > 4 else 1)
    array = ARRAYS[sys.argv[5] if len(sys.argv) > 5 else "iasm6"]
    if os.environ.get("SIGNAL", "speech") == "noise":
        sigs = [rng.normal(0.0, 1.0, int(10 * FS)) for _ in TALKERS]
    else:
        with tempfile.TemporaryDirectory() as tmp:
            sigs = [speech(v, t, tmp) for v, _, t in TALKERS]
    e_abs, max_order = pra.inverse_sabine(rt60, DIMS)
    os.makedirs(out + "/audio", exist_ok=True)
    os.makedirs(out + "/pose", exist_ok=True)
    poses = stops()
    n = int(CLIP_S * FS)
    fan_db = os.environ.get("FAN_DB")
    fan_gain = None if fan_db is None else 10 ** ((float(fan_db) - 65.0) / 20.0)

    def heard(x, y, th, sources, length):
        room = pra.ShoeBox(DIMS, fs=FS, materials=pra.Material(e_abs), max_order=max_order)
        c, sn = np.cos(np.radians(th)), np.sin(np.radians(th))
        rot = np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1]])
        centre = np.array([x, y, ARRAY_Z])
        for pos, signal in sources:
            if pos is None:  # the fan, in the array frame
                pos = rot @ FAN_OFFSET + centre
            room.add_source(list(pos), signal=signal)
        room.add_microphone_array(pra.MicrophoneArray(rot @ array.T + centre[:, None], FS))
        room.simulate()
        return room.mic_array.signals[:, :length]

    clips, sd0 = [], None
    for k, (x, y, th) in enumerate(poses):
        sources = [(pos, np.roll(s, -rng.integers(0, len(s)))[:n]) for s, (_, pos, _) in zip(sigs, TALKERS)]
        talkers = heard(x, y, th, sources, n)
        sd = np.sqrt(np.mean(talkers ** 2) / 10 ** (snr / 10))
        sd0 = sd if sd0 is None else sd0
        sig = talkers
        if fan_gain is not None:
            sig = sig + heard(x, y, th, [(None, fan_gain * pink(n, rng))], n)
        sig = sig + rng.normal(0, sd, sig.shape)
        if fan_gain is None:
            sig = 0.5 * sig / np.max(np.abs(sig))
        clips.append(sig)
    if fan_gain is not None:
        m = int(ALONE_S * FS)
        x, y, th = poses[0]
        alone = heard(x, y, th, [(None, fan_gain * pink(m, rng))], m)
        alone = alone + rng.normal(0, sd0, alone.shape)
        scale = 0.5 / max(np.max(np.abs(c)) for c in clips + [alone])
        clips = [c * scale for c in clips]
        os.makedirs(out + "/noise", exist_ok=True)
        wavfile.write(f"{out}/noise/robot.wav", FS, (alone.T * scale * 32767).astype(np.int16))
    for k, sig in enumerate(clips):
        wavfile.write(f"{out}/audio/sub{k + 1:02d}.wav", FS, (sig.T * 32767).astype(np.int16))
    with open(out + "/pose/poses.csv", "w") as f:
        f.write("x,y,theta_deg\n" + "".join(f"{x:.4f},{y:.4f},{th:.4f}\n" for x, y, th in poses))
    with open(out + "/src_gt.csv", "w") as f:
        f.write("x,y,z\n" + "".join(f"{p[0]},{p[1]},{p[2]}\n" for _, p, _ in TALKERS))
    print(f"{out}: {len(poses)} stops, {len(TALKERS)} talkers, RT60 {rt60} s, max_order {max_order}")


if __name__ == "__main__":
    main()
