#!/usr/bin/env python3
"""Writes a data set in the published layout (audio/*.wav, one per stop, and
pose/*.csv with x, y, theta_deg) as the ROS 1 bag a robot would have recorded on the same
run, with rosbags: at each stop the robot stands for the recording plus margins, and
drives to the next stop in between; audio_common_msgs/AudioData in 0.1-s buffers
(S16LE, AudioInfo beside them) and nav_msgs/Odometry at 20 Hz. The stop's recording fills
its listening window exactly (`iasm bag`'s default settling 0.3 s and end margin 0.2 s
are padded with low noise), so that `iasm bag` then `iasm map` can be compared with
`iasm map` on the data set itself.

    pip install rosbags==0.11.9 scipy
    python3 scripts/dataset_to_bag.py DATASET OUT.bag [--drive 1.0]

With --ros2, OUT is a ROS 2 bag (MCAP storage, CDR; a folder, or with OUT ending in .mcap
one MCAP file in zstd chunks, as `ros2 bag record` compresses them) as a ROS 2 robot records it:
audio_common_msgs/msg/AudioStamped on /audio as the ROS 2 audio_common's
audio_capturer_node publishes it (int16 samples, each buffer stamped with its last
sample's time), nav_msgs/msg/Odometry on /odom, and the data set's map as
nav_msgs/msg/OccupancyGrid on /map (frame `odom`, the poses' frame, sent once at the
start). fixtures/bags/sim_run.mcap was made so, from the scene in fixtures/bags/sim/:

    pip install rosbags==0.11.9 scipy mcap zstandard
    iasm simulate fixtures/bags/sim/two_talkers_six_stops.toml --out /tmp/sim6
    python3 scripts/dataset_to_bag.py /tmp/sim6 fixtures/bags/sim_run.mcap --ros2 --drive 0.4
"""

import argparse
import math
import os
import sys
from pathlib import Path

import numpy as np
from scipy.io import wavfile

sys.path.insert(0, str(Path(__file__).parent))
from make_bag_fixtures import header, quat, typestore  # noqa: E402
from rosbags.rosbag1 import Writer  # noqa: E402

