#!/usr/bin/env bash
# Self-test of the CGAL baseline programs (about 2 s): builds them, then checks the PRNG test
# vector, reproducibility, mesh topology (Euler characteristic, no boundary / non-manifold
# edges), the JSON output shape and that bad input exits with status 2 and a message.
#   bench/cgal/selftest.sh [BIN_DIR]      (default <repo>/target/cgal)
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="${1:-$root/target/cgal}"
"$here/build.sh" "$bin" || exit 1
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fails=0
check() {  # check NAME COMMAND... : the command must succeed
  if "${@:2}"; then echo "ok   $1" >&2; else echo "FAIL $1" >&2; fails=$((fails + 1)); fi
}
# field FILE KEY: a JSON field of the (single) line in FILE
field() { python3 -c 'import json,sys; print(json.loads(open(sys.argv[1]).read())[sys.argv[2]])' "$1" "$2"; }
one_json_line() { [ "$(wc -l <"$1")" = 1 ] && python3 -c 'import json,sys; json.loads(open(sys.argv[1]).read())' "$1"; }
expect_error() {  # the command must exit with status 2 and print "error:" on stderr
  "$@" >"$tmp/o" 2>"$tmp/e"
  [ $? = 2 ] && grep -q '^error: ' "$tmp/e" && [ ! -s "$tmp/o" ]
}

# PRNG: SplitMix64 seed 1, first uniform = 0.5665615751722809 (x of the first cube point).
"$bin/cgal_delaunay" --random 5 --seed 1 --dump-points "$tmp/p.xyz" >"$tmp/d.json"
check "prng test vector" python3 -c 'import sys; x=float(open(sys.argv[1]).read().split()[0]); sys.exit(x != 0.5665615751722809)' "$tmp/p.xyz"
check "delaunay json" one_json_line "$tmp/d.json"
"$bin/cgal_delaunay" --random 2000 --seed 2 --distribution sphere --check --dump-points "$tmp/s.xyz" >"$tmp/s.json"
check "delaunay sphere valid" test "$(field "$tmp/s.json" valid)" = True
check "sphere points have norm 1" python3 -c 'import sys,math; sys.exit(any(abs(math.sqrt(sum(float(t)**2 for t in l.split()))-1)>1e-15 for l in open(sys.argv[1])))' "$tmp/s.xyz"
"$bin/cgal_delaunay" --input "$tmp/s.xyz" >"$tmp/s2.json"
check "xyz round trip same cells" test "$(field "$tmp/s.json" finite_cells)" = "$(field "$tmp/s2.json" finite_cells)"

for spec in "sphere 0.1 2" "torus 0.1 0" "double_torus 0.1 -2" "tanglecube 0.3 -8" "chair 0.3 -4"; do
  read -r s r chi <<<"$spec"
  "$bin/cgal_surface_mesher" --surface "$s" --radius "$r" --distance "$r" --output "$tmp/$s.off" >"$tmp/$s.json"
  check "surface $s json" one_json_line "$tmp/$s.json"
  check "surface $s euler $chi" test "$(field "$tmp/$s.json" euler)" = "$chi"
  check "surface $s closed manifold" test "$(field "$tmp/$s.json" boundary_edges)$(field "$tmp/$s.json" nonmanifold_edges)" = 00
  check "surface $s off header" test "$(head -1 "$tmp/$s.off")" = OFF
done
"$bin/cgal_surface_mesher" --surface torus --radius 0.1 --distance 0.1 --seed 5 >"$tmp/t1.json"
"$bin/cgal_surface_mesher" --surface torus --radius 0.1 --distance 0.1 --seed 5 >"$tmp/t2.json"
check "surface reproducible" test "$(field "$tmp/t1.json" vertices)/$(field "$tmp/t1.json" f_evals)" = "$(field "$tmp/t2.json" vertices)/$(field "$tmp/t2.json" f_evals)"
TMPDIR="$tmp" "$bin/cgal_image_mesher" --tanglecube-grid 48 --radius 0.25 --distance 0.25 >"$tmp/i.json"
check "image json" one_json_line "$tmp/i.json"
check "image tanglecube euler -8" test "$(field "$tmp/i.json" euler)" = -8
check "image inr size" test "$(stat -c %s "$tmp/cgal_tanglecube_48.inr")" = $((256 + 48 * 48 * 48 * 4))

printf '0 0 0\n1 x 0\n' >"$tmp/bad.xyz"
check "bad xyz line" expect_error "$bin/cgal_delaunay" --input "$tmp/bad.xyz"
check "missing file" expect_error "$bin/cgal_delaunay" --input "$tmp/none.xyz"
check "bad distribution" expect_error "$bin/cgal_delaunay" --random 10 --distribution foo
check "bad count" expect_error "$bin/cgal_delaunay" --random -3
check "unknown option" expect_error "$bin/cgal_surface_mesher" --surface sphere --radius 1 --distance 1 --bogus 1
check "unknown surface" expect_error "$bin/cgal_surface_mesher" --surface cube --radius 1 --distance 1
check "bad radius" expect_error "$bin/cgal_surface_mesher" --surface sphere --radius 0 --distance 1
check "angle > 30" expect_error "$bin/cgal_surface_mesher" --surface sphere --radius 1 --distance 1 --angle 45
check "non-number" expect_error "$bin/cgal_surface_mesher" --surface sphere --radius abc --distance 1
check "image center outside" expect_error "$bin/cgal_image_mesher" --input "$tmp/cgal_tanglecube_48.inr" --origin -4,-4,-4 --center 0,0,0 --sphere-radius 6 --radius 1 --distance 1
check "image not an image" expect_error "$bin/cgal_image_mesher" --input "$tmp/bad.xyz" --center 0,0,0 --sphere-radius 6 --radius 1 --distance 1
check "image bad center" expect_error "$bin/cgal_image_mesher" --input "$tmp/bad.xyz" --center 0,0 --sphere-radius 6 --radius 1 --distance 1

if [ "$fails" = 0 ]; then echo "selftest: all passed" >&2; else echo "selftest: $fails FAILED" >&2; exit 1; fi
