#!/usr/bin/env bash
# Times the reference problem as issue 7 asks: both pedestal examples
# (stress-projection wrinkling; penalty and multipliers), RUNS runs each
# (default 5), interleaved so that a change in the machine's load hits both
# alike, and prints every run and the median of `wall_seconds` from
# summary.json, with the Newton iterations and the final monitor positions
# (the results to compare between builds, to the Newton tolerance).
#
#   cargo build --release && scripts/pedestal-bench.sh
#   RUNS=9 DRAPE=/path/to/other/drape scripts/pedestal-bench.sh
#
# The machine is shared: run it when nothing else is compiling (see
# `uptime`), and compare builds measured in the same hour.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=${DRAPE:-target/release/drape}
runs=${RUNS:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
examples=(examples/fabric-on-pedestal.toml examples/fabric-on-pedestal-lagrange.toml)
for ((r = 1; r <= runs; r++)); do
  for e in "${examples[@]}"; do
    name=$(basename "$e" .toml)
    "$drape" run "$e" --out "$work/$name" --quiet
    python3 - "$work/$name/summary.json" "$name" >> "$work/runs.txt" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print(sys.argv[2], d["wall_seconds"], d["newton_iterations"],
      d["output_seconds"], json.dumps(d["monitors"]))
PY
  done
done
python3 - "$work/runs.txt" <<'PY'
import json, statistics, sys
runs = {}
for line in open(sys.argv[1]):
    name, wall, its, out, monitors = line.split(" ", 4)
    runs.setdefault(name, []).append((float(wall), int(its), float(out), json.loads(monitors)))
for name, rs in runs.items():
    walls = [r[0] for r in rs]
    print(f"{name}: wall {' / '.join(f'{w:.3f}' for w in walls)} s, "
          f"median {statistics.median(walls):.3f} s; output {statistics.median(r[2] for r in rs):.3f} s; "
          f"Newton iterations {rs[0][1]}")
    for m, p in sorted(rs[0][3].items()):
        print(f"  {m}: [{p[0]:.7f}, {p[1]:.7f}, {p[2]:.7f}]")
PY