T0 = 1_700_000_000_000_000_000
SETTLE, END = 0.3, 0.2


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("out")
    ap.add_argument("--drive", type=float, default=1.0, help="seconds between stops")
    ap.add_argument("--ros2", action="store_true", help="a ROS 2 bag folder (module docs)")
    ap.add_argument("--stamped", action="store_true",
                    help="AudioDataStamped, each buffer stamped with its last sample's time "
                         "(else AudioData, timed by its receipt 2 ms later)")
    a = ap.parse_args()
    d = Path(a.dataset)
    wavs = sorted((d / "audio").glob("*.wav"), key=lambda p: [int(t) if t.isdigit() else t for t in __import__("re").split(r"(\d+)", p.name)])
    pose_file = next((d / "pose").glob("*.csv"))
    poses = np.genfromtxt(pose_file, delimiter=",", names=True)
    fs = None
    clips = []
    for w in wavs:
        r, x = wavfile.read(w)
        if x.dtype != np.int16:
            x = np.clip(np.round(x.astype(np.float64) / np.max(np.abs(x)) * 0.5 * 32767), -32768, 32767).astype(np.int16)
        fs = fs or r
        clips.append(x)
    ch = clips[0].shape[1]
    rng = np.random.default_rng(1)
    pad = lambda s: (rng.standard_normal((int(round(s * fs)), ch)) * 3).astype(np.int16)
    # The run: for stop k, SETTLE of pad, the clip, END of pad, then a drive of pad.
    pieces, schedule, t = [], [], 0.0
    for k, x in enumerate(clips):
        still = SETTLE + len(x) / fs + END
        schedule.append((t, t + still))
        pieces += [pad(SETTLE), x, pad(END)]
        t += still
        if k + 1 < len(clips):
            pieces.append(pad(a.drive))
            t += a.drive
    audio = np.concatenate(pieces)
    total = len(audio) / fs

    def pose_at(t):
        for k, (s, e) in enumerate(schedule):
            if t <= e:
                if t >= s or k == 0:
                    p = poses[k]
                    return p["x"], p["y"], math.radians(p["theta_deg"])
                u = (t - schedule[k - 1][1]) / (s - schedule[k - 1][1])
                p, q = poses[k - 1], poses[k]
                th = math.radians(p["theta_deg"]) + u * math.remainder(math.radians(q["theta_deg"] - p["theta_deg"]), 2 * math.pi)
                return p["x"] + u * (q["x"] - p["x"]), p["y"] + u * (q["y"] - p["y"]), th
        p = poses[-1]
        return p["x"], p["y"], math.radians(p["theta_deg"])

    if a.ros2:
        write_ros2(a, d, audio, fs, ch, total, pose_at)
        return
    ts = typestore()
    T = ts.types
    out = Path(a.out)
    out.unlink(missing_ok=True)
    with Writer(out) as w:
        ci = w.add_connection("/audio/audio_info", "audio_common_msgs/msg/AudioInfo", typestore=ts, latching=1)
        audio_type = "audio_common_msgs/msg/AudioDataStamped" if a.stamped else "audio_common_msgs/msg/AudioData"
        ca = w.add_connection("/audio/audio_stamped" if a.stamped else "/audio/audio", audio_type, typestore=ts)
        co = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        info = T["audio_common_msgs/msg/AudioInfo"](channels=ch, sample_rate=fs, sample_format="S16LE", bitrate=fs * ch * 16, coding_format="wave")
        w.write(ci, T0, ts.serialize_ros1(info, "audio_common_msgs/msg/AudioInfo"))
        events = []
        buf = fs // 10
        for k in range(0, len(audio), buf):
            blk = audio[k:k + buf]
            ns = T0 + round((k + len(blk)) / fs * 1e9)
            msg = T["audio_common_msgs/msg/AudioData"](data=np.frombuffer(blk.astype("<i2").tobytes(), dtype=np.uint8))
            if a.stamped:
                msg = T[audio_type](header=header(ts, ns, "mic"), audio=msg)
            events.append((ns + 2_000_000, ca, ts.serialize_ros1(msg, audio_type)))
        V = T["geometry_msgs/msg/Vector3"]
        for j in range(int(total * 20) + 1):
            t = j / 20
            x, y, th = pose_at(t)
            ns = T0 + round(t * 1e9)
            P = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0), orientation=quat(ts, th))
            msg = T["nav_msgs/msg/Odometry"](
                header=header(ts, ns, "odom"), child_frame_id="base_link",
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=P, covariance=np.zeros(36)),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=V(x=0.0, y=0.0, z=0.0), angular=V(x=0.0, y=0.0, z=0.0)), covariance=np.zeros(36)))
            events.append((ns + 1_000_000, co, ts.serialize_ros1(msg, "nav_msgs/msg/Odometry")))
        for ns, c, data in sorted(events, key=lambda e: e[0]):
            w.write(c, ns, data)
    print(f"{out}: {len(clips)} stops, {total:.1f} s, {os.path.getsize(out)} bytes")


def read_map(d):
    """The data set's map/*.yaml and its PGM as (resolution, origin, rows from the bottom
    as ROS occupancy values), or None."""
    import re
    yamls = sorted((d / "map").glob("*.yaml"))
    if not yamls:
        return None
    text = yamls[0].read_text()
    res = float(re.search(r"resolution:\s*([0-9.eE+-]+)", text).group(1))
    origin = [float(v) for v in re.search(r"origin:\s*\[([^\]]*)\]", text).group(1).split(",")]
    image = re.search(r"image:\s*(\S+)", text).group(1)
    raw = (yamls[0].parent / image).read_bytes()
    parts = raw.split(maxsplit=4)
    w, h = int(parts[1]), int(parts[2])
    px = np.frombuffer(parts[4][: w * h], dtype=np.uint8).reshape(h, w)[::-1]
    occ = np.where(px <= 50, 100, np.where(px >= 250, 0, -1)).astype(np.int8)
    return res, origin, w, h, occ.reshape(-1)


