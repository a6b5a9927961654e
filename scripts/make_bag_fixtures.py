#!/usr/bin/env python3
"""Writes the ROS 1 bags of fixtures/bags/ with rosbags (an implementation of the format
independent of ours), so that the `bag` crate's reader is tested against bags it did not
write.

    pip install rosbags==0.11.9 mcap==1.6.0
    python3 scripts/make_bag_fixtures.py fixtures/bags

Both bags record the same robot run of 3.0 s: still at (1.0, 2.0), heading 0, until
1.2 s; driving along x at 0.25 m/s while turning to 30 degrees until 1.8 s; still at
(1.15, 2.0), heading 30 degrees, until 3.0 s. Times are counted from T0 (a real ROS
epoch). The audio is 4 channels at 8 kHz in messages of 800 frames, published when a
buffer fills (stamp = time of its last sample + 1/fs, received 3 ms later); channel c of
frame i holds the integer pattern (37 i + 1000 c) mod 4096 - 2048, so that every sample
can be checked.

- `run_lz4.bag`: LZ4 chunks; audio_common_msgs/AudioDataStamped on /audio (S16LE),
  AudioInfo on /audio_info, nav_msgs/Odometry on /odom at 20 Hz.
- `run_bz2.bag`: BZ2 chunks; unstamped audio_common_msgs/AudioData on /mic/audio (S32LE,
  the pattern times 65536), AudioInfo on /mic/audio_info, Odometry on /odom at 20 Hz and
  geometry_msgs/PoseStamped on /robot_pose at 5 Hz (the same poses, shifted by +10 m in
  x: another frame), so that a reader has two pose topics to choose from.

- `run_ros2/`: a ROS 2 bag (rosbags' MCAP storage, CDR messages, ROS 2 Jazzy's types) of
  the bz2 bag's topics, but audio_common_msgs/AudioDataStamped in S16LE on /mic/audio
  (the ROS 2 port of audio_common has the same three messages).

- The bz2 and ROS 2 bags also hold tf2_msgs/TFMessage: on /tf, map -> odom at 5 Hz (the
  odometry frame at (5.0, -1.0), turned by 90 degrees, in the map) and odom -> base_link
  at 20 Hz (the odometry's poses); on /tf_static, base_link -> laser (0.2 m ahead).

- `run_split/`: run_lz4.bag cut in two as `rosbag record --split` cuts a run: the
  messages recorded before 1.5 s in run_split_0.bag (with the one AudioInfo), the rest in
  run_split_1.bag, each file with its own connection records.

- `run_db3/`: the same ROS 2 bag in rosbag2's SQLite storage (`.db3`, Humble's default).

- `run_db3_zstd/`: run_db3 compressed as `ros2 bag record --compression-mode file
  --compression-format zstd` writes it: the whole `.db3` file as `run_db3_zstd.db3.zstd`,
  metadata.yaml naming the mode and format.

- `run_mcap_zstd_msg/`: run_ros2 compressed message by message (`--compression-mode
  message`): each message's CDR bytes a zstd frame of their own, in an MCAP file.

- `run_mcap_zstd_file/`: run_ros2 compressed file by file, its `.mcap.zstd` rewritten as
  two zstd frames (the file's first 100000 bytes, then the rest), as a compressor may
  write a large file: a reader must go on past the first frame.

- `run_zstd.mcap`: run_ros2's messages but /odom's and /robot_pose's, rewritten by
  Foxglove's own MCAP writer (the `mcap` package) in zstd-compressed chunks of 64 kB, as
  `ros2 bag record` compresses them by default: a bag whose poses are only in /tf.

- `run_audiostamped.mcap`: the ROS 2 `audio_common` of `audio_capturer_node` (its own
  audio_common_msgs: AudioStamped = header + Audio {AudioInfo {format, channels, rate,
  chunk}, AudioData {float32[], int32[], int16[], int8[], uint8[]}}), the samples as
  int16 (paInt16, its default) on /audio/in, with /odom; zstd chunks. No map.

The others also hold a nav_msgs/OccupancyGrid on /map (latched, frame "map"): 40 x 30 cells of
0.1 m from (-1.0, -0.5); the border cells occupied (100), the 5 x 4 cells from cell
(10, 10) unknown (-1), cell (20, 15) at 50 (neither), the rest free (0). The lz4 bag's
poses are odometry (frame "odom"), the bz2 bag's /robot_pose is in "map".
"""

