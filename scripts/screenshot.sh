#!/usr/bin/env bash
# Runs the real editor window under Xvfb, drives it with xdotool like a user (select a
# handle, show its weight, the dual graph, hover for the weights tooltip), and saves a
# screenshot. Usage: scripts/screenshot.sh [OUT.png] [cage]
# (default: assets/screenshot.png). With `cage`: the cage tool instead — a cage from
# the lizard's outline, solved, two vertices dragged, the last one's coordinate as a
# heat map, the locality plots (assets/screenshot-cage.png).
# Needs what scripts/setup.sh installs.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-assets/screenshot.png}
mode=${2:-handles}
cargo build --release --quiet
display=:97
Xvfb "$display" -screen 0 1280x820x24 >/dev/null 2>&1 &
xvfb=$!
# Wait for the server's socket before anything connects to it.
for _ in $(seq 100); do
  [ -S "/tmp/.X11-unix/X${display#:}" ] && break
  sleep 0.1
done
export DISPLAY=$display WGPU_BACKEND=vulkan
XDG_RUNTIME_DIR=$(mktemp -d)
export XDG_RUNTIME_DIR
./target/release/c2warp >/dev/null 2>&1 &
app=$!
trap 'kill $app $xvfb 2>/dev/null || true' EXIT
window=$(xdotool search --sync --name C2Warp | head -1)
sleep 3
# No window manager: give the window the keyboard focus, and click an empty spot.
xdotool windowfocus "$window" || true
xdotool mousemove 1180 60 click 1
sleep 0.5
# Drags from one screen point to another in eight steps, as a hand would.
drag() {
  xdotool mousemove "$1" "$2" mousedown 1
  sleep 0.3
  for i in 1 2 3 4 5 6 7 8; do
    xdotool mousemove $(($1 + ($3 - $1) * i / 8)) $(($2 + ($4 - $2) * i / 8))
    sleep 0.1
  done
  xdotool mouseup 1
  sleep 0.6
}
if [ "$mode" = cage ]; then
  # The cage tool (K), then its panel's "Cage from outline", the heat map (H), Solve
  # (Enter) and a wait for the solve.
  xdotool key k
  sleep 1
  xdotool mousemove 67 341 click 1
  sleep 1
  xdotool key h
  sleep 0.5
  xdotool key Return
  # The solve takes a few seconds in a release build.
  sleep "${SOLVE_SECONDS:-12}"
  # The cage's vertex by the tail's end, then the one by the front leg.
  drag 926 565 968 478
  drag 735 263 796 194
  xdotool mousemove 1100 760
  sleep 1.5
  import -window root "$out"
  echo "screenshot: $out"
  exit 0
fi
for key in n n h g; do
  xdotool key "$key"
  sleep 0.5
done
# Hover the lizard's body for the weights tooltip.
xdotool mousemove 555 325
sleep 0.5
xdotool mousemove 560 330
sleep 1.5
import -window root "$out"
echo "screenshot: $out"
