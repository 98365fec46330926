#!/usr/bin/env bash
# Build the rdt_mesher wheel and run the Python tests in a fresh virtual environment:
#   bash python/build_and_test.sh [pytest args...]
# Needs python3 (3.9+, with venv) and cargo; maturin, numpy, pytest and the test packages come
# from python/requirements-test.txt. The venv lives in target/py-venv, the wheel in
# target/py-wheels. Exits non-zero when a step or a test fails.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
PYTHON="${PYTHON:-python3}"
VENV="$ROOT/target/py-venv"
WHEELS="$ROOT/target/py-wheels"

if [ ! -x "$VENV/bin/python" ]; then
    mkdir -p "$ROOT/target"
    "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r python/requirements-test.txt

# The CLI the tests compare with (a no-op when it is up to date).
cargo build --release --quiet -p xtask

rm -rf "$WHEELS"
"$VENV/bin/maturin" build --release --quiet -m python/Cargo.toml -i "$VENV/bin/python" -o "$WHEELS"
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps "$WHEELS"/rdt_mesher-*.whl

# From the repository root: the package imported is the installed wheel, not python/rdt_mesher.
export RDT_XTASK="$ROOT/target/release/xtask"
"$VENV/bin/python" -c 'import rdt_mesher, sys; print("rdt_mesher", rdt_mesher.__version__, "from", rdt_mesher.__file__, file=sys.stderr)'
"$VENV/bin/python" -m pytest -q -p no:cacheprovider python/tests "$@"
