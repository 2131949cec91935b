#!/usr/bin/env python3
"""Weighted total variation of a set of piecewise-linear coordinates on a mesh.

    E(W) = sum over triangles s, cage vertices i of  phi_i^s * A_s * |grad_s w_i|

with phi_i^s = tau(D_i^s), D_i^s the distance field averaged over the triangle's
three corners and then normalised, tau(x) = x^2 by default (the paper's eqs.
10-12, 16; LBC's "square" weighting).

The distances are taken from a plain-text matrix (one row per mesh vertex, one
column per cage vertex), e.g. the geodesics the authors' DataSetup computed, so
that two weight matrices can be scored under the same phi.

Normalisation of D (the two codes differ here):
  global  D / max over all vertices and cage vertices (the authors' code,
          DataSetup.cpp compute_solver_data: grad_weights_ /= geodesic_distance_.maxCoeff())
  column  D_i / max over vertices of D_i (the paper's eq. 12; c2warp's reading)

Frame: the objective scales with length (A |grad w| ~ length). It is printed in
the mesh file's own coordinates and in the authors' DataSetup frame (vertices
centred on their mean, the farthest at distance 250: DataSetup::normalize_sample_points),
which is the frame of the objective the driver prints.

Weights: a plain-text matrix (rows = mesh vertices, columns = cage vertices), or
the JSON that `c2warp weights` writes (per-vertex [cage index, weight] pairs).

Usage:
  lbc_objective.py MESH.obj DIST.txt WEIGHTS(.txt|.json) [WEIGHTS2 ...] [--tau square]
                   [--json]
"""
import argparse
import json
import sys

import numpy as np


def read_obj(path):
    vs, fs = [], []
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                vs.append((float(p[1]), float(p[2])))
            elif p[0] == "f":
                idx = [int(t.split("/")[0]) for t in p[1:]]
                if len(idx) != 3:
                    raise SystemExit(f"{path}: only triangles are supported")
                fs.append([i - 1 if i > 0 else len(vs) + i for i in idx])
    return np.array(vs, dtype=float), np.array(fs, dtype=np.int64)


def read_weights(path, n_vertices, n_cage):
    if path.endswith(".json"):
        with open(path) as f:
            d = json.load(f)
        rows = d["weights"]
        if len(rows) != n_vertices:
            raise SystemExit(
                f"{path}: {len(rows)} weight rows for {n_vertices} mesh vertices "
                "(vertices inserted or dropped?)")
        W = np.zeros((n_vertices, n_cage))
        for v, row in enumerate(rows):
            for c, w in row:
                W[v, c] = w
        meta = {k: d[k] for k in ("iterations", "converged", "objective") if k in d}
        meta["nodes_vertex"] = [n.get("vertex") for n in d.get("nodes", [])]
        return W, meta
    W = np.loadtxt(path, ndmin=2)
    if W.shape != (n_vertices, n_cage):
        raise SystemExit(f"{path}: shape {W.shape}, expected {(n_vertices, n_cage)}")
    return W, {}


TAU = {
    "square": lambda x: x * x,
    "linear": lambda x: x,
    "constant": lambda x: np.ones_like(x),
    "sqrt": lambda x: np.sqrt(np.maximum(x, 0.0)),
}


def tv_terms(V, F, W):
    """A_s * |grad_s w_i| for every triangle s and column i (T x n)."""
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    cross = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]  # 2 * signed area
    # the constant gradient g solves [e1; e2] g = [w1 - w0; w2 - w0]
    w0, w1, w2 = W[F[:, 0]], W[F[:, 1]], W[F[:, 2]]
    d1, d2 = w1 - w0, w2 - w0  # T x n
    inv = 1.0 / cross
    gx = (e2[:, 1, None] * d1 - e1[:, 1, None] * d2) * inv[:, None]
    gy = (-e2[:, 0, None] * d1 + e1[:, 0, None] * d2) * inv[:, None]
    area = 0.5 * np.abs(cross)
    return area[:, None] * np.hypot(gx, gy), area


def phi_of(F, D, norm, tau):
    Dc = (D[F[:, 0]] + D[F[:, 1]] + D[F[:, 2]]) / 3.0
    if norm == "global":
        Dc = Dc / D.max()
    else:
        Dc = Dc / D.max(axis=0)[None, :]
    return TAU[tau](Dc)


def their_frame_scale(V):
    c = V.mean(axis=0)
    return 250.0 / max(1e-10, np.sqrt(((V - c) ** 2).sum(axis=1)).max())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("dist")
    ap.add_argument("weights", nargs="+")
    ap.add_argument("--tau", default="square", choices=sorted(TAU))
    ap.add_argument("--cage-index", help="text file: mesh vertex of each cage vertex (for the reproduction check)")
    ap.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    a = ap.parse_args()

    V, F = read_obj(a.mesh)
    D = np.loadtxt(a.dist, ndmin=2)
    if D.shape[0] != len(V):
        raise SystemExit(f"{a.dist}: {D.shape[0]} rows for {len(V)} mesh vertices")
    n = D.shape[1]
    cage = None
    if a.cage_index:
        ci = np.loadtxt(a.cage_index, dtype=np.int64, ndmin=1)
        cage = V[ci]
    s = their_frame_scale(V)
    phis = {norm: phi_of(F, D, norm, a.tau) for norm in ("global", "column")}

    out = {"mesh": a.mesh, "vertices": len(V), "triangles": len(F), "cage_vertices": n,
           "their_frame_scale": s, "results": []}
    for path in a.weights:
        W, meta = read_weights(path, len(V), n)
        terms, _ = tv_terms(V, F, W)
        r = {"weights": path}
        for norm, phi in phis.items():
            e = float((phi * terms).sum())
            r[f"objective_{norm}_file_frame"] = e
            r[f"objective_{norm}_their_frame"] = e * s
        r["unweighted_tv_file_frame"] = float(terms.sum())
        r["partition_of_unity_max_err"] = float(np.abs(W.sum(axis=1) - 1.0).max())
        r["min_weight"] = float(W.min())
        if cage is not None:
            r["reproduction_max_err"] = float(np.abs(W @ cage - V).max())
        r["nonzeros_per_vertex_gt_1e-3/n"] = float((W > 1e-3 / n).sum(axis=1).mean())
        r.update({k: v for k, v in meta.items() if k != "nodes_vertex"})
        if cage is not None and meta.get("nodes_vertex"):
            if list(meta["nodes_vertex"]) != [int(x) for x in ci]:
                r["warning"] = "the JSON's cage vertices are not the mesh vertices of cage_vertex_index"
        out["results"].append(r)

    if a.json:
        print(json.dumps(out, indent=1))
        return
    print(f"{a.mesh}: {len(V)} vertices, {len(F)} triangles, {n} cage vertices; tau={a.tau}")
    print(f"{'weights':40s} {'E global/their':>16s} {'E column/their':>16s} {'E global/file':>16s} "
          f"{'PU err':>9s} {'min w':>10s} {'repro err':>9s}")
    for r in out["results"]:
        print(f"{r['weights'][-40:]:40s} {r['objective_global_their_frame']:16.8g} "
              f"{r['objective_column_their_frame']:16.8g} {r['objective_global_file_frame']:16.8g} "
              f"{r['partition_of_unity_max_err']:9.2e} {r['min_weight']:10.2e} "
              f"{r.get('reproduction_max_err', float('nan')):9.2e}")


if __name__ == "__main__":
    main()
