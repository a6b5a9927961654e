#!/usr/bin/env python3
"""Which sources does the front end hear? Recall of drawn scenes by kind, height, array and
source count.

A stop heard a source when one of its DoAs lies within 5 degrees of the bearing to it (the
DoA score's tolerance). For each group this prints the share of stop-source pairs heard,
the same for pairs nearer than 2.5 m, and, per method, the share of sources heard from at
least 3 and 5 stops (the mapper's quorums) and from none. Same layout as
`scripts/doas_at_images.py`:

    iasm scenes generate --count 24 --seed 0 --out ROOT/scenes   # from the repository's top
    for f in ROOT/scenes/*.toml; do iasm simulate $f --out ROOT/data/$(basename $f .toml); done
    for each scene S and method M:
        iasm ssl --dataset ROOT/data/S --method M --num N --out ROOT/doas_M_S.csv
    python3 scripts/recall_by_kind.py ROOT mvdr gcc-phat

(N is the scene's `[expect] num`.) Pure Python, no dependency.
"""

import csv
import glob
import math
import os
import sys
import tomllib
from collections import defaultdict

TOL_DEG = 5.0
NEAR_M = 2.5
HIGH_M = 1.9


def kind(source):
    if "wav" in source or source.get("signal") == "speech_shaped":
        return "talker"
    return {"voiced": "hum", "pink_noise": "vent (pink)", "white_noise": "vent (white)"}.get(
        source.get("signal", ""), source.get("signal", "?")
    )


def main(root, methods):
    pairs = defaultdict(lambda: [0, 0, 0, 0])  # heard, pairs, near heard, near pairs
    per_source = defaultdict(list)
    for path in sorted(glob.glob(os.path.join(root, "scenes", "*.toml"))):
        name = os.path.basename(path)[:-5]
        with open(path, "rb") as f:
            scene = tomllib.load(f)
        with open(os.path.join(root, "data", name, "pose", "poses.csv")) as f:
            poses = [tuple(map(float, r)) for r in list(csv.reader(f))[1:]]
        array = scene["array"]["preset"]
        count = len(scene["sources"])
        for m in methods:
            with open(os.path.join(root, f"doas_{m}_{name}.csv")) as f:
                rows = [[float(x) for x in r if x] for r in csv.reader(f)]
            for s in scene["sources"]:
                x, y, z = s["pos"]
                heard = near = near_heard = 0
                for (px, py, theta), row in zip(poses, rows):
                    b = math.degrees(math.atan2(y - py, x - px)) - theta
                    hit = any(abs((a - b + 180) % 360 - 180) <= TOL_DEG for a in row)
                    heard += hit
                    if math.hypot(x - px, y - py) < NEAR_M:
                        near += 1
                        near_heard += hit
                groups = [
                    "all",
                    kind(s),
                    "high (>= 1.9 m)" if z >= HIGH_M else "low",
                    array,
                    "6-8 sources" if count >= 6 else f"{count} sources",
                ]
                for g in groups:
                    p = pairs[(g, m)]
                    p[0] += heard
                    p[1] += len(rows)
                    p[2] += near_heard
                    p[3] += near
                per_source[m].append(heard)
    print(f"{'group':<18} {'method':<9} {'recall':>6} {'near':>6} {'near pairs':>10}")
    for (g, m), (h, n, nh, nn) in sorted(pairs.items()):
        print(f"{g:<18} {m:<9} {h / n:>6.2f} {nh / max(nn, 1):>6.2f} {nn:>10}")
    for m, heard in per_source.items():
        n = len(heard)
        print(
            f"{m}: of {n} sources, heard from >= 3 stops {sum(h >= 3 for h in heard) / n:.2f}, "
            f">= 5 {sum(h >= 5 for h in heard) / n:.2f}, none {sum(h == 0 for h in heard) / n:.2f}"
        )


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
