#!/usr/bin/env bash
# Runs the real editor window under Xvfb, drives it with xdotool like a user (select a
# handle, show its weight, the dual graph, hover for the weights tooltip), and saves a
# screenshot. Usage: scripts/screenshot.sh [OUT.png]   (default: assets/screenshot.png)
# Needs what scripts/setup.sh installs.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-assets/screenshot.png}
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
xdotool mousemove 1150 760 click 1
sleep 0.5
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
