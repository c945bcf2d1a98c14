#!/usr/bin/env bash
# Bending's cost per Newton iteration at 100k elements (issue 20: "bending
# adds at most 30 % to the cost of a Newton iteration"). Runs
# crates/drape-bench/scenarios/membrane-100k.toml and bending-100k.toml
# (the same 1 m square, 224 x 224 squares = 100,352 T3, 151,200 free unknowns,
# hanging from one edge, 3 steps of 5 ms, plain Newton; the second with
# bending_rigidity = 2e-5 N m) RUNS times each (default 3), interleaved so
# that a change in the machine's load hits both alike, and prints per run
# and as min / median:
#
#   per iteration   (wall_seconds - setup_seconds - output_seconds) / newton_iterations
#   later steps     the same without the first step (first_step_seconds and
#                   its iterations: the first step also does the symbolic
#                   analysis the later ones reuse)
#
# the ratio bending / membrane of the medians, and the linear solver's path
# (summary.json's `linear` counts). With PERF=1 it then records one more
# run of each under `perf record --call-graph dwarf` and prints the hottest
# functions (self time, `perf report --no-children`) and the CPU time split
# by what called them: Cholesky factorisation (numeric, symbolic),
# triangular solves, the membrane and mass assembly, the bending patches,
# the matrix-vector products of the residual checks, set-up.
#
#   cargo build --release -p drape-cli && scripts/bending-bench.sh
#   RUNS=5 PERF=1 DRAPE=/path/to/drape scripts/bending-bench.sh
#
# A run takes about 8 s without bending and 33 s with it on this 2-core
# machine in a quiet hour (up to 15 and 50 s in a busy one; perf adds a
# little). The machine is shared: run it when nothing else is compiling
# (see `uptime`), one benchmark at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=${DRAPE:-target/release/drape}
runs=${RUNS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
names=(membrane-100k bending-100k)
for ((r = 1; r <= runs; r++)); do
  for name in "${names[@]}"; do
    "$drape" run "crates/drape-bench/scenarios/$name.toml" --out "$work/$name" --quiet
    python3 - "$work/$name" "$name" "$r" "$work/runs.txt" <<'PY'
import csv, json, sys
out, name, r, runs = sys.argv[1:5]
s = json.load(open(f"{out}/summary.json"))
assert s["status"] == "completed", s["message"]
rows = list(csv.DictReader(open(f"{out}/history.csv")))[1:]
its = [int(x["iterations"]) for x in rows]
steps_time = s["wall_seconds"] - s["setup_seconds"] - s["output_seconds"]
d = dict(name=name, run=int(r), its=s["newton_iterations"], iterations=its,
         per_it=steps_time / s["newton_iterations"],
         later=(steps_time - s["first_step_seconds"]) / (s["newton_iterations"] - its[0]),
         wall=s["wall_seconds"], setup=s["setup_seconds"], first=s["first_step_seconds"],
         linear=s["linear"], dofs=s["dofs"], fixed=s["fixed_dofs"], elements=s["elements"])
with open(runs, "a") as f:
    print(json.dumps(d), file=f)
print(f"{name:14s} run {r}: {d['its']} Newton iterations {its}, wall {d['wall']:.2f} s "
      f"(set-up {d['setup']:.2f} s, first step {d['first']:.2f} s), "
      f"{d['per_it']:.3f} s per iteration, {d['later']:.3f} s in the later steps")
PY
  done
done
python3 - "$work/runs.txt" <<'PY'
import json, statistics, sys
runs = {}
for line in open(sys.argv[1]):
    d = json.loads(line)
    runs.setdefault(d["name"], []).append(d)
med = {}
print()
for name, rs in runs.items():
    l = rs[0]["linear"]
    path = [f"{l[k]} {k.replace('_', ' ')}" for k in
            ("cholesky_factorizations", "lu_factorizations", "block_lu_factorizations",
             "multigrid_builds") if l[k]]
    print(f"{name}: {rs[0]['elements']} elements, {rs[0]['dofs'] - rs[0]['fixed']} free unknowns; "
          f"linear: {l['solves']} solves ({', '.join(path) or 'no factorisation'}), "
          f"{l['krylov_iterations']} Krylov iterations, {l['chord_solves']} chord solves")
    for key, label in (("per_it", "per Newton iteration"), ("later", "later steps, per iteration")):
        xs = sorted(d[key] for d in rs)
        med[name, key] = statistics.median(xs)
        print(f"  {label:27s} min {xs[0]:.3f} s, median {med[name, key]:.3f} s, max {xs[-1]:.3f} s "
              f"({len(xs)} runs)")
print()
for key, label in (("per_it", "per Newton iteration"), ("later", "later steps, per iteration")):
    ratio = med["bending-100k", key] / med["membrane-100k", key]
    print(f"bending / membrane, {label}: {ratio:.2f} (target of issue 20: at most 1.30)")
PY
[[ -n "${PERF:-}" ]] || exit 0
# The CPU time split: each sample goes to set-up if its stack passes
# through the scenario build or the initial state, else to the first of
# the rules matched from its leaf up; faer's dense kernels (gemm) rarely
# unwind and count, by their name alone, as factorisation (the
# triangular solves use them too, for far fewer flops). "s/iteration" is
# the category's CPU time (samples / 97 Hz) over the run's Newton
# iterations, set-up included in the run but not in the iterations.
cat > "$work/classify.py" <<'PY'
import collections, re, sys
setup = r"drape::scenario::|Newmark::initial_state|DynamicWorkspace::with_mode|drape::model::Layout::new"
rules = [
    ("bending patches (drape::bending)", r"drape::bending::"),
    ("matrix-vector products (residual checks)", r"drape::solver::product"),
    ("Cholesky: symbolic analysis, ordering", r"Cholesky::analyse|symbolic|amd::"),
    ("Cholesky: numeric factorisation", r"factorize_supernodal_numeric|Cholesky::factorize|permute_self_adjoint"),
    ("triangular solves", r"solve_in_place|triangular_solve"),
    ("membrane elements, mass, gather into the pattern", r"drape::model::|drape::element::|drape::material::"),
    ("output (frames, history)", r"drape::output::|drape::simulation::frames"),
]
fallback = [
    ("faer dense kernels, stack not unwound (factorisation; some solves)", r"gemm|pulp::|faer::"),
    ("operating system (page faults, memset)", r"page_fault|clear_page|__memset|__memmove"),
]
counts, total = collections.Counter(), 0
for sample in sys.stdin.read().split("\n\n"):
    frames = [l.strip() for l in sample.strip().split("\n")[1:] if l.strip()]
    if not frames:
        continue
    total += 1
    label = None
    if any(re.search(setup, f) for f in frames):
        label = "set-up (scenario build, pattern, initial acceleration)"
    for f in frames:
        if label:
            break
        for l, p in rules:
            if re.search(p, f):
                label = l
                break
    for l, p in fallback:
        if label:
            break
        if any(re.search(p, f) for f in frames):
            label = l
    counts[label or "other"] += 1
its = int(sys.argv[1])  # Newton iterations of the recorded run
for label, c in counts.most_common():
    print(f"  {100 * c / total:5.1f} %  {c / 97 / its:6.3f} s/iteration  {label}")
print(f"  ({total} samples at 97 Hz, {total / 97:.1f} s of CPU; {its} Newton iterations)")
PY
for name in "${names[@]}"; do
  echo
  echo "== perf: $name (CPU time of both threads, whole run)"
  perf record -q -F 97 --call-graph dwarf,16384 -o "$work/$name.perf" \
    "$drape" run "crates/drape-bench/scenarios/$name.toml" --out "$work/$name-perf" --quiet
  perf report -i "$work/$name.perf" --no-children --stdio --percent-limit 2 -g none \
    --sort dso,sym 2>/dev/null | grep -E '^ +[0-9]' || true
  its=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["newton_iterations"])' \
    "$work/$name-perf/summary.json")
  perf script -i "$work/$name.perf" -F tid,ip,sym 2>/dev/null | python3 "$work/classify.py" "$its"
done