import math
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

T0 = 1_700_000_000_000_000_000  # ns
FS = 8000
CH = 4
FRAMES = 800
DURATION = 3.0

AUDIO_MSGS = {
    "audio_common_msgs/msg/AudioData": "uint8[] data\n",
    "audio_common_msgs/msg/AudioDataStamped": "std_msgs/Header header\naudio_common_msgs/AudioData audio\n",
    "audio_common_msgs/msg/AudioInfo": "uint8 channels\nuint32 sample_rate\nstring sample_format\nuint32 bitrate\nstring coding_format\n",
}


def typestore(store=Stores.ROS1_NOETIC):
    ts = get_typestore(store)
    types = {}
    for name, text in AUDIO_MSGS.items():
        types.update(get_types_from_msg(text, name))
    if "tf2_msgs/msg/TFMessage" not in ts.types:
        # ROS 1 Noetic's store has no tf2_msgs.
        types.update(get_types_from_msg("geometry_msgs/TransformStamped[] transforms\n", "tf2_msgs/msg/TFMessage"))
    ts.register(types)
    return ts


def pose_at(t):
    """(x, y, yaw) of the robot at t s."""
    if t <= 1.2:
        return 1.0, 2.0, 0.0
    if t >= 1.8:
        return 1.15, 2.0, math.radians(30.0)
    s = (t - 1.2) / 0.6
    return 1.0 + 0.15 * s, 2.0, math.radians(30.0) * s


def pattern():
    i = np.arange(int(FS * DURATION))[:, None]
    c = np.arange(CH)[None, :]
    return ((37 * i + 1000 * c) % 4096 - 2048).astype(np.int64)


