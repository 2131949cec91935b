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

With `--check`, the BBW result is also checked, so that a time is never compared
against a solve that stopped early: the raw weights must interpolate the handles
(identity rows at the handle vertices) and stay within [0, 1] up to `--tolerance`;
every row must have a positive sum, so that the normalised weights (libigl's solve
leaves out the partition-of-unity constraint, as the BBW paper suggests, and the raw
rows sum to one only approximately: their largest deviation is reported) are finite
and sum to one; and a second solve allowed ten times the active-set iterations must
agree with the first (a solve that converged within `--max-iter` repeats itself; one
cut off by the limit goes on and moves). libigl reports an
unconverged active set only on stderr, and the pip wheel compiles that message out,
so this re-solve is the only sign of one. The report gets a `bbw_check` entry and the
script exits with status 1 if any check fails.

    pip install libigl pillow
    python3 scripts/bbw_compare.py --c2warp target/release/c2warp \
        --image assets/lizard.png --density 31000 --handles 10 --check
"""

import argparse
import json
import statistics
import subprocess
import sys
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
    """The command's stdout; its stderr passes through to ours."""
    return subprocess.run(command, check=True, stdout=subprocess.PIPE, text=True).stdout


def check_bbw(vertices: np.ndarray, faces: np.ndarray, b: np.ndarray, bc: np.ndarray,
              w: np.ndarray, tolerance: float, max_iter: int) -> dict:
    """Checks raw BBW weights `w` (before any normalisation) and re-solves to confirm
    the active set had converged."""
    at_handles = float(np.abs(w[b] - bc).max())
    low, high = float(w.min()), float(w.max())
    sums = w.sum(axis=1)
    unity = float(np.abs(sums - 1.0).max())
    normalised = w / sums[:, None] if sums.min() > 0.0 else None
    normalised_unity = (float(np.abs(normalised.sum(axis=1) - 1.0).max())
                        if normalised is not None and np.isfinite(normalised).all()
                        else float("inf"))

    clock = time.perf_counter()
    longer = igl.bbw(vertices, faces, b, bc, max_iter=10 * max_iter)
    resolve_s = time.perf_counter() - clock
    resolve_diff = float(np.abs(longer - w).max())

    checks = {
        "interpolates_handles": at_handles <= tolerance,
        "bounded": low >= -tolerance and high <= 1.0 + tolerance,
        "partition_of_unity_normalised": normalised_unity <= tolerance,
        "converged": resolve_diff <= tolerance,
    }
    return {
        "tolerance": tolerance,
        "max_error_at_handles": at_handles,
        "min_weight": low,
        "max_weight": high,
        "max_unity_error_raw": unity,
        "min_row_sum_raw": float(sums.min()),
        "max_unity_error_normalised": normalised_unity,
        "resolve_max_iter": 10 * max_iter,
        "resolve_s": round(resolve_s, 3),
        "resolve_max_difference": resolve_diff,
        "checks": checks,
        "passed": all(checks.values()),
    }


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
    parser.add_argument("--max-iter", type=int, default=100,
                        help="BBW active-set iterations (libigl's default: 100)")
    parser.add_argument("--check", action="store_true",
                        help="check BBW's weights and re-solve to confirm convergence")
    parser.add_argument("--tolerance", type=float, default=1e-6,
                        help="tolerance of the --check tests")
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
            raw = igl.bbw(vertices, faces, b, bc, max_iter=args.max_iter)
            bbw_s.append(time.perf_counter() - clock)
        check = (check_bbw(vertices, faces, b, bc, raw, args.tolerance, args.max_iter)
                 if args.check else None)
        w = raw / raw.sum(axis=1, keepdims=True)

        c2 = statistics.median(build_ms) / 1e3
        bbw = statistics.median(bbw_s)
        report = {
            "mesh": {"vertices": len(vertices), "triangles": len(faces)},
            "handles": len(b),
            "virtual_handles": builds[0].get("virtual_handles"),
            "c2_build_ms": [round(t, 2) for t in build_ms],
            "bbw_s": [round(t, 3) for t in bbw_s],
            "bbw_at_handles": float(np.min(w[b, np.arange(len(b))])),
            "bbw_min_weight": float(w.min()),
            "ratio": round(bbw / c2),
        }
        if check is not None:
            report["bbw_check"] = check
        print(json.dumps(report, indent=1))
        if check is not None and not check["passed"]:
            sys.exit(1)


if __name__ == "__main__":
    main()
