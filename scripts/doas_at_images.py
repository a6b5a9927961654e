#!/usr/bin/env python3
"""Are the sources the front end misses heard at their images in the walls?

For drawn scenes (`iasm scenes generate`), each simulated (`iasm simulate`) and localised
(`iasm ssl --dataset D --out doas_<method>_<scene>.csv`), this sorts every stop-source pair
and every DoA by the plan's geometry:

- a pair is **heard directly** when a DoA lies within 5 degrees of the source's bearing;
  otherwise **heard at an image** when a DoA lies within 5 degrees of one of the source's
  first- or second-order images in the plan's walls that reaches the stop (the image
  model's specular paths, each leg clear of the other walls) and not within 5 degrees of
  another source's bearing;
- a DoA is **direct** (within 5 degrees of a source's bearing), else a **first-** or
  **second-order image** of a source, else **none**.

Images cover much of the circle (a source has four to eight first-order images and tens
of second-order ones), so a DoA can lie near one by chance. The same counts with every
DoA turned by a fixed angle (the rows keep their spacing, the geometry loses its hold)
give that chance level, averaged over eight angles.

    iasm scenes generate --count 16 --seed 0 --out ROOT/scenes
    for f in ROOT/scenes/*.toml; do iasm simulate $f --out ROOT/data/$(basename $f .toml); done
    for each scene and method:
        iasm ssl --dataset ROOT/data/S --method M --num N --out ROOT/doas_M_S.csv
    python3 scripts/doas_at_images.py ROOT mvdr gcc-phat

(N is the scene's `[expect] num`.) Heights are left out: a floor's or ceiling's image
has the source's azimuth. Pure Python, no dependency.
"""

import csv
import glob
import math
import os
import sys
import tomllib

TOL = math.radians(5.0)
NEAR_M = 3.0
CHANCE_TURNS_DEG = [23, 41, 67, 97, 131, 163, 199, 241]


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def params(p, q, a, b):
    """Where the lines p-q and a-b meet, as the fractions (t along p-q, u along a-b); None
    when they are parallel."""
    r = (q[0] - p[0], q[1] - p[1])
    s = (b[0] - a[0], b[1] - a[1])
    den = r[0] * s[1] - r[1] * s[0]
    if abs(den) < 1e-12:
        return None
    t = ((a[0] - p[0]) * s[1] - (a[1] - p[1]) * s[0]) / den
    u = ((a[0] - p[0]) * r[1] - (a[1] - p[1]) * r[0]) / den
    return t, u


def crosses(p, q, a, b):
    """Whether segment p-q crosses segment a-b (not at p or q)."""
    tu = params(p, q, a, b)
    return tu is not None and 1e-6 < tu[0] < 1 - 1e-6 and -1e-9 <= tu[1] <= 1 + 1e-9


def clear(p, q, walls, skip=()):
    return not any(crosses(p, q, a, b) for i, (a, b) in enumerate(walls) if i not in skip)


