#!/usr/bin/env bash
# Builds the CGAL baseline programs (cgal_delaunay, cgal_surface_mesher, cgal_image_mesher).
#
#   bench/cgal/build.sh [OUT_DIR]        (default: <repo>/target/cgal)
#
# Installs libcgal-dev and cmake with apt-get if the CGAL headers are missing (Debian 12 ships
# CGAL 5.5.1, header-only; the programs also link GMP and MPFR, which libcgal-dev pulls in).
# Idempotent: a program is rebuilt only when a source (or this script) is newer than it.
# Env: CXX (default g++), CXXFLAGS_EXTRA (appended, e.g. -march=native; default none).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-$root/target/cgal}"
cxx="${CXX:-g++}"

if [ ! -f /usr/include/CGAL/version.h ] || ! command -v cmake >/dev/null 2>&1 \
   || ! command -v "$cxx" >/dev/null 2>&1; then
  echo "build.sh: CGAL headers, cmake or $cxx missing: installing libcgal-dev cmake g++ with apt-get" >&2
  sudo_cmd=""
  if [ "$(id -u)" != 0 ]; then sudo_cmd="sudo"; fi
  $sudo_cmd apt-get update >&2
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y libcgal-dev cmake g++ >&2
fi
if [ ! -f /usr/include/CGAL/version.h ]; then
  echo "build.sh: error: /usr/include/CGAL/version.h still missing after install; install libcgal-dev by hand" >&2
  exit 1
fi
version="$(sed -n 's/^#define CGAL_VERSION \([0-9.]*\).*/\1/p' /usr/include/CGAL/version.h)"

mkdir -p "$out"
# -frounding-math: CGAL's interval filters need it with GCC (CGAL's own CMake setup adds it).
# -ffp-contract=off: keeps the point generator bit-identical to the Rust one (no FMA).
flags=(-O3 -DNDEBUG -std=c++17 -frounding-math -ffp-contract=off)
# shellcheck disable=SC2206
extra=(${CXXFLAGS_EXTRA:-})
common=("$here/common.hpp" "$here/surfaces.hpp" "$here/mesh_stats.hpp" "$here/surface_run.hpp"
        "$here/build.sh")

for prog in cgal_delaunay cgal_surface_mesher cgal_image_mesher; do
  src="$here/$prog.cpp"
  bin="$out/$prog"
  stale=0
  if [ ! -x "$bin" ]; then
    stale=1
  else
    for dep in "$src" "${common[@]}"; do
      if [ "$dep" -nt "$bin" ]; then stale=1; fi
    done
  fi
  if [ "$stale" = 1 ]; then
    echo "build.sh: building $bin (CGAL $version)" >&2
    "$cxx" "${flags[@]}" "${extra[@]}" -o "$bin.tmp" "$src" -lgmp -lmpfr
    mv -f "$bin.tmp" "$bin"
  else
    echo "build.sh: $bin is up to date (CGAL $version)" >&2
  fi
done
