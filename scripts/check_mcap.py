#!/usr/bin/env python3
"""Hand-run check of an `--mcap` file against its map JSON, with two decoders that share
nothing with iasm: Foxglove's `mcap-ros2-support` (decoding by the schemas the file
embeds) and `rosbags` (decoding by ROS 2 Humble's and Jazzy's own message definitions,
which checks that the embedded schemas are those types' real layouts).

    python3 -m venv /tmp/v && /tmp/v/bin/pip install mcap-ros2-support rosbags
    iasm map --dataset D --method mvdr --out map.json --mcap map.mcap
    /tmp/v/bin/python scripts/check_mcap.py map.mcap map.json

Prints one line per message and exits 1 on any disagreement.
"""
import json
import math
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.typesys import Stores, get_typestore


def yaw(q):
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def check(path, json_path):
    want = json.load(open(json_path))
    sources = want["sources"]
    stores = [get_typestore(Stores.ROS2_HUMBLE), get_typestore(Stores.ROS2_JAZZY)]
    bad = []
    last = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages():
            # The same bytes by the distributions' own definitions.
            for ts in stores:
                other = ts.deserialize_cdr(message.data, schema.name)
                if schema.name.endswith("MarkerArray"):
                    a = [(m.ns, m.id, m.type, m.pose.position.x, m.text) for m in msg.markers]
                    b = [(m.ns, m.id, m.type, m.pose.position.x, m.text) for m in other.markers]
                    if a != b:
                        bad.append(f"{channel.topic}: rosbags reads other markers")
            if msg.header.frame_id if hasattr(msg, "header") else False:
                if msg.header.frame_id != "map":
                    bad.append(f"{channel.topic}: frame {msg.header.frame_id}")
            last[channel.topic] = msg
            print(f"{message.log_time / 1e9:8.1f} s  {channel.topic:22} {schema.name}")
    poses = last["/iasm/source_poses"].poses
    if len(poses) != len(sources):
        bad.append(f"{len(poses)} source poses, {len(sources)} in the JSON")
    for p, s in zip(poses, sources):
        if abs(p.position.x - s["x"]) > 1e-9 or abs(p.position.y - s["y"]) > 1e-9:
            bad.append(f"source pose {p.position} is not {s['x']}, {s['y']}")
    markers = last["/iasm/sources"].markers
    for k, s in enumerate(sources):
        e = [m for m in markers if m.ns == "ellipses" and m.id == k]
        label = [m for m in markers if m.ns == "labels" and m.id == k]
        if not label or label[0].text != f"s{k + 1}: {s['observations']} DoAs":
            bad.append(f"source {k}: label {label[0].text if label else None}")
        if e:
            a, b, phi = (e[0].scale.x / 4) ** 2, (e[0].scale.y / 4) ** 2, yaw(e[0].pose.orientation)
            c, sn = math.cos(phi), math.sin(phi)
            cov = [[a * c * c + b * sn * sn, (a - b) * c * sn], [(a - b) * c * sn, a * sn * sn + b * c * c]]
            err = max(abs(cov[i][j] - s["covariance"][i][j]) for i in range(2) for j in range(2))
            if err > 1e-9:
                bad.append(f"source {k}: ellipse covariance off by {err}")
    grid = last["/map"]
    print(f"sources {len(sources)}, rays at {len(last['/iasm/doas'].markers)} stops, "
          f"path {len(last['/iasm/path'].poses)} stops, grid {grid.info.width} x {grid.info.height} "
          f"at {grid.info.resolution:.3f} m: decoded by mcap-ros2-support and by rosbags "
          f"(Humble, Jazzy) alike")
    for b in bad:
        print("MISMATCH", b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(check(sys.argv[1], sys.argv[2]))
