#!/usr/bin/env bash
# The fabric validation of issue 45 (docs/validation.md): drape tests of
# measured fabrics against the laboratory's drape coefficient and folds.
#
#   cargo build --release -p drape-cli && scripts/fabric-tests.sh [SET ...]
#
# SET (default: matsudaira):
#   matsudaira      the four fabrics of Matsudaira et al. 2015
#                   (examples/fabrics/matsudaira2015-*.toml, KES units,
#                   25.4 cm specimen on a 12.7 cm pedestal)
#   matsudaira-iso  the same fabrics on the ISO 9073-9 geometry (30 cm on
#                   18 cm, 15 rings, F 31): the article's diameters are not known
#   matsudaira-hysteresis
#                   the four fabrics with their measured bending hysteresis,
#                   [material.kes] 2HB (Table 1; the files leave it out)
#   matsudaira-stick
#                   the same, the moment held by a stick spring of STICK
#                   (default 4) times the fabric's B instead of the creep
#   library         the six Petrak et al. 2025 files on converged meshes:
#                   each file with [refine] levels = 4 along the folds, the
#                   rim and the contact line, tolerance 0.01
#
# Each fabric is one `drape test` of SPECIMENS (3) specimens, JOBS (2) at a
# time, seed 0; the script prints per fabric the laboratory's DC and nodes,
# the test's mean ± sd, 95 % interval, fold counts, modal folds and the DC
# at them, each specimen's refinement levels and the slowest specimen's
# wall time. Results stay in OUT (default: a temporary directory) when it
# is given. The library takes about an hour on a 2-core machine, each
# Matsudaira geometry 10-20 minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
drape=$(realpath "${DRAPE:-target/release/drape}")
specimens=${SPECIMENS:-3}
jobs=${JOBS:-2}
if [ -n "${OUT:-}" ]; then
  work=$OUT
  mkdir -p "$work"
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi

summary() { # label, lab DC (%), lab nodes, test directory
  python3 - "$@" <<'PY'
import json, sys
label, lab_dc, lab_nodes, out = sys.argv[1:5]
t = json.load(open(f"{out}/test.json"))
if not t["measured"]:
    print(f"{label}: lab {lab_dc} %, {lab_nodes} nodes | no specimen measured (see {out}.log)")
    sys.exit(0)
folds = ", ".join(f"{k} ({v})" for k, v in sorted(t["fold_histogram"].items(), key=lambda kv: int(kv[0])))
lo, hi = t["ci95"] if t.get("ci95") else (float("nan"), float("nan"))
slowest = max(s.get("wall_seconds") or 0.0 for s in t["specimens"])
print(f"{label}: lab {lab_dc} %, {lab_nodes} nodes | drape {100 * t['mean']:.1f} ± {100 * t['sd']:.1f} %, "
      f"95 % [{100 * lo:.1f}, {100 * hi:.1f}], folds {folds}, modal {t['modal_folds']}: "
      f"{100 * t['dc_at_modal_folds']:.1f} %, {t['measured']} of {t['count']} measured, "
      f"slowest specimen {slowest:.0f} s")
for s in t["specimens"]:
    levels = s.get("message", "")
    levels = levels[levels.find("; ") + 2:] if "; " in levels else levels
    dc = s.get("drape_coefficient")
    dc = "-" if dc is None else f"{dc:.4f}"
    crossed = f", {s['crossings']} crossings" if s.get("crossings") else ""
    print(f"  specimen {s['specimen']}: {s['status']}, DC {dc}, "
          f"{s.get('folds')} folds{crossed}, {levels}")
PY
}

test_one() { # label, lab DC, lab nodes, scenario
  local out="$work/$1"
  "$drape" test "$4" --specimens "$specimens" --jobs "$jobs" --out "$out" >"$out.log" 2>&1 || true
  summary "$1" "$2" "$3" "$out"
}

