#!/usr/bin/env bash
# Regenerates every measured figure in docs/ and the README from the commands that make them, in
# dependency order (the firmware gain before the firmware counts, the firmware counts before the
# accuracy cost column). A change to the model moves most of them; run this after one.
#
# Usage: scripts/regen-docs.sh [STAGE...]     (default: every stage; `--list` lists them)
#
# Stages and their wall time on 2 cores (release builds of host-sim and absorber-studies assumed
# warm; the studies that write docs/ are the developer tool absorber-studies):
#   gain         firmware/src/estimator_gain.rs (the mast arm's calibrated N = 3 model and gain)   5 s
#   stability    docs/stability.md                                                              10 s
#   validation   docs/validation.md, docs/img/validation-*.png                                  30 s
#   embedded     docs/embedded.md/.json (QEMU exact counts; scripts/embedded-report.sh)          2-5 min
#   cost         docs/accuracy-cost.json (QEMU; scripts/accuracy-cost.sh)                      2-4 min
#   accuracy     docs/accuracy.md, docs/img/accuracy_*.png (references cached in target/)       1 min
#   monitoring   docs/monitoring.md's table, docs/monitoring.json, the mast-arm and lab images,
#                the fatigue images                                                            3 min
#   chaos        docs/chaos.md (600 runs: 5 frequencies, 3 steps, 5 configurations, K = 8)     17 min
#   paper        the README's "What the first command prints" block (`host-sim paper`)           5 s
#
# Printed for pasting (their figures sit inside hand-written prose or need a tool the stage
# cannot install): `fmu` (docs/fmu.md's block, scripts/fmu-test.sh, 3 min), `fleet` (docs/fleet.md,
# the Python fleet study with 64 records on a LocalCluster of 2, 3 min; needs the wheel and
# dask[distributed]), `tuned` (the README's tuned range, scripts/tuned-range.sh, 1 min),
# `sensitivity` (the load-model table of docs/monitoring.md, scripts/lab-sensitivity.sh, 4-10 min).
# Their output goes to $OUT (default target/regen), one file per stage.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-target/regen}
ALL=(gain stability validation embedded cost accuracy monitoring chaos fmu fleet paper tuned sensitivity)
if [[ ${1:-} == --list ]]; then printf '%s\n' "${ALL[@]}"; exit 0; fi
stages=("$@")
[[ ${#stages[@]} -eq 0 ]] && stages=("${ALL[@]}")
for s in "${stages[@]}"; do
  [[ " ${ALL[*]} " == *" $s "* ]] || { echo "unknown stage '$s' (stages: ${ALL[*]})" >&2; exit 2; }
done
mkdir -p "$OUT"
cargo build --release -q -p host-sim -p absorber-studies
bin=target/release/host-sim
studies=target/release/absorber-studies
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

for s in "${stages[@]}"; do
  start=$(date +%s)
  echo "== $s"
  case $s in
    gain) "$studies" firmware-gain ;;
    stability) "$studies" stability ;;
    validation) "$studies" validation ;;
    embedded) scripts/embedded-report.sh ;;
    cost) scripts/accuracy-cost.sh ;;
    accuracy) "$studies" accuracy ;;
    monitoring)
      "$studies" monitoring
      "$bin" estimate --scene scenes/mast-arm.toml --out "$tmp/estimate"
      cp "$tmp/estimate/estimate_stress.png" "$tmp/estimate/estimate_histogram.png" \
        "$tmp/estimate/estimate.json" docs/img/
      "$bin" estimate --scene paper --lab --duration 60 --out "$tmp/lab413"
      cp "$tmp/lab413/lab_stress.png" docs/img/lab_stress.png
      "$bin" fatigue --calibrate-against 16 --out "$tmp/fatigue"
      for f in fatigue.png fatigue.csv; do cp "$tmp/fatigue/$f" "docs/img/${f/fatigue/fatigue_damage_rate}"; done
      cp "$tmp/fatigue/fatigue_calibrated.png" "$tmp/fatigue/fatigue_calibrated.csv" docs/img/
      ;;
    chaos) "$studies" chaos ;; # its defaults are the document's grid, which its header repeats
    fmu) scripts/fmu-test.sh | tee "$OUT/fmu.txt" ;;
    fleet)
      if ! python3 -c "import absorber, dask.distributed" 2>/dev/null; then
        echo "fleet: needs the absorber wheel and dask[distributed] in the active Python" \
          "(pip install ./python 'dask[distributed]')" >&2
        exit 1
      fi
      python3 examples/python/fleet_study.py --records 64 --workers 2 | tee "$OUT/fleet.txt"
      ;;
    paper)
      # The README's fenced block right after the line `<!-- host-sim paper -->`.
      "$bin" paper > "$OUT/paper.txt"
      python3 - "$OUT/paper.txt" <<'PY'
import sys
out = open(sys.argv[1]).read().rstrip("\n")
lines = open("README.md").read().split("\n")
i = lines.index("<!-- host-sim paper -->")
assert lines[i + 1].startswith("```"), "README.md: no fenced block after <!-- host-sim paper -->"
j = lines.index("```", i + 2)
lines[i + 2 : j] = out.split("\n")
open("README.md", "w").write("\n".join(lines))
PY
      ;;
    tuned) HOST_SIM=$bin scripts/tuned-range.sh | tee "$OUT/tuned.txt" ;;
    sensitivity) scripts/lab-sensitivity.sh | tee "$OUT/sensitivity.txt" ;;
  esac
  echo "-- $s: $(($(date +%s) - start)) s"
done
git status --short docs README.md firmware/src/estimator_gain.rs
