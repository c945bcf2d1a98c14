#!/usr/bin/env bash
# The cost of running drape from Python (issue 23: "running the pedestal
# example through drape.run costs at most 5 % more wall time than the
# CLI"). Times examples/fabric-on-pedestal.toml RUNS times (default 10)
# three ways, interleaved so that a change in the machine's load hits all
# alike:
#
#   cli          the command line, a whole process:
#                  drape run examples/fabric-on-pedestal.toml --out W/cli --quiet
#   python       Python, a whole process (the interpreter's start and
#                `import drape` included):
#                  python -c "import drape; drape.run('examples/fabric-on-pedestal.toml', out='W/py')"
#   drape.run    the call alone, in an interpreter that is already running
#                (a notebook's or a script's case)
#
# and prints each one's min and median wall seconds, and the medians of the
# pair-by-pair ratios python / cli and drape.run / cli.
#
#   cargo build --release -p drape-cli && scripts/python-bench.sh
#   RUNS=20 DRAPE=/path/to/drape scripts/python-bench.sh
#
# Python runs in a virtual environment of its own, made once as
# drape-py-bench-venv in the target directory, without the interpreter's
# other packages (--system-site-packages would have `site` read their .pth
# files at every start: 40 ms here); the package is rebuilt into it on
# every run (pip install ./crates/drape-py, from PyPI: maturin to build,
# numpy). A run of the pedestal takes about half a second: RUNS = 10 takes
# about 20 s. The machine is shared: run it when nothing else is compiling
# (see `uptime`), one benchmark at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=${DRAPE:-target/release/drape}
runs=${RUNS:-10}
target=$(cargo metadata --format-version 1 --no-deps |
  python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
venv="$target/drape-py-bench-venv"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check ./crates/drape-py

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$venv/bin/python" - "$drape" "$runs" "$work" <<'EOF'
import statistics
import subprocess
import sys
import time

import drape

cli, runs, work = sys.argv[1], int(sys.argv[2]), sys.argv[3]
scenario = "examples/fabric-on-pedestal.toml"
commands = {
    "cli": [cli, "run", scenario, "--out", f"{work}/cli", "--quiet"],
    "python": [sys.executable, "-c", f"import drape; drape.run({scenario!r}, out={work + '/py'!r})"],
}


def process(argv):
    start = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def call():
    start = time.perf_counter()
    drape.run(scenario, out=f"{work}/call")
    return time.perf_counter() - start


# One of each first, uncounted: the files in the page cache, the pools up.
process(commands["cli"]), process(commands["python"]), call()
times = {"cli": [], "python": [], "drape.run": []}
for r in range(runs):
    times["cli"].append(process(commands["cli"]))
    times["python"].append(process(commands["python"]))
    times["drape.run"].append(call())
    print(f"run {r + 1:2d}: " + "  ".join(f"{k} {v[-1]:.3f} s" for k, v in times.items()), flush=True)
print()
for name, t in times.items():
    print(f"{name:10s} min {min(t):.3f} s  median {statistics.median(t):.3f} s")
for name in ("python", "drape.run"):
    ratios = [a / b for a, b in zip(times[name], times["cli"])]
    print(
        f"{name} / cli: median {statistics.median(ratios):.3f} "
        f"(min {min(ratios):.3f}, max {max(ratios):.3f}; pair by pair)"
    )
EOF