# fabric stem, laboratory DC (%) and nodes (Matsudaira et al. 2015, Table 2)
matsudaira="matsudaira2015-a-cotton-broad 82.9 2
matsudaira2015-b-wool-tropical 49.8 5
matsudaira2015-c-polyester-tropical 50.7 5
matsudaira2015-f-polyester-faille 28.3 7"
# fabric stem, 2HB (gf cm/cm; Matsudaira et al. 2015, Table 1)
hysteresis="matsudaira2015-a-cotton-broad 0.124
matsudaira2015-b-wool-tropical 0.033
matsudaira2015-c-polyester-tropical 0.029
matsudaira2015-f-polyester-faille 0.007"
# fabric stem, laboratory DC (%) (Petrak et al. 2025, Table 5; nodes not given)
library="petrak2025-m1-polyester-twill 22.3
petrak2025-m2-polyester-plain 22.8
petrak2025-m3-wool-polyester-elastane-twill 34.9
petrak2025-m4-polyester-viscose-elastane-twill 28.6
petrak2025-m5-polyester-elastane-plain 44.3
petrak2025-m6-cotton-polyester-elastane-twill 54.9"

for set in "${@:-matsudaira}"; do
  case $set in
    matsudaira)
      while read -r stem dc nodes; do
        test_one "$stem" "$dc" "$nodes" "examples/fabrics/$stem.toml"
      done <<<"$matsudaira" ;;
    matsudaira-iso)
      while read -r stem dc nodes; do
        iso="$work/iso-$stem.toml"
        sed -e 's/^radius = 0\.127 .*/radius = 0.15/' -e 's/^rings = 13 .*/rings = 15/' \
            -e 's/^rings = 26 .*/rings = 31/' \
            -e 's/^radius = 0\.0635 .*/radius = 0.09/' \
            -e 's/at = \[0\.127, 0\.0, 0\.0\]/at = [0.15, 0.0, 0.0]/' \
            "examples/fabrics/$stem.toml" >"$iso"
        test_one "iso-$stem" "$dc" "$nodes" "$iso"
      done <<<"$matsudaira" ;;
    matsudaira-hysteresis)
      while read -r stem dc nodes; do
        hb=$(awk -v s="$stem" '$1 == s { print $2 }' <<<"$hysteresis")
        with="$work/hysteresis-$stem.toml"
        sed -e "s/^\[material.kes\]\$/[material.kes]\n2HB = { warp = $hb, weft = $hb }   # gf cm\/cm/" \
            "examples/fabrics/$stem.toml" >"$with"
        test_one "hysteresis-$stem" "$dc" "$nodes" "$with"
      done <<<"$matsudaira" ;;
    matsudaira-stick)
      # As matsudaira-hysteresis, the frictional moment held by a stick of
      # STICK (default 4) times the fabric's larger KES B
      # (bending_hysteresis_stiffness, N m; 1 gf cm^2/cm = 9.80665e-5 N m).
      while read -r stem dc nodes; do
        hb=$(awk -v s="$stem" '$1 == s { print $2 }' <<<"$hysteresis")
        k=$(awk -v r="${STICK:-4}" -F'[={},]' '/^B = / { b = ($4 + 0 > $6 + 0 ? $4 + 0 : $6 + 0); printf "%.4e", r * b * 9.80665e-5 }' "examples/fabrics/$stem.toml")
        with="$work/stick-$stem.toml"
        sed -e "s/^\[material.kes\]\$/[material.kes]\n2HB = { warp = $hb, weft = $hb }   # gf cm\/cm/" \
            -e "s/^\[material\]\$/[material]\nbending_hysteresis_stiffness = $k   # N m/" \
            "examples/fabrics/$stem.toml" >"$with"
        test_one "stick-$stem" "$dc" "$nodes" "$with"
      done <<<"$matsudaira" ;;
    library)
      while read -r stem dc; do
        converged="$work/converged-$stem.toml"
        cat "examples/fabrics/$stem.toml" - >"$converged" <<'TOML'

[refine]
levels = 4
also = ["rim", "contact"]
where = "folds"
tolerance = 0.01
TOML
        test_one "converged-$stem" "$dc" "?" "$converged"
      done <<<"$library" ;;
    *) echo "unknown set '$set' (matsudaira, matsudaira-iso, matsudaira-hysteresis, matsudaira-stick, library)" >&2; exit 2 ;;
  esac
done
