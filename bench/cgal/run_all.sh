#!/usr/bin/env bash
# Runs the CGAL baseline benchmark set and prints one JSON line per run on stdout.
#
#   bench/cgal/run_all.sh [--bin DIR] [--repeat K] [--set standard|quick|full] [--summary]
#
#   --bin DIR   where the programs are/are built (default <repo>/target/cgal); build.sh is run
#               first (idempotent, its messages go to stderr).
#   --repeat K  runs per configuration (default 3).
#   --set       standard (default): the figures of bench/README.md; quick: small sizes for a
#               smoke test (~1 s); full: standard + the other catalog surfaces + manifold tag.
#   --summary   instead of every run, print per configuration the line of the run with the
#               median "seconds", plus "runs":K and "seconds_all":[...] (needs python3).
#
# Each line is the program's JSON object with two fields prepended: "config" (a stable id,
# e.g. "surface_sphere_r0.02") and "run" (0-based). Exit status 1 if any run failed (the
# others still run; the failure is reported on stderr).
set -uo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="$root/target/cgal"
repeat=3
set_name=standard
summary=0
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bin="$2"; shift 2 ;;
    --repeat) repeat="$2"; shift 2 ;;
    --set) set_name="$2"; shift 2 ;;
    --summary) summary=1; shift ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "run_all.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$repeat" in ''|*[!0-9]*|0) echo "run_all.sh: --repeat needs a positive integer, got '$repeat'" >&2; exit 2 ;; esac

# config id | program | arguments
standard=(
  "delaunay_cube_1e5|cgal_delaunay|--random 100000 --seed 1 --distribution cube"
  "delaunay_cube_1e6|cgal_delaunay|--random 1000000 --seed 1 --distribution cube"
  "delaunay_sphere_1e6|cgal_delaunay|--random 1000000 --seed 1 --distribution sphere"
  "surface_sphere_r0.02|cgal_surface_mesher|--surface sphere --angle 30 --radius 0.02 --distance 0.02"
  "surface_torus_r0.0194|cgal_surface_mesher|--surface torus --angle 30 --radius 0.0194 --distance 0.0194"
  "image_tanglecube128_r0.06|cgal_image_mesher|--tanglecube-grid 128 --iso 0 --angle 30 --radius 0.06 --distance 0.06"
)
quick=(
  "delaunay_cube_1e4|cgal_delaunay|--random 10000 --seed 1 --distribution cube"
  "delaunay_sphere_1e4|cgal_delaunay|--random 10000 --seed 1 --distribution sphere"
  "surface_sphere_r0.1|cgal_surface_mesher|--surface sphere --angle 30 --radius 0.1 --distance 0.1"
  "surface_torus_r0.1|cgal_surface_mesher|--surface torus --angle 30 --radius 0.1 --distance 0.1"
  "image_tanglecube64_r0.2|cgal_image_mesher|--tanglecube-grid 64 --iso 0 --angle 30 --radius 0.2 --distance 0.2"
)
full=("${standard[@]}"
  "surface_ellipsoid_r0.02|cgal_surface_mesher|--surface ellipsoid --angle 30 --radius 0.02 --distance 0.02"
  "surface_double_torus_r0.02|cgal_surface_mesher|--surface double_torus --angle 30 --radius 0.02 --distance 0.02"
  "surface_tanglecube_r0.06|cgal_surface_mesher|--surface tanglecube --angle 30 --radius 0.06 --distance 0.06"
  "surface_chair_r0.1|cgal_surface_mesher|--surface chair --angle 30 --radius 0.1 --distance 0.1"
  "surface_blobs_r0.02|cgal_surface_mesher|--surface blobs --angle 30 --radius 0.02 --distance 0.02"
  "surface_heart_r0.02|cgal_surface_mesher|--surface heart --angle 30 --radius 0.02 --distance 0.02"
  "surface_sphere_r0.02_manifold|cgal_surface_mesher|--surface sphere --angle 30 --radius 0.02 --distance 0.02 --manifold"
  "surface_torus_r0.0194_manifold|cgal_surface_mesher|--surface torus --angle 30 --radius 0.0194 --distance 0.0194 --manifold"
  "image_tanglecube128_r0.06_manifold|cgal_image_mesher|--tanglecube-grid 128 --iso 0 --angle 30 --radius 0.06 --distance 0.06 --manifold"
)
case "$set_name" in
  standard) configs=("${standard[@]}") ;;
  quick) configs=("${quick[@]}") ;;
  full) configs=("${full[@]}") ;;
  *) echo "run_all.sh: unknown --set '$set_name' (standard, quick or full)" >&2; exit 2 ;;
esac

"$here/build.sh" "$bin" || { echo "run_all.sh: build failed" >&2; exit 1; }

tmpdir="$(mktemp -d)"
trap 'rm -rf "$tmpdir"' EXIT
status=0
run_set() {
  for cfg in "${configs[@]}"; do
    IFS='|' read -r id prog cargs <<<"$cfg"
    for ((k = 0; k < repeat; k++)); do
      # shellcheck disable=SC2086
      if line="$(TMPDIR="$tmpdir" "$bin/$prog" $cargs)"; then
        printf '{"config":"%s","run":%d,%s\n' "$id" "$k" "${line#\{}"
      else
        echo "run_all.sh: $id run $k failed: $bin/$prog $cargs" >&2
        status=1
      fi
    done
  done
}

if [ "$summary" = 1 ]; then
  command -v python3 >/dev/null || { echo "run_all.sh: --summary needs python3" >&2; exit 2; }
  run_set > "$tmpdir/runs.jsonl"
  python3 - "$tmpdir/runs.jsonl" <<'PY'
import json, sys
groups = {}
for line in open(sys.argv[1]):
    r = json.loads(line)
    groups.setdefault(r["config"], []).append(r)
for cfg, runs in groups.items():
    runs.sort(key=lambda r: r["seconds"])
    med = dict(runs[(len(runs) - 1) // 2])
    med.pop("run", None)
    med["runs"] = len(runs)
    med["seconds_all"] = [r["seconds"] for r in runs]
    print(json.dumps(med, separators=(",", ":")))
PY
else
  run_set
fi
exit $status
