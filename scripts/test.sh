#!/usr/bin/env bash
# The project's test command (README, first code block; what .ci/run runs):
#
#   scripts/test.sh
#
# 1. the Rust tests, `cargo test --release --workspace --exclude
#    drape-bench`: the tests of the default members (drape-py has none in
#    Rust, drape-bench only criterion's benchmarks), with drape-py among
#    the packages so that cargo gives the dependencies the features
#    maturin's build of drape-py gives them — that build then reuses the
#    compiled faer and drape (drape-py's Cargo.toml, `libc`). The `drape`
#    binary it builds is the one the Python tests compare with;
# 2. the Python package: `pip install ./crates/drape-py` into a virtual
#    environment, then its tests, `pytest crates/drape-py/tests`.
#
# First of all, `scripts/import-cycles.py`: the library's modules import
# one another one way, without circles (docs/testing.md).
#
# Needs cargo and python3 (3.9 or later, with venv and pip). The virtual
# environment is made once, as drape-py-venv in the target directory
# ($CARGO_TARGET_DIR or target/), and the package is rebuilt into it on
# every run (maturin builds it in the same target directory, so only the
# Python crate is compiled after step 1). The environment sees the
# interpreter's own packages (--system-site-packages): maturin, pytest,
# numpy and matplotlib (for the example examples/python/sweep_bending.py)
# are taken from there where installed (.ci/run installs them), else
# installed into the environment; Ray and Dask, the optional engines, only
# from there — their tests skip, saying so, where they cannot be imported.
set -euo pipefail
cd "$(dirname "$0")/.."

start=$SECONDS
echo "== Import circles: python3 scripts/import-cycles.py"
python3 scripts/import-cycles.py
echo "== Rust: cargo test --release --workspace --exclude drape-bench"
cargo test --release --workspace --exclude drape-bench
echo "== Rust tests done in $((SECONDS - start)) s"

target=$(cargo metadata --format-version 1 --no-deps |
  python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
venv="$target/drape-py-venv"
python="$venv/bin/python"
if [ ! -x "$python" ]; then
  python3 -m venv --system-site-packages "$venv"
fi
missing=$("$python" -c '
import importlib.util
print(" ".join(n for n in ("maturin", "pytest", "numpy", "matplotlib") if importlib.util.find_spec(n) is None))')
if [ -n "$missing" ]; then
  echo "== Python: installing $missing into $venv"
  "$python" -m pip install --quiet --disable-pip-version-check $missing
fi

echo "== Python: pip install ./crates/drape-py (into $venv)"
# --no-build-isolation: the environment's maturin builds it (no download).
# Its build hook runs the `maturin` program, found on PATH: the
# environment's own, where this script installed it, comes first.
export PATH="$venv/bin:$PATH"
"$python" -m pip install --quiet --disable-pip-version-check --no-build-isolation ./crates/drape-py

echo "== Python: package built and installed at $((SECONDS - start)) s"
echo "== Python: pytest crates/drape-py/tests"
# The tests compare drape.run with the binary step 1 built. No cache
# directory: it would be left in the work tree.
DRAPE_CLI="$target/release/drape" \
  "$python" -m pytest crates/drape-py/tests -p no:cacheprovider -rs