def stamp(ts, ns):
    return ts.types["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def header(ts, ns, frame):
    H = ts.types["std_msgs/msg/Header"]
    if "seq" in H.__dataclass_fields__:
        return H(seq=0, stamp=stamp(ts, ns), frame_id=frame)
    return H(stamp=stamp(ts, ns), frame_id=frame)


def quat(ts, yaw):
    Q = ts.types["geometry_msgs/msg/Quaternion"]
    return Q(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def pose_msg(ts, t, dx=0.0):
    x, y, yaw = pose_at(t)
    P = ts.types["geometry_msgs/msg/Pose"]
    Pt = ts.types["geometry_msgs/msg/Point"]
    return P(position=Pt(x=x + dx, y=y, z=0.0), orientation=quat(ts, yaw))


def odometry(ts, t):
    ns = T0 + round(t * 1e9)
    T = ts.types
    pwc = T["geometry_msgs/msg/PoseWithCovariance"](pose=pose_msg(ts, t), covariance=np.zeros(36))
    V = T["geometry_msgs/msg/Vector3"]
    tw = T["geometry_msgs/msg/Twist"](linear=V(x=0.0, y=0.0, z=0.0), angular=V(x=0.0, y=0.0, z=0.0))
    twc = T["geometry_msgs/msg/TwistWithCovariance"](twist=tw, covariance=np.zeros(36))
    return ns, T["nav_msgs/msg/Odometry"](header=header(ts, ns, "odom"), child_frame_id="base_link", pose=pwc, twist=twc)


def write(path, compression, stamped, fmt, topic, info_topic, pose_stamped, ros2=False, storage=StoragePlugin.MCAP,
          ros2_compression=None):
    ts = typestore(Stores.ROS2_JAZZY if ros2 else Stores.ROS1_NOETIC)
    T = ts.types
    ser = ts.serialize_cdr if ros2 else ts.serialize_ros1
    if ros2:
        import shutil
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)
    samples = pattern()
    if fmt == "S32LE":
        samples = samples * 65536
    dtype = {"S16LE": "<i2", "S32LE": "<i4"}[fmt]
    if ros2:
        w = Writer2(path, version=9, storage_plugin=storage)
        if ros2_compression is not None:
            w.set_compression(ros2_compression, CompressionFormat.ZSTD)
    else:
        w = Writer(path)
        w.set_compression(compression)
    with w:
        audio_type = "audio_common_msgs/msg/AudioDataStamped" if stamped else "audio_common_msgs/msg/AudioData"
        latched = {} if ros2 else {"latching": 1}
        c_info = w.add_connection(info_topic, "audio_common_msgs/msg/AudioInfo", typestore=ts, **latched)
        c_audio = w.add_connection(topic, audio_type, typestore=ts)
        c_odom = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        c_pose = w.add_connection("/robot_pose", "geometry_msgs/msg/PoseStamped", typestore=ts) if pose_stamped else None
        c_map = w.add_connection("/map", "nav_msgs/msg/OccupancyGrid", typestore=ts, **latched)
        c_tf = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts) if pose_stamped else None
        c_tfs = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts, **latched) if pose_stamped else None
        bits = 8 * np.dtype(dtype).itemsize
        info = T["audio_common_msgs/msg/AudioInfo"](
            channels=CH, sample_rate=FS, sample_format=fmt, bitrate=FS * CH * bits, coding_format="wave")
        w.write(c_info, T0, ser(info, "audio_common_msgs/msg/AudioInfo"))
        w.write(c_map, T0, ser(grid(ts, T0), "nav_msgs/msg/OccupancyGrid"))
        if c_tfs is not None:
            w.write(c_tfs, T0, ser(tf_msg(ts, [(T0, "base_link", "laser", 0.2, 0.0, 0.0)]), "tf2_msgs/msg/TFMessage"))
        events = []
        for k in range(int(FS * DURATION) // FRAMES):
            block = samples[k * FRAMES:(k + 1) * FRAMES].astype(dtype).tobytes()
            ns = T0 + round((k + 1) * FRAMES / FS * 1e9)
            data = T["audio_common_msgs/msg/AudioData"](data=np.frombuffer(block, dtype=np.uint8))
            msg = T[audio_type](header=header(ts, ns, "mic"), audio=data) if stamped else data
            events.append((ns + 3_000_000, c_audio, ser(msg, audio_type)))
        for k in range(int(DURATION * 20) + 1):
            ns, msg = odometry(ts, k / 20)
            events.append((ns + 1_000_000, c_odom, ser(msg, "nav_msgs/msg/Odometry")))
        if c_tf is not None:
            for k in range(int(DURATION * 20) + 1):
                t = k / 20
                ns = T0 + round(t * 1e9)
                x, y, yaw = pose_at(t)
                trs = [(ns, "odom", "base_link", x, y, yaw)]
                if k % 4 == 0:
                    trs.append((ns, "map", "odom", 5.0, -1.0, math.radians(90.0)))
                events.append((ns + 1_500_000, c_tf, ser(tf_msg(ts, trs), "tf2_msgs/msg/TFMessage")))
        if c_pose is not None:
            for k in range(int(DURATION * 5) + 1):
                t = k / 5
                ns = T0 + round(t * 1e9)
                msg = T["geometry_msgs/msg/PoseStamped"](header=header(ts, ns, "map"), pose=pose_msg(ts, t, dx=10.0))
                events.append((ns + 2_000_000, c_pose, ser(msg, "geometry_msgs/msg/PoseStamped")))
        for ns, conn, data in sorted(events, key=lambda e: e[0]):
            w.write(conn, ns, data)


def grid(ts, ns):
    T = ts.types
    w, h = 40, 30
    data = np.zeros((h, w), dtype=np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    data[10:14, 10:15] = -1
    data[15, 20] = 50
    P = T["geometry_msgs/msg/Pose"]
    Pt = T["geometry_msgs/msg/Point"]
    info = T["nav_msgs/msg/MapMetaData"](
        map_load_time=stamp(ts, ns), resolution=0.1, width=w, height=h,
        origin=P(position=Pt(x=-1.0, y=-0.5, z=0.0), orientation=quat(ts, 0.0)))
    return T["nav_msgs/msg/OccupancyGrid"](header=header(ts, ns, "map"), info=info, data=data.reshape(-1))


def tf_msg(ts, transforms):
    """A TFMessage of (ns, parent, child, x, y, yaw) transforms."""
    T = ts.types
    V = T["geometry_msgs/msg/Vector3"]
    out = []
    for ns, parent, child, x, y, yaw in transforms:
        tr = T["geometry_msgs/msg/Transform"](translation=V(x=x, y=y, z=0.0), rotation=quat(ts, yaw))
        out.append(T["geometry_msgs/msg/TransformStamped"](header=header(ts, ns, parent), child_frame_id=child, transform=tr))
    return T["tf2_msgs/msg/TFMessage"](transforms=out)


def recompress(src, dst, drop=()):
    """The messages of the MCAP file `src` but those of the topics `drop`, written to `dst`
    in zstd chunks of 64 kB."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType
    from mcap.writer import Writer as McapWriter

    dst.unlink(missing_ok=True)
    with open(src, "rb") as f, open(dst, "wb") as g:
        w = McapWriter(g, chunk_size=64 * 1024, compression=CompressionType.ZSTD)
        w.start(profile="ros2", library="make_bag_fixtures.py")
        schemas, channels = {}, {}
        for schema, channel, message in make_reader(f).iter_messages():
            if channel.topic in drop:
                continue
            if schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(channel.topic, channel.message_encoding, schemas[schema.id])
            w.add_message(channels[channel.id], message.log_time, message.data, message.publish_time)
        w.finish()


# The ROS 2 audio_common's messages (audio_capturer_node's).
AUDIO_STAMPED_DEFS = {
    "audio_common_msgs/msg/AudioInfo": "int32 format\nint32 channels\nint32 rate\nint32 chunk\n",
    "audio_common_msgs/msg/AudioData": "float32[] float32_data\nint32[] int32_data\nint16[] int16_data\nint8[] int8_data\nuint8[] uint8_data\n",
    "audio_common_msgs/msg/Audio": "audio_common_msgs/AudioInfo info\naudio_common_msgs/AudioData audio_data\n",
    "audio_common_msgs/msg/AudioStamped": "std_msgs/Header header\naudio_common_msgs/Audio audio\n",
}


def write_audiostamped(dst):
    """`run_audiostamped.mcap` (module docs), through a temporary ROS 2 bag."""
    import shutil
    import tempfile

    ts = get_typestore(Stores.ROS2_JAZZY)
    defs = {
        "audio_common_msgs/msg/AudioInfo": "int32 format\nint32 channels\nint32 rate\nint32 chunk\n",
        "audio_common_msgs/msg/AudioData": "float32[] float32_data\nint32[] int32_data\nint16[] int16_data\nint8[] int8_data\nuint8[] uint8_data\n",
        "audio_common_msgs/msg/Audio": "audio_common_msgs/AudioInfo info\naudio_common_msgs/AudioData audio_data\n",
        "audio_common_msgs/msg/AudioStamped": "std_msgs/Header header\naudio_common_msgs/Audio audio\n",
    }
    types = {}
    for name, text in defs.items():
        types.update(get_types_from_msg(text, name))
    ts.register(types)
    T = ts.types
    tmp = Path(tempfile.mkdtemp()) / "bag"
    samples = pattern().astype("<i2")
    empty = lambda dt: np.zeros(0, dtype=dt)
    with Writer2(tmp, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        ca = w.add_connection("/audio/in", "audio_common_msgs/msg/AudioStamped", typestore=ts)
        co = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        events = []
        for k in range(int(FS * DURATION) // FRAMES):
            ns = T0 + round((k + 1) * FRAMES / FS * 1e9)
            info = T["audio_common_msgs/msg/AudioInfo"](format=8, channels=CH, rate=FS, chunk=FRAMES)
            data = T["audio_common_msgs/msg/AudioData"](
                float32_data=empty(np.float32), int32_data=empty(np.int32),
                int16_data=samples[k * FRAMES:(k + 1) * FRAMES].reshape(-1), int8_data=empty(np.int8),
                uint8_data=empty(np.uint8))
            audio = T["audio_common_msgs/msg/Audio"](info=info, audio_data=data)
            msg = T["audio_common_msgs/msg/AudioStamped"](header=header(ts, ns, "mic"), audio=audio)
            events.append((ns + 3_000_000, ca, ts.serialize_cdr(msg, "audio_common_msgs/msg/AudioStamped")))
        for k in range(int(DURATION * 20) + 1):
            ns, msg = odometry(ts, k / 20)
            events.append((ns + 1_000_000, co, ts.serialize_cdr(msg, "nav_msgs/msg/Odometry")))
        for ns, conn, data in sorted(events, key=lambda e: e[0]):
            w.write(conn, ns, data)
    recompress(next(tmp.glob("*.mcap")), dst)
    shutil.rmtree(tmp.parent)


def split(src, dst, at_ns):
    """The ROS 1 bag `src` cut at `at_ns` into `dst`/`dst.name`_0.bag and _1.bag."""
    import shutil
    from rosbags.rosbag1 import Reader

    shutil.rmtree(dst, ignore_errors=True)
    dst.mkdir(parents=True)
    with Reader(src) as r:
        msgs = list(r.messages())
        conns = r.connections
        writers = []
        for k in range(2):
            w = Writer(dst / f"{dst.name}_{k}.bag")
            w.set_compression(Writer.CompressionFormat.LZ4)
            w.open()
            ids = {c.id: w.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data, md5sum=c.digest,
                                          callerid=c.ext.callerid, latching=c.ext.latching) for c in conns}
            writers.append((w, ids))
        for c, t, data in msgs:
            w, ids = writers[0 if t < at_ns else 1]
            w.write(ids[c.id], t, data)
        for w, _ in writers:
            w.close()


def two_frames(path, at):
    """Rewrites the zstd-compressed file `path` as two frames, split at byte `at` of its
    content."""
    try:
        from compression import zstd
    except ImportError:
        from backports import zstd
    data = zstd.decompress(path.read_bytes())
    path.write_bytes(zstd.compress(data[:at]) + zstd.compress(data[at:]))


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "fixtures/bags")
    out.mkdir(parents=True, exist_ok=True)
    write(out / "run_lz4.bag", Writer.CompressionFormat.LZ4, True, "S16LE", "/audio", "/audio_info", False)
    split(out / "run_lz4.bag", out / "run_split", T0 + 1_500_000_000)
    write(out / "run_bz2.bag", Writer.CompressionFormat.BZ2, False, "S32LE", "/mic/audio", "/mic/audio_info", True)
    write(out / "run_ros2", None, True, "S16LE", "/mic/audio", "/mic/audio_info", True, ros2=True)
    write(out / "run_db3", None, True, "S16LE", "/mic/audio", "/mic/audio_info", True, ros2=True,
          storage=StoragePlugin.SQLITE3)
    write(out / "run_db3_zstd", None, True, "S16LE", "/mic/audio", "/mic/audio_info", True, ros2=True,
          storage=StoragePlugin.SQLITE3, ros2_compression=CompressionMode.FILE)
    write(out / "run_mcap_zstd_msg", None, True, "S16LE", "/mic/audio", "/mic/audio_info", True, ros2=True,
          ros2_compression=CompressionMode.MESSAGE)
    write(out / "run_mcap_zstd_file", None, True, "S16LE", "/mic/audio", "/mic/audio_info", True, ros2=True,
          ros2_compression=CompressionMode.FILE)
    two_frames(out / "run_mcap_zstd_file" / "run_mcap_zstd_file.mcap.zstd", 100000)
    recompress(out / "run_ros2" / "run_ros2.mcap", out / "run_zstd.mcap", drop=("/odom", "/robot_pose"))
    write_audiostamped(out / "run_audiostamped.mcap")
    for p in sorted(list(out.glob("*.bag")) + list(out.glob("*.mcap")) + list(out.glob("run_*/*"))):
        print(p, p.stat().st_size, "bytes")


if __name__ == "__main__":
    main()
