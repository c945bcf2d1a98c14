#!/usr/bin/env bash
# The settle benchmark of issue 17: the drape tester (Gmsh T3 and T6
# discs, stress-projection wrinkling, penalty contact, clamped centre)
# settling to rest with adaptive steps and the rest criterion
# (crates/drape-bench/scenarios/settle-*.toml). Prints, per mesh, how the
# run ended, the steps, Newton iterations (total and per step), cut-back
# steps, wall time and the settled rim height.
#
#   cargo build --release -p drape-cli && scripts/settle-bench.sh
#   MESHES=t3 scripts/settle-bench.sh                 # one mesh only
#   BENDING=1 scripts/settle-bench.sh                 # the drape tester with bending
#                                                     # (settle-bending-*.toml: 2e-5 N m,
#                                                     # no tension-field model, to rest)
#   BENDING=1 PROJECTIONS="never progressive always" scripts/settle-bench.sh
#                                                     # also each Newton of [solver]
#                                                     # projection (issue 30) on the
#                                                     # scenario
#   BENDING=1 BASELINE=/path/to/older/drape scripts/settle-bench.sh
#                                                     # the adaptive run with another
#                                                     # build too (main's, from its
#                                                     # commit in a git worktree)
#   FIXED=1 scripts/settle-bench.sh                   # also the same scenario at fixed
#                                                     # 1 ms steps to t = 2.1 s (no
#                                                     # adaptive keys, no rest)
#   FIXED=1 BASELINE=/path/to/older/drape scripts/settle-bench.sh
#                                                     # that fixed run with another build
#                                                     # too (e.g. release 1's, built from
#                                                     # its commit in a git worktree)
#
# Runs are long (minutes for the fixed steps): run it when nothing else is
# compiling, and compare builds measured in the same hour.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=${DRAPE:-target/release/drape}
meshes=${MESHES:-t3 t6}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
report() { # label, output directory
  python3 - "$1" "$2/summary.json" "$2/history.csv" <<'PY'
import csv, json, sys
label, summary, history = sys.argv[1:4]
s = json.load(open(summary))
rows = list(csv.DictReader(open(history)))[1:]
steps = max(len(rows), 1)
cut = sum(1 for r in rows if float(r["cutbacks"]) > 0)
rim = s["monitors"].get("rim", [float("nan")] * 3)
print(f"{label:28s} {s['status']:9s} t = {s['time']:.4f} s  steps {s['steps']:5d}  "
      f"Newton {s['newton_iterations']:6d} ({s['newton_iterations'] / steps:.2f}/step)  "
      f"cut-back steps {cut:4d} ({100 * cut / steps:.1f} %)  wall {s['wall_seconds']:.1f} s  "
      f"rim z {rim[2]:.5f} m")
print(f"{'':28s} {s['message']}")
PY
}
for m in $meshes; do
  scenario=crates/drape-bench/scenarios/settle-${BENDING:+bending-}$m.toml
  "$drape" run "$scenario" --out "$work/$m" --quiet || true
  report "$m adaptive" "$work/$m"
  if [[ -n "${BASELINE:-}" && -z "${FIXED:-}" ]]; then
    "$BASELINE" run "$scenario" --out "$work/$m-baseline" --quiet || true
    report "$m adaptive (baseline)" "$work/$m-baseline"
  fi
  for p in ${PROJECTIONS:-}; do
    # The scenario with `[solver] projection = p` (it has no [solver]).
    copy="$(dirname "$scenario")/.settle-$m-$p.toml"
    { cat "$scenario"; printf '\n[solver]\nprojection = "%s"\n' "$p"; } > "$copy"
    "$drape" run "$copy" --out "$work/$m-$p" --quiet || true
    rm -f "$copy"
    report "$m adaptive, $p" "$work/$m-$p"
  done
  if [[ -n "${FIXED:-}" ]]; then
    # The same scenario without the adaptive keys: fixed steps to 2.1 s.
    fixed="$(dirname "$scenario")/.settle-$m-fixed.toml"
    grep -v -E '^(adaptive|dt_max|rest) *=' "$scenario" > "$fixed"
    trap 'rm -rf "$work" "$fixed"' EXIT
    "$drape" run "$fixed" --out "$work/$m-fixed" --quiet || true
    report "$m fixed 1 ms" "$work/$m-fixed"
    if [[ -n "${BASELINE:-}" ]]; then
      "$BASELINE" run "$fixed" --out "$work/$m-baseline" --quiet || true
      report "$m fixed 1 ms (baseline)" "$work/$m-baseline"
    fi
    rm -f "$fixed"
  fi
done
