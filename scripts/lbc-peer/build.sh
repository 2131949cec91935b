#!/usr/bin/env bash
# Builds the LBC authors' solver (github.com/bldeng/LBC) headless, with the
# lbc-peer driver, into $LBC_PEER_DIR (default /tmp/lbc-peer). Nothing is written
# into the c2warp source tree.
#
#   LBC_PEER_DIR   build/output folder            (default /tmp/lbc-peer)
#   LBC_MIRROR     bare git dir of bldeng/LBC     (default /work/.mirror/bldeng+LBC/repo;
#                  if absent, https://github.com/bldeng/LBC is cloned)
#   C2WARP         c2warp binary to snapshot as $LBC_PEER_DIR/c2warp-base if that
#                  file does not exist yet (default: target/release/c2warp)
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
P="${LBC_PEER_DIR:-/tmp/lbc-peer}"
MIRROR="${LBC_MIRROR:-/work/.mirror/bldeng+LBC/repo}"
LBC_COMMIT=85624882dfc7a02d2d3145e7e37e0c727f0a1e9c   # bldeng/LBC HEAD, "Adds definition of macro TRIVOID"
TRIANGLE_SDIST=triangle-20200424.tar.gz                # PyPI 'triangle' sdist, bundles Triangle 1.6 (c/)
TRIANGLE_SHA256=828fa58fa09218a785f249a7618d58d10260767d52841a024328c94e5eefe3e3  # of c/triangle.c
mkdir -p "$P/dl" "$P/build"

# c2warp snapshot (the binary in target/ may be rebuilt while the benchmark runs)
if [ ! -x "$P/c2warp-base" ]; then
  cp "${C2WARP:-$ROOT/target/release/c2warp}" "$P/c2warp-base"
fi

# Eigen (Debian's; the authors' README says the same: apt-get install libeigen3-dev)
if [ ! -f /usr/include/eigen3/Eigen/Dense ]; then
  apt-get install -y libeigen3-dev || { apt-get update && apt-get install -y libeigen3-dev; }
fi

# The authors' sources, pinned, with Triangle and the timer patch; redone only
# when the commit or the patch changed
STAMP="$LBC_COMMIT $(sha256sum "$HERE/datasetup-timers.patch" | cut -c1-16)"
if [ "$(cat "$P/src/.lbc-peer-stamp" 2>/dev/null)" != "$STAMP" ]; then
  rm -rf "$P/src"; mkdir -p "$P/src"
  if [ -d "$MIRROR" ]; then
    git --git-dir="$MIRROR" archive "$LBC_COMMIT" | tar -x -C "$P/src"
  else
    rm -rf "$P/lbc-clone"
    git clone -q https://github.com/bldeng/LBC "$P/lbc-clone"
    git -C "$P/lbc-clone" archive "$LBC_COMMIT" | tar -x -C "$P/src"
  fi

  # Shewchuk's Triangle 1.6, from the PyPI sdist of 'triangle' (netlib is not reachable)
  if [ ! -f "$P/dl/$TRIANGLE_SDIST" ]; then
    (cd "$P/dl" && pip download --no-binary :all: --no-deps "triangle==20200424")
  fi
  tar -xzf "$P/dl/$TRIANGLE_SDIST" -C "$P/dl"
  mkdir -p "$P/src/external/triangle"
  cp "$P/dl/triangle-20200424/c/triangle.c" "$P/dl/triangle-20200424/c/triangle.h" "$P/src/external/triangle/"
  echo "$TRIANGLE_SHA256  $P/src/external/triangle/triangle.c" | sha256sum -c --quiet

  # Timestamps between DataSetup::init's stages (adds omp_get_wtime() calls only)
  (cd "$P/src" && patch -s -p0 < "$HERE/datasetup-timers.patch")
  rm -f "$P/build/"*.o
  echo "$STAMP" > "$P/src/.lbc-peer-stamp"
fi

# The UI's mesh generation, cut verbatim out of LBCUI.cpp
{
  echo "// extracted by build.sh from bldeng/LBC@$LBC_COMMIT LBCUI.cpp"
  for fn in 'bool LBCUI::read_cage' 'double LBCUI::domain_area' 'void LBCUI::delaunay_Triangulation'; do
    awk -v start="^$fn" '$0 ~ start {on=1} on {print} on && /^}/ {exit}' "$P/src/LBCUI.cpp"
    echo
  done
} > "$P/build/lbcui_extract.inc"
grep -q 'ostr_switches << "pza" << averageArea << "q33.0Y"' "$P/build/lbcui_extract.inc"
cp "$HERE/main.cpp" "$P/build/main.cpp"

# Compile. LBC.pro: DEFINES += TRILIBRARY ANSI_DECLARATORS, -fopenmp, -lgomp, no
# -march; qmake's release build would use -O2, we use -O3 -DNDEBUG (Eigen's
# assertions off). No CHOLMOD (commented out in LBC.pro): Eigen's SimplicialLDLT.
CXXFLAGS="-O3 -DNDEBUG -fopenmp -DTRILIBRARY -DANSI_DECLARATORS -I/usr/include/eigen3 -I$P/src -I$P/build"
cd "$P/build"
# (-DVOID=void -DREAL=double: the PyPI copy includes triangle.h first and
# comments out "#define VOID int"; its setup.py passes both. It also uses
# 64-bit-safe pointer arithmetic, INT_PTR = unsigned long long.)
[ -f triangle.o ] || gcc -O3 -DNDEBUG -DTRILIBRARY -DANSI_DECLARATORS -DVOID=void -DREAL=double -w \
  -c "$P/src/external/triangle/triangle.c" -o triangle.o
[ -f DataSetup.o ] || g++ $CXXFLAGS -c "$P/src/DataSetup.cpp" -o DataSetup.o
[ -f LBCSolver.o ] || g++ $CXXFLAGS -c "$P/src/LBCSolver.cpp" -o LBCSolver.o
g++ $CXXFLAGS -c main.cpp -o main.o
g++ -fopenmp main.o DataSetup.o LBCSolver.o triangle.o -o "$P/lbc-peer-driver"
echo "built $P/lbc-peer-driver"
