#!/usr/bin/env bash
# The lab study's constant-gain baseline under four tip-load models, at three forcing
# frequencies (docs/monitoring.md, "The paper's lab scene"): prints the markdown table.
# Usage: scripts/lab-sensitivity.sh [--duration 60]
set -euo pipefail
cd "$(dirname "$0")/.."
duration=60
if [[ ${1:-} == --duration ]]; then duration=$2; fi
cargo build --release -q -p host-sim
bin=target/release/host-sim
echo "| forcing | load model: σ per sample, τ | ball left out: RMS error, damage ratio | control (ball locked in truth and model) |"
echo "|---|---|---:|---:|"
for f in 3.70 4.05 4.13; do
    for model in "4e-3 5" "1.2e-3 5" "4e-3 20" "1.2e-3 20"; do
        read -r step time <<<"$model"
        "$bin" estimate --scene paper --lab --duration "$duration" --frequency "$f" \
            --load-step "$step" --load-time "$time" --json |
            python3 -c '
import json, sys
r = json.load(sys.stdin)
cells = " | ".join("%.1f %%, %.2f" % (e["stress_rms_error_pct"], e["damage_ratio"])
                  for e in r["estimators"] if e["estimator"] == "constant-gain")
print("| %s Hz | %s N, %s s | %s |" % (sys.argv[1], sys.argv[2], sys.argv[3], cells))
' "$f" "$step" "$time"
    done
done
