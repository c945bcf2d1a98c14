#!/usr/bin/env bash
# Times drape per step and per Newton iteration at several mesh sizes and
# prints a Markdown table (docs/performance.md, "Scaling"), then the
# exponent of a least-squares fit `time per Newton iteration ~ elements^p`.
#
#   scripts/scaling.sh [DIVISIONS...]            # default: 20 50 100 200 400
#   LINEAR=auto scripts/scaling.sh 100            # another [solver] linear (default iterative)
#   STEPS=2 scripts/scaling.sh 700                # steps per run (default 5)
#
# The problem: the hanging cloth (examples/hanging-cloth.toml) at N x N
# divisions, STEPS steps of 1e-4 s from rest (Newton works at every step:
# the pins hold the cloth while it starts to fall). "wall / step" is the
# time of the mechanics and solvers of the steps alone (summary.json:
# wall_seconds - setup_seconds - output_seconds); the set-up
# (linear-solver structures, initial acceleration, first outputs) and the
# outputs of the steps (history rows, the last frame) have their own
# columns, and the scenario build (mesh, pattern, mass matrix) is outside
# all of them. Needs a release build (`cargo build
# --release`) and GNU time (/usr/bin/time) for the peak memory.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=target/release/drape
linear=${LINEAR:-iterative}
steps=${STEPS:-5}
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(20 50 100 200 400)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "| divisions | elements | unknowns | wall / step | wall / Newton iteration | Newton its / step | Krylov its / solve | multigrid builds | factorisations | set-up | first step | later steps, each | outputs / step | peak memory |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for n in "${sizes[@]}"; do
  sed -e "s/^divisions = \[20, 20\]/divisions = [$n, $n]/" \
      -e "s/^segments = .*/segments = [{ steps = $steps, dt = 1.0e-4 }]/" \
      -e "s/^every = 10/every = 100000/" \
      -e "s/^max_iterations = 30/max_iterations = 30\nlinear = \"$linear\"/" \
      examples/hanging-cloth.toml > "$work/s.toml"
  /usr/bin/time -f "%M" -o "$work/mem" "$drape" run "$work/s.toml" --out "$work/out" --quiet
  python3 - "$n" "$work" <<'PY'
import json, sys
n, work = sys.argv[1], sys.argv[2]
s = json.load(open(f"{work}/out/summary.json"))
steps, its = s["steps"], max(s["newton_iterations"], 1)
stepping = s["wall_seconds"] - s["setup_seconds"] - s["output_seconds"]
# Steps after the first: the first also builds what the solver keeps.
later = (stepping - s["first_step_seconds"]) / (steps - 1) if steps > 1 else float("nan")
mem = int(open(f"{work}/mem").read().split()[-1]) / 1024
l = s["linear"]
factorisations = l["cholesky_factorizations"] + l["lu_factorizations"] + l["block_lu_factorizations"]
print(f"| {n}x{n} | {s['elements']:,} | {s['dofs']:,} | {stepping/steps:.3f} s | {stepping/its:.4f} s | {its/steps:.1f} | {l['krylov_iterations']/max(l['solves'],1):.1f} | {l['multigrid_builds']} | {factorisations} | {s['setup_seconds']:.2f} s | {s['first_step_seconds']:.3f} s | {later:.3f} s | {s['output_seconds']/steps:.3f} s | {mem:.0f} MB |")
with open(f"{work}/rows", "a") as f:
    # Steady state (later steps) per Newton iteration when there are any.
    per_iteration = later / (its / steps) if steps > 1 else stepping / its
    f.write(f"{s['elements']} {per_iteration}\n")
PY
done
python3 - "$work/rows" <<'PY'
import math, sys
rows = [tuple(map(float, l.split())) for l in open(sys.argv[1])]
if len(rows) >= 2:
    xs = [math.log(e) for e, _ in rows]
    ys = [math.log(t) for _, t in rows]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    p = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    print(f"\ntime per Newton iteration (later steps) ~ elements^{p:.2f} (least squares over {len(rows)} sizes)")
PY
