#!/bin/sh
# Runs delaunay3 and CGAL (Debian libcgal-dev, header-only) on the same points, one after the
# other, so that the ratio comes from one run on one (shared) machine. Prints JSON lines plus
# user CPU time and peak RSS from /usr/bin/time. Usage: benches/cgal_baseline.sh [sizes...]
set -eu
cd "$(dirname "$0")/.."
out=${TMPDIR:-/tmp}/delaunay3_cgal_baseline
g++ -O3 -DNDEBUG -std=c++17 -o "$out" benches/cgal_baseline.cpp -lgmp -lmpfr
cargo build --release -q -p delaunay3 --example bench_points
ours=$(cargo metadata --format-version 1 --no-deps | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')/release/examples/bench_points
for spec in ${@:-100000:cube 1000000:cube 1000000:sphere}; do
  n=${spec%%:*}; d=${spec#*:}
  for prog in "$ours" "$out"; do
    /usr/bin/time -f "  user %U s, peak RSS %M KB" "$prog" "$n" 1 "$d"
  done
done
