#!/usr/bin/env python3
"""The bag benchmark of BENCHMARKS.md, by hand:

    pip install rosbags==0.11.9 mcap==1.6.0
    python3 scripts/bench_bag.py make /tmp/big10.bag 10     # a 10-minute ROS 1 bag
    rosbags-convert --src /tmp/big10.bag --dst /tmp/big10_ros2 --dst-storage mcap
    rosbags-convert --src /tmp/big10.bag --dst /tmp/big10_db3 --dst-storage sqlite3
    python3 scripts/bench_bag.py zstd /tmp/big10_ros2/big10_ros2.mcap /tmp/big10_zstd.mcap
    # compressed as `ros2 bag record --compression-format zstd` does:
    mkdir /tmp/mz /tmp/dz && zstd -3 /tmp/big10_ros2/big10_ros2.mcap -o /tmp/mz/big10.mcap.zstd
    zstd -3 /tmp/big10_db3/big10_db3.db3 -o /tmp/dz/big10.db3.zstd      # --compression-mode file
    python3 scripts/bench_bag.py message /tmp/big10.bag /tmp/big10_msgz  # --compression-mode message
    /usr/bin/time -f "%e s %M KB" iasm bag /tmp/big10.bag      # and the two MCAP stores
    python3 scripts/bench_bag.py read /tmp/big10.bag            # the rosbags baseline

`make`: 6 channels at 48 kHz of white noise (S16LE AudioData in 0.1-s buffers, AudioInfo
beside them), odometry at 50 Hz of a robot that stands 5 s and drives 0.4 m in 3 s, over
and over. `zstd`: the messages rewritten in 64-kB zstd chunks by Foxglove's MCAP writer.
`read`: rosbags iterating every raw message, decoding none. `message`: the ROS 1 bag
rewritten as a ROS 2 MCAP bag whose messages are each a zstd frame (rosbags' writer).
"""

import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from make_bag_fixtures import header, quat, recompress, typestore  # noqa: E402
from rosbags.rosbag1 import Writer  # noqa: E402

T0 = 1_700_000_000_000_000_000
FS, CH, FRAMES = 48000, 6, 4800
STILL, DRIVE = 5.0, 3.0


def pose_at(t):
    k = int(t // (STILL + DRIVE))
    u = min(max((t - k * (STILL + DRIVE) - STILL) / DRIVE, 0.0), 1.0)
    return 0.4 * (k + u), 0.0, 0.0


def make(out, minutes):
    ts = typestore()
    T = ts.types
    out = Path(out)
    out.unlink(missing_ok=True)
    rng = np.random.default_rng(1)
    noise = (rng.standard_normal((FRAMES * 50, CH)) * 3000).astype("<i2")
    V = T["geometry_msgs/msg/Vector3"]
    with Writer(out) as w:
        ci = w.add_connection("/audio/audio_info", "audio_common_msgs/msg/AudioInfo", typestore=ts, latching=1)
        ca = w.add_connection("/audio/audio", "audio_common_msgs/msg/AudioData", typestore=ts)
        co = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        info = T["audio_common_msgs/msg/AudioInfo"](channels=CH, sample_rate=FS, sample_format="S16LE", bitrate=FS * CH * 16, coding_format="wave")
        w.write(ci, T0, ts.serialize_ros1(info, "audio_common_msgs/msg/AudioInfo"))
        j = 0
        for k in range(int(minutes * 60 * FS) // FRAMES):
            end = (k + 1) * FRAMES / FS
            while j / 50 <= end:
                t = j / 50
                x, y, yaw = pose_at(t)
                ns = T0 + round(t * 1e9)
                P = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0), orientation=quat(ts, yaw))
                msg = T["nav_msgs/msg/Odometry"](
                    header=header(ts, ns, "odom"), child_frame_id="base_link",
                    pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=P, covariance=np.zeros(36)),
                    twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=V(x=0.0, y=0.0, z=0.0), angular=V(x=0.0, y=0.0, z=0.0)), covariance=np.zeros(36)))
                w.write(co, ns + 1_000_000, ts.serialize_ros1(msg, "nav_msgs/msg/Odometry"))
                j += 1
            block = noise[(k % 50) * FRAMES:(k % 50 + 1) * FRAMES]
            data = T["audio_common_msgs/msg/AudioData"](data=np.frombuffer(block.tobytes(), dtype=np.uint8))
            w.write(ca, T0 + round(end * 1e9) + 3_000_000, ts.serialize_ros1(data, "audio_common_msgs/msg/AudioData"))
    print(out, out.stat().st_size, "bytes")


def read(path):
    from rosbags.highlevel import AnyReader

    t = time.perf_counter()
    n = 0
    with AnyReader([Path(path)]) as r:
        for _, _, raw in r.messages():
            n += len(raw)
    print(f"{time.perf_counter() - t:.2f} s in the loop, {n} bytes")


def message(src, dst):
    import shutil

    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import CompressionFormat, CompressionMode
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores

    shutil.rmtree(dst, ignore_errors=True)
    ts = typestore(Stores.ROS2_JAZZY)
    with AnyReader([Path(src)], default_typestore=typestore(Stores.ROS1_NOETIC)) as r:
        w = Writer2(Path(dst), version=9)
        w.set_compression(CompressionMode.MESSAGE, CompressionFormat.ZSTD)
        with w:
            conns = {c.id: w.add_connection(c.topic, c.msgtype, typestore=ts) for c in r.connections}
            for c, t, raw in r.messages():
                w.write(conns[c.id], t, ts.serialize_cdr(r.deserialize(raw, c.msgtype), c.msgtype))


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "make":
        make(sys.argv[2], float(sys.argv[3]))
    elif cmd == "zstd":
        recompress(Path(sys.argv[2]), Path(sys.argv[3]))
    elif cmd == "message":
        message(sys.argv[2], sys.argv[3])
    elif cmd == "read":
        read(sys.argv[2])
    else:
        sys.exit(__doc__)
