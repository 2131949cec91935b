#!/usr/bin/env bash
# Installs what building and testing C2Warp needs beyond a Rust toolchain, on Debian 12
# (bookworm) or a derivative: a C compiler for crates that build C, a software Vulkan
# driver (Mesa lavapipe) so GPU rendering works without a GPU, and Xvfb, xdotool and
# ImageMagick to run and screenshot the editor window without a display.
# Safe to run again: packages already installed are skipped.
set -euo pipefail

packages=(
  gcc libc6-dev
  mesa-vulkan-drivers libvulkan1 libegl1 libegl-mesa0
  xvfb libxcursor1 libxi6 libxrandr2 libxkbcommon-x11-0 xdotool imagemagick
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  sudo="sudo"
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