def write_ros2(a, d, audio, fs, ch, total, pose_at):
    from make_bag_fixtures import AUDIO_STAMPED_DEFS, stamp
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for name, text in AUDIO_STAMPED_DEFS.items():
        types.update(get_types_from_msg(text, name))
    ts.register(types)
    T = ts.types
    import shutil
    import tempfile
    final = Path(a.out)
    single = final.suffix == ".mcap"
    out = Path(tempfile.mkdtemp()) / "bag" if single else final
    if out.exists():
        shutil.rmtree(out)
    empty = lambda dt: np.zeros(0, dtype=dt)
    with Writer2(out, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        ca = w.add_connection("/audio", "audio_common_msgs/msg/AudioStamped", typestore=ts)
        co = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        events = []
        m = read_map(d)
        if m is not None:
            res, origin, gw, gh, data = m
            cm = w.add_connection("/map", "nav_msgs/msg/OccupancyGrid", typestore=ts)
            P, Pt = T["geometry_msgs/msg/Pose"], T["geometry_msgs/msg/Point"]
            info = T["nav_msgs/msg/MapMetaData"](
                map_load_time=stamp(ts, T0), resolution=res, width=gw, height=gh,
                origin=P(position=Pt(x=origin[0], y=origin[1], z=0.0), orientation=quat(ts, 0.0)))
            grid = T["nav_msgs/msg/OccupancyGrid"](header=header(ts, T0, "odom"), info=info, data=data)
            events.append((T0, cm, ts.serialize_cdr(grid, "nav_msgs/msg/OccupancyGrid")))
        buf = fs // 10
        for k in range(0, len(audio), buf):
            blk = audio[k:k + buf]
            ns = T0 + round((k + len(blk)) / fs * 1e9)
            info = T["audio_common_msgs/msg/AudioInfo"](format=8, channels=ch, rate=fs, chunk=len(blk))
            data = T["audio_common_msgs/msg/AudioData"](
                float32_data=empty(np.float32), int32_data=empty(np.int32),
                int16_data=blk.astype(np.int16).reshape(-1), int8_data=empty(np.int8),
                uint8_data=empty(np.uint8))
            msg = T["audio_common_msgs/msg/AudioStamped"](
                header=header(ts, ns, "mic"), audio=T["audio_common_msgs/msg/Audio"](info=info, audio_data=data))
            events.append((ns + 2_000_000, ca, ts.serialize_cdr(msg, "audio_common_msgs/msg/AudioStamped")))
        V = T["geometry_msgs/msg/Vector3"]
        for j in range(int(total * 20) + 1):
            t = j / 20
            x, y, th = pose_at(t)
            ns = T0 + round(t * 1e9)
            P = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0), orientation=quat(ts, th))
            msg = T["nav_msgs/msg/Odometry"](
                header=header(ts, ns, "odom"), child_frame_id="base_link",
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=P, covariance=np.zeros(36)),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=V(x=0.0, y=0.0, z=0.0), angular=V(x=0.0, y=0.0, z=0.0)), covariance=np.zeros(36)))
            events.append((ns + 1_000_000, co, ts.serialize_cdr(msg, "nav_msgs/msg/Odometry")))
        for ns, c, data in sorted(events, key=lambda e: e[0]):
            w.write(c, ns, data)
    if single:
        from make_bag_fixtures import recompress
        recompress(next(out.glob("*.mcap")), final)
        shutil.rmtree(out.parent)
        size = final.stat().st_size
    else:
        size = sum(f.stat().st_size for f in out.iterdir())
    print(f"{final}: {total:.1f} s, {size} bytes")


if __name__ == "__main__":
    main()
