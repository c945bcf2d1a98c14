#!/usr/bin/env bash
# Times drape per step and per Newton iteration at several mesh sizes and
# prints a Markdown table (docs/performance.md, "Scaling").
#
#   scripts/scaling.sh [DIVISIONS...]          # default: 20 50 100 200
#   LINEAR=iterative scripts/scaling.sh 100     # another [solver] linear
#
# The problem: the hanging cloth (examples/hanging-cloth.toml) at N x N
# divisions, 5 steps of 1e-4 s from rest (Newton works at every step: the
# pins hold the cloth while it starts to fall). Needs a release build
# (`cargo build --release`) and GNU time (/usr/bin/time) for the memory.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=target/release/drape
linear=${LINEAR:-auto}
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(20 50 100 200)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "| divisions | elements | unknowns | wall / step | wall / Newton iteration | Newton its / step | Cholesky | LU | Krylov its | peak memory |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for n in "${sizes[@]}"; do
  sed -e "s/^divisions = \[20, 20\]/divisions = [$n, $n]/" \
      -e "s/^segments = .*/segments = [{ steps = 5, dt = 1.0e-4 }]/" \
      -e "s/^every = 10/every = 100000/" \
      -e "s/^max_iterations = 30/max_iterations = 30\nlinear = \"$linear\"/" \
      examples/hanging-cloth.toml > "$work/s.toml"
  /usr/bin/time -f "%M" -o "$work/mem" "$drape" run "$work/s.toml" --out "$work/out" --quiet
  python3 - "$n" "$work" <<'PY'
import json, sys
n, work = sys.argv[1], sys.argv[2]
s = json.load(open(f"{work}/out/summary.json"))
# Time of the steps alone: history has no wall clock, so subtract a
# zero-step run? Keep it simple: the run's wall time over its steps
# (set-up included, which is a small share from 100 x 100 on).
steps, its = s["steps"], max(s["newton_iterations"], 1)
mem = int(open(f"{work}/mem").read().split()[-1]) / 1024
l = s["linear"]
print(f"| {n}x{n} | {s['elements']:,} | {s['dofs']:,} | {s['wall_seconds']/steps:.3f} s | {s['wall_seconds']/its:.3f} s | {its/steps:.1f} | {l['cholesky_factorizations']} | {l['lu_factorizations']} | {l['krylov_iterations']} | {mem:.0f} MB |")
PY
done