def mirror(x, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    t = ((x[0] - a[0]) * dx + (x[1] - a[1]) * dy) / (dx * dx + dy * dy)
    return (2 * (a[0] + t * dx) - x[0], 2 * (a[1] + t * dy) - x[1])


def meets(p, q, a, b):
    """Where segment p-q meets wall a-b, or None."""
    tu = params(p, q, a, b)
    if tu is None or not (0 < tu[0] < 1 and 0 <= tu[1] <= 1):
        return None
    return (p[0] + tu[0] * (q[0] - p[0]), p[1] + tu[0] * (q[1] - p[1]))


def images(p, s, walls):
    """Bearings from p of the images of s that reach p, with their order (1 or 2)."""
    out = []
    for i, (a, b) in enumerate(walls):
        s1 = mirror(s, a, b)
        q = meets(p, s1, a, b)
        if q and clear(p, q, walls, (i,)) and clear(q, s, walls, (i,)):
            out.append((math.atan2(s1[1] - p[1], s1[0] - p[0]), 1))
        for j, (c, d) in enumerate(walls):
            if j == i:
                continue
            s2 = mirror(s1, c, d)
            q2 = meets(p, s2, c, d)
            q1 = q2 and meets(q2, s1, a, b)
            if q1 and clear(p, q2, walls, (j,)) and clear(q2, q1, walls, (i, j)) and clear(q1, s, walls, (i,)):
                out.append((math.atan2(s2[1] - p[1], s2[0] - p[0]), 2))
    return out


def scene_stops(root, name):
    """Per stop: (position, each source's bearing, whether it sees each, images, DoA rows)."""
    sc = tomllib.load(open(f"{root}/scenes/{name}.toml", "rb"))
    plan = sc["room"]["plan"]
    walls = [(tuple(plan[i]), tuple(plan[(i + 1) % len(plan)])) for i in range(len(plan))]
    srcs = [tuple(x["pos"][:2]) for x in sc["sources"] if not x.get("on_robot")]
    with open(f"{root}/data/{name}/pose/poses.csv") as f:
        poses = [(float(r["x"]), float(r["y"]), math.radians(float(r["theta_deg"]))) for r in csv.DictReader(f)]
    stops = []
    for x, y, th in poses:
        p = (x, y)
        stops.append(
            dict(
                p=p,
                theta=th,
                bearing=[math.atan2(s[1] - y, s[0] - x) for s in srcs],
                dist=[math.hypot(s[0] - x, s[1] - y) for s in srcs],
                sees=[clear(p, s, walls) for s in srcs],
                images=[images(p, s, walls) for s in srcs],
            )
        )
    return stops


def count(stops, rows, turn):
    c = dict(near=0, direct=0, image1=0, image2=0, hidden=0, hidden_image1=0, hidden_image2=0)
    c.update(doas=0, d_direct=0, d_image1=0, d_image2=0)
    for st, row in zip(stops, rows):
        doas = [wrap(st["theta"] + math.radians(a + turn)) for a in row]
        n = len(st["bearing"])
        for k in range(n):
            near = lambda b: any(abs(wrap(d - b)) <= TOL for d in doas)
            others = [st["bearing"][j] for j in range(n) if j != k]

            def at_image(order):
                return any(
                    abs(wrap(d - b)) <= TOL and all(abs(wrap(d - o)) > TOL for o in others)
                    for d in doas
                    for b, o_ in st["images"][k]
                    if o_ == order
                )

            if not st["sees"][k]:
                c["hidden"] += 1
                first = at_image(1)
                c["hidden_image1"] += first
                c["hidden_image2"] += not first and at_image(2)
            if st["dist"][k] > NEAR_M:
                continue
            c["near"] += 1
            if near(st["bearing"][k]):
                c["direct"] += 1
            elif at_image(1):
                c["image1"] += 1
            elif at_image(2):
                c["image2"] += 1
        for d in doas:
            c["doas"] += 1
            of_order = lambda o: any(abs(wrap(d - b)) <= TOL for im in st["images"] for b, oo in im if oo == o)
            if any(abs(wrap(d - b)) <= TOL for b in st["bearing"]):
                c["d_direct"] += 1
            elif of_order(1):
                c["d_image1"] += 1
            elif of_order(2):
                c["d_image2"] += 1
    return c


def main():
    root, methods = sys.argv[1], sys.argv[2:]
    names = sorted(os.path.basename(f)[:-5] for f in glob.glob(f"{root}/scenes/*.toml"))
    geometry = {n: scene_stops(root, n) for n in names}
    print(f"{len(names)} scenes; pairs within {NEAR_M:.0f} m; a hit within 5 degrees; chance: DoAs turned by {CHANCE_TURNS_DEG} degrees")
    for m in methods:
        real, chance = None, []
        for turn in [0] + CHANCE_TURNS_DEG:
            tot = {}
            for n in names:
                with open(f"{root}/doas_{m}_{n}.csv") as f:
                    rows = [[float(v) for v in r if v.strip()] for r in csv.reader(f)]
                for k, v in count(geometry[n], rows, turn).items():
                    tot[k] = tot.get(k, 0) + v
            if turn == 0:
                real = tot
            else:
                chance.append(tot)

        for t in [real] + chance:
            t["missed"] = t["near"] - t["direct"]
            t["not_direct"] = t["doas"] - t["d_direct"]

        def share(t, k, of):
            return t[k] / max(t[of], 1)

        def line(k, of):
            ch = sum(share(t, k, of) for t in chance) / len(chance)
            return f"{share(real, k, of):.2f} (chance {ch:.2f})"

        print(f"\n{m}: {real['near']} near pairs, {real['doas']} DoAs, {real['hidden']} pairs the walls hide")
        print(f"  near pairs heard directly             {line('direct', 'near')}")
        print(f"  of those missed, at a 1st-order image {line('image1', 'missed')}")
        print(f"  of those missed, at a 2nd-order image {line('image2', 'missed')}")
        print(f"  pairs the walls hide, 1st-order image {line('hidden_image1', 'hidden')}")
        print(f"  or else at a 2nd-order image          {line('hidden_image2', 'hidden')}")
        print(f"  DoAs at a source's bearing            {line('d_direct', 'doas')}")
        print(f"  of the others, at a 1st-order image   {line('d_image1', 'not_direct')}")
        print(f"  of the others, at a 2nd-order image   {line('d_image2', 'not_direct')}")


if __name__ == "__main__":
    main()
