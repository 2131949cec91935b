#!/usr/bin/env python3
"""A long-limbed gingerbread figure meshed by Shewchuk's Triangle (the `triangle`
package: `pip install triangle numpy`), as an outside tool meshes it, for
`c2warp bench --mesh`: head, body, long thin arms and legs, about N vertices.

    python3 scripts/gingerbread_mesh.py 100000 g100k.obj [spread.json]

With a third argument it also writes a rig file of 10 point handles spread over the
figure by farthest-point sampling (the first at the top of the head).
"""
import json
import sys

import numpy as np
import triangle


def capsule(p, a, b, r):
    a, b = np.array(a), np.array(b)
    pa, ba = p - a, b - a
    h = np.clip((pa @ ba) / (ba @ ba), 0, 1)
    return np.linalg.norm(pa - np.outer(h, ba), axis=-1) - r


def sdf(p):
    d = np.linalg.norm(p - np.array([0, -0.95]), axis=1) - 0.42  # head
    body = np.linalg.norm((p - np.array([0, 0.1])) / np.array([0.55, 0.75]), axis=1)
    d = np.minimum(d, body * 0.55 - 0.55)
    for s in (-1, 1):
        d = np.minimum(d, capsule(p, [0, -0.3], [s * 2.1, -0.75], 0.16))  # arms
        d = np.minimum(d, capsule(p, [s * 0.2, 0.6], [s * 1.1, 2.4], 0.18))  # legs
    return d


def main():
    n, name = int(sys.argv[1]), sys.argv[2]
    # The outline: the figure is star-shaped about its centre; 4,000 rays.
    ts = np.linspace(0, 3.2, 3201)
    outline = []
    for a in np.linspace(0, 2 * np.pi, 4000, endpoint=False):
        d = np.array([np.cos(a), np.sin(a)])
        inside = sdf(np.outer(ts, d)) < 0
        outline.append(ts[np.nonzero(inside)[0].max()] * d)
    pts = np.array(outline) * 300 + np.array([800, 900])
    seg = np.array([[i, (i + 1) % len(pts)] for i in range(len(pts))])
    x, y = pts[:, 0], pts[:, 1]
    area = 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    t = triangle.triangulate({"vertices": pts, "segments": seg}, "pqa%fQ" % (area / (n * 1.25)))
    v, f = t["vertices"], t["triangles"]
    with open(name, "w") as out:
        for p in v:
            out.write("v %.4f %.4f 0\n" % (p[0], p[1]))
        for tri in f:
            out.write("f %d %d %d\n" % (tri[0] + 1, tri[1] + 1, tri[2] + 1))
    print(name, len(v), "vertices", len(f), "triangles", file=sys.stderr)
    if len(sys.argv) > 3:
        chosen = [int(np.argmin(v[:, 1]))]
        nearest = np.linalg.norm(v - v[chosen[0]], axis=1)
        for _ in range(9):
            j = int(np.argmax(nearest))
            chosen.append(j)
            nearest = np.minimum(nearest, np.linalg.norm(v - v[j], axis=1))
        handles = [
            {"type": "point", "rest": [round(float(v[i, 0]), 4), round(float(v[i, 1]), 4)]}
            for i in chosen
        ]
        with open(sys.argv[3], "w") as out:
            json.dump({"version": 1, "handles": handles}, out, indent=1)


if __name__ == "__main__":
    main()
