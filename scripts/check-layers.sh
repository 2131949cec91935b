#!/usr/bin/env bash
# The numeric core knows no UI, GPU or dialog crates, and no images; meshing and
# drawing know no UI; fail if a dependency tree says otherwise (see ARCHITECTURE.md).
set -euo pipefail
status=0
for crate in geometry weights-core arap lbc mls animation depth; do
  tree=$(cargo tree -p "$crate" -e normal --prefix none)
  if echo "$tree" | grep -Eq '^(egui|eframe|wgpu|rfd|winit|image) '; then
    echo "layering: $crate depends on: $(echo "$tree" | grep -Eo '^(egui|eframe|wgpu|rfd|winit|image) ' | sort -u | tr '\n' ' ')"
    status=1
  fi
done
for crate in mesh render layers project; do
  tree=$(cargo tree -p "$crate" -e normal --prefix none)
  if echo "$tree" | grep -Eq '^(egui|eframe|rfd|winit|weights-core) '; then
    echo "layering: $crate depends on: $(echo "$tree" | grep -Eo '^(egui|eframe|rfd|winit|weights-core) ' | sort -u | tr '\n' ' ')"
    status=1
  fi
done
# The shared pipeline serves the command line too: no UI crates.
tree=$(cargo tree -p pipeline -e normal --prefix none)
if echo "$tree" | grep -Eq '^(egui|eframe|rfd|winit|editor) '; then
  echo "layering: pipeline depends on: $(echo "$tree" | grep -Eo '^(egui|eframe|rfd|winit|editor) ' | sort -u | tr '\n' ' ')"
  status=1
fi
[ $status -eq 0 ] && echo "layering: ok"
exit $status
