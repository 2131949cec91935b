#!/usr/bin/env bash
# Runs the LBC authors' solver (via lbc-peer-driver, built by build.sh) and
# c2warp's (the snapshot $P/c2warp-base) side by side on the paper's four 2-D
# cages, on the same mesh (the authors' UI triangulation, sized to the paper's
# Table 2 vertex counts), and scores both weight sets under the authors'
# geodesic distances with lbc_objective.py. Prints a table; everything it writes
# goes to $P/run/<model>/.
#
#   LBC_PEER_DIR  (default /tmp/lbc-peer)   THREADS (default 2)   REPEAT (default 3)
#   MODELS        (default "woody cactus Gil_Gecko LBClogo")
# Timings: the minimum over REPEAT runs of each side, the two sides' runs alternating
# (the machine may be shared; OpenMP barriers suffer badly when another process takes
# a core).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
P="${LBC_PEER_DIR:-/tmp/lbc-peer}"
THREADS="${THREADS:-2}"
REPEAT="${REPEAT:-3}"
MODELS="${MODELS:-woody cactus Gil_Gecko LBClogo}"
C2W="${C2WARP:-$P/c2warp-base}"
DRV="$P/lbc-peer-driver"
[ -x "$DRV" ] || { echo "run build.sh first ($DRV missing)" >&2; exit 1; }
[ -x "$C2W" ] || { echo "$C2W missing (build.sh snapshots target/release/c2warp)" >&2; exit 1; }
export OMP_NUM_THREADS="$THREADS" RAYON_NUM_THREADS="$THREADS"

declare -A TARGET=([woody]=6069 [cactus]=12862 [Gil_Gecko]=11554 [LBClogo]=4479)  # paper, Table 2 |V|

for m in $MODELS; do
  d="$P/run/$m"; mkdir -p "$d"
  cage="$P/src/data/2D/$m-control-edgeset.obj"
  echo "== $m (load: $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  # their solver: first run finds the UI cell count for the paper's |V|
  "$DRV" "$cage" "$d" --target-vertices "${TARGET[$m]}" > "$d/their_1.txt" 2> "$d/their_1.log"
  cp "$d/their_stats.json" "$d/their_stats_1.json"
  cells=$(python3 -c "import json,sys;print(json.load(open(sys.argv[1]))['cells_param'])" "$d/their_stats.json")
  # ours: `weights` (wall time of the whole command) and `bench` (stage times); the
  # two solvers' runs alternate, so that a slow spell of the machine falls on both
  ours() {
    /usr/bin/time -f "%e" -o "$d/ours_weights_time_$1.txt" \
      "$C2W" weights --mesh "$d/mesh.obj" --rig "$d/rig.json" -o "$d/ours.json" 2> "$d/ours_weights_$1.log"
    "$C2W" bench --mesh "$d/mesh.obj" --rig "$d/rig.json" --method lbc > "$d/ours_bench_$1.json" 2> "$d/ours_bench_$1.log"
  }
  ours 1
  for r in $(seq 2 "$REPEAT"); do
    "$DRV" "$cage" "$d" --cells "$cells" > "$d/their_$r.txt" 2> "$d/their_$r.log"
    cp "$d/their_stats.json" "$d/their_stats_$r.json"
    ours "$r"
  done
  python3 "$HERE/lbc_objective.py" "$d/mesh.obj" "$d/their_geodesics.txt" "$d/their_weights.txt" "$d/ours.json" \
    --cage-index "$d/cage_vertex_index.txt" --json > "$d/objectives.json"
done

python3 - "$P" "$REPEAT" $MODELS <<'EOF'
import json, sys, statistics
P, R, models = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
rows = []
for m in models:
    d = f"{P}/run/{m}"
    th = [json.load(open(f"{d}/their_stats_{r}.json")) for r in range(1, R + 1)]
    best = min(th, key=lambda s: s["total_s"])
    ow = [float(open(f"{d}/ours_weights_time_{r}.txt").read().split()[-1]) for r in range(1, R + 1)]
    ob = [json.load(open(f"{d}/ours_bench_{r}.json")) for r in range(1, R + 1)]
    # (our factorisation runs beside the geodesics: its time is within theirs)
    solve = lambda b: (b["geodesics_ms"] + b["admm_ms"] + b["projection_ms"]) / 1000
    bb = min(ob, key=solve)
    obj = json.load(open(f"{d}/objectives.json"))
    t, o = obj["results"]
    rows.append((m, best, min(ow), bb, solve(bb), t, o, [s["total_s"] for s in th], ow))

print(f"their solver: OMP_NUM_THREADS={rows[0][1]['threads']}, min of {R} runs; ours: min of {R} runs")
print()
print(f"{'model':10s} {'|V|':>6s} {'|T|':>6s} {'n':>3s} {'cells':>6s} | {'setup':>6s} {'geod':>6s} {'fact':>6s} "
      f"{'iters':>7s} {'total':>7s} {'#it':>5s} | {'geod':>6s} {'fact':>6s} {'admm':>6s} {'solve':>6s} {'#it':>4s} "
      f"{'weights':>7s} | {'ratio':>6s}")
print(f"{'':10s} {'':6s} {'':6s} {'':3s} {'':6s} | {'theirs (s)':^44s} | {'ours, bench stages and weights wall (s)':^47s} |")
for m, b, ow, bb, sv, t, o, tt, oww in rows:
    print(f"{m:10s} {b['vertices']:6d} {b['triangles']:6d} {b['cage_vertices']:3d} {b['cells_param']:6d} | "
          f"{b['setup_s']:6.2f} {b['geodesics_s']:6.2f} {b['factorisation_s']:6.2f} {b['iterations_s']:7.2f} "
          f"{b['total_s']:7.2f} {b['iterations']:5d} | {bb['geodesics_ms']/1000:6.2f} {bb['factorisation_ms']/1000:6.2f} "
          f"{bb['admm_ms']/1000:6.2f} {sv:6.2f} {bb['admm_iterations']:4d} {ow:7.2f} | {b['total_s']/ow:6.1f}x")
print()
print("objective sum phi A |grad w| under THEIR geodesics, in their frame (farthest vertex at 250);")
print("phi = (D/max)^2 with max global (their code) or per cage vertex (paper eq. 12, ours)")
print(f"{'model':10s} | {'theirs glob':>12s} {'ours glob':>12s} {'ours/theirs':>11s} | {'theirs col':>12s} {'ours col':>12s} "
      f"{'ours/theirs':>11s} | {'their min w':>11s} {'their conv':>10s}")
for m, b, ow, bb, sv, t, o, tt, oww in rows:
    tg, og = t["objective_global_their_frame"], o["objective_global_their_frame"]
    tc, oc = t["objective_column_their_frame"], o["objective_column_their_frame"]
    print(f"{m:10s} | {tg:12.6g} {og:12.6g} {og/tg:11.4f} | {tc:12.6g} {oc:12.6g} {oc/tc:11.4f} | "
          f"{t['min_weight']:11.2e} {str(b['converged']):>10s}")
print()
print("all runs (s): " + "; ".join(f"{r[0]} theirs {', '.join(f'{x:.2f}' for x in r[7])} ours {', '.join(f'{x:.2f}' for x in r[8])}" for r in rows))
EOF
