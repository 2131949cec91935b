#!/usr/bin/env python3
"""Times the C² rig build of `c2warp` against libigl's bounded biharmonic weights
(BBW, Jacobson et al. 2011) on the same mesh and the same point handles.

The mesh is the one `c2warp` builds from the picture at the given density (written
with `c2warp deform` under a rig whose handles do not move, so the output is the rest
mesh); the handles are N point handles spread over the picture's opaque pixels by
farthest-point sampling (or clustered 12 px apart near the middle, as in the insertion
benchmark); BBW gets each handle's mesh vertex (from `c2warp weights`)
as a boundary condition with the identity as values, and solves to libigl's default
convergence. The C² time is the median full build reported by `c2warp bench`
(distances, Voronoi cells, virtual handles, weights).

    pip install libigl pillow
    python3 scripts/bbw_compare.py --c2warp target/release/c2warp \
        --image assets/lizard.png --density 31000 --handles 10
"""

import argparse
import json
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import igl
import numpy as np
from PIL import Image


def spread_handles(image: Path, count: int) -> list[list[float]]:
    """`count` pixel centres of opaque pixels, by farthest-point sampling."""
    alpha = np.asarray(Image.open(image).convert("RGBA"))[:, :, 3]
    ys, xs = np.nonzero(alpha > 200)
    points = np.stack([xs + 0.5, ys + 0.5], axis=1)
    chosen = [len(points) // 2]
    nearest = np.linalg.norm(points - points[chosen[0]], axis=1)
    while len(chosen) < count:
        far = int(np.argmax(nearest))
        chosen.append(far)
        nearest = np.minimum(nearest, np.linalg.norm(points - points[far], axis=1))
    return [points[i].tolist() for i in chosen]


def clustered_handles(image: Path, count: int) -> list[list[float]]:
    """`count` opaque pixel centres at least 12 px apart, nearest the centroid first."""
    alpha = np.asarray(Image.open(image).convert("RGBA"))[:, :, 3]
    ys, xs = np.nonzero(alpha > 200)
    points = np.stack([xs + 0.5, ys + 0.5], axis=1)
    order = np.argsort(np.linalg.norm(points - points.mean(axis=0), axis=1), kind="stable")
    chosen: list[np.ndarray] = []
    for i in order:
        if all(np.linalg.norm(points[i] - c) >= 12.0 for c in chosen):
            chosen.append(points[i])
            if len(chosen) == count:
                break
    return [c.tolist() for c in chosen]


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if parts and parts[0] == "v":
            vertices.append([float(parts[1]), float(parts[2])])
        elif parts and parts[0] == "f":
            faces.append([int(p.split("/")[0]) - 1 for p in parts[1:4]])
    return np.array(vertices, dtype=np.float64), np.array(faces, dtype=np.int64)


def run(command: list[str]) -> str:
    return subprocess.run(command, check=True, capture_output=True, text=True).stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--c2warp", default="target/release/c2warp")
    parser.add_argument("--image", default="assets/lizard.png")
    parser.add_argument("--density", type=int, default=31000)
    parser.add_argument("--handles", type=int, default=10)
    parser.add_argument("--layout", choices=["spread", "clustered"], default="spread",
                        help="handles over the extremities, or 12 px apart near the middle")
    parser.add_argument("--runs", type=int, default=5, help="c2warp bench runs")
    parser.add_argument("--bbw-runs", type=int, default=3)
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        rig = tmp / "rig.json"
        rig.write_text(json.dumps({
            "version": 1,
            "handles": [{"type": "point", "rest": p}
                        for p in (spread_handles if args.layout == "spread"
                                  else clustered_handles)(Path(args.image), args.handles)],
        }))
        common = ["--image", args.image, "--density", str(args.density), "--rig", str(rig)]
        run([args.c2warp, "deform", *common, "-o", str(tmp / "mesh.obj")])
        weights = json.loads(run([args.c2warp, "weights", *common, "-o", "-"]))
        vertices, faces = read_obj(tmp / "mesh.obj")
        handle_vertices = [n["vertex"] for n in weights["nodes"] if n["kind"] == "point"]

        builds = []
        for _ in range(args.runs):
            report = json.loads(run([args.c2warp, "bench", *common, "--positions", "1"]))
            builds.append(report)
        build_ms = [r["build_ms"]["total"] for r in builds]

        b = np.array(handle_vertices, dtype=np.int64)
        bc = np.eye(len(b), dtype=np.float64)
        bbw_s = []
        for _ in range(args.bbw_runs):
            clock = time.perf_counter()
            w = igl.bbw(vertices, faces, b, bc)
            bbw_s.append(time.perf_counter() - clock)
        w = w / w.sum(axis=1, keepdims=True)

        c2 = statistics.median(build_ms) / 1e3
        bbw = statistics.median(bbw_s)
        print(json.dumps({
            "mesh": {"vertices": len(vertices), "triangles": len(faces)},
            "handles": len(b),
            "virtual_handles": builds[0].get("virtual_handles"),
            "c2_build_ms": [round(t, 2) for t in build_ms],
            "bbw_s": [round(t, 3) for t in bbw_s],
            "bbw_at_handles": float(np.min(w[b, np.arange(len(b))])),
            "bbw_min_weight": float(w.min()),
            "ratio": round(bbw / c2),
        }, indent=1))


if __name__ == "__main__":
    main()
