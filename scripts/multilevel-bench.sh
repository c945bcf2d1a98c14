#!/usr/bin/env bash
# The multilevel benchmark of issue 43: the settle benchmark's fabric
# (E = 2 MPa, 0.6 mm, B = 2e-5 N m) on the generated disc, settled
# quasi-statically (centre held, weight in 20 static increments) — once
# uniformly on 60 rings (crates/drape-bench/scenarios/quasi-static-60.toml,
# 21,600 T3) and once on 15 rings refined twice along the folds
# (multilevel-15-folds.toml), and four times along the folds, the rim and
# the contact line (multilevel-15-folds-rim.toml) — side by side in one
# run of this script.
# Prints each run's wall time, Newton iterations and drape coefficient,
# the multilevel run's level-to-level changes, its distance to the
# uniform value and the wall-time ratio (the issue asks within 0.01, at
# most 1/5).
#
#   cargo build --release -p drape-cli && scripts/multilevel-bench.sh
#   UNIFORM=0 scripts/multilevel-bench.sh      # the multilevel run alone
#   EXTRA="path/a.toml path/b.toml" scripts/multilevel-bench.sh
#                                              # more [refine] scenarios, reported alike
#
# The uniform run takes many minutes (about 1 s per Newton iteration at
# 33,000 unknowns on this 2-core machine): run it when nothing else is
# compiling.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=${DRAPE:-target/release/drape}
scenarios=crates/drape-bench/scenarios
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
run() { # label, scenario -> prints the summary's figures
  local out="$work/$1"
  "$drape" run "$2" --out "$out" --quiet || true
  python3 - "$1" "$out" "$drape" <<'PY'
import json, subprocess, sys
label, out, DRAPE = sys.argv[1], sys.argv[2], sys.argv[3]
s = json.load(open(f"{out}/summary.json"))
print(f"{label}: {s['status']}, {s['elements']} T3, {s['steps']} steps, "
      f"{s['newton_iterations']} Newton iterations, wall {s['wall_seconds']:.1f} s")
levels = s.get("levels", [])
previous = None
for k, l in enumerate(levels):
    dc = l.get("drape_coefficient")
    change = "" if previous is None or dc is None else f", change {dc - previous:+.4f}"
    print(f"  level {k}: {l['elements']} T3, {l['newton_iterations']} iterations, "
          f"{l['wall_seconds']:.1f} s, DC {dc:.4f}, {l.get('folds')} folds{change}")
    previous = dc
if not levels:
    m = json.loads(subprocess.run([DRAPE, "measure", out],
                                  capture_output=True, text=True).stdout or "{}")
    dc = m.get("drape_coefficient")
    print(f"  DC {dc:.4f}, {m.get('folds')} folds" if dc is not None else "  not measured")
    levels = [{"drape_coefficient": dc}]
json.dump({"dc": levels[-1].get("drape_coefficient"), "wall": s["wall_seconds"]},
          open(f"{out}.result", "w"))
PY
}
labels="multilevel multilevel-rim"
run multilevel "$scenarios/multilevel-15-folds.toml"
run multilevel-rim "$scenarios/multilevel-15-folds-rim.toml"
for extra in ${EXTRA:-}; do
  run "$(basename "$extra" .toml)" "$extra"
  labels="$labels $(basename "$extra" .toml)"
done
if [ "${UNIFORM:-1}" = 1 ]; then
  run uniform-60 "$scenarios/quasi-static-60.toml"
  python3 - "$work" $labels <<'PY'
import json, sys
work, labels = sys.argv[1], sys.argv[2:]
u = json.load(open(f"{work}/uniform-60.result"))
for label in labels:
    m = json.load(open(f"{work}/{label}.result"))
    print(f"{label} against uniform 60 rings: DC {m['dc']:.4f} against {u['dc']:.4f} "
          f"(difference {m['dc'] - u['dc']:+.4f}), wall {m['wall']:.1f} s against {u['wall']:.1f} s "
          f"(ratio {m['wall'] / u['wall']:.3f})")
PY
fi
