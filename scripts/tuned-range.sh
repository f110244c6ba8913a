#!/usr/bin/env bash
# The README's tuned result as a range: the tuned scene (scenes/tuned.toml, 4.13 Hz, 60 s) with
# the track radius R over 48.0-49.6 mm, an ensemble of K runs at each R (`run --ensemble`), the
# steady tip amplitude and tip RMS (t >= 20 s) as mean +- sd (min-max); then the locked ball.
# Usage: scripts/tuned-range.sh [K] (default 8). Needs a release build of host-sim.
set -euo pipefail
cd "$(dirname "$0")/.."
K=${1:-8}
BIN=${HOST_SIM:-target/release/host-sim}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-8s %-34s %-34s\n' "R [mm]" "steady tip amplitude [mm]" "tip RMS [mm]"
for r in 48.0 48.2 48.4 48.6 48.8 48.819008 49.0 49.2 49.4 49.6; do
  m=$(python3 -c "print($r / 1000)")
  sed "s/^track_radius = .*/track_radius = $m/" scenes/tuned.toml > "$tmp/r.toml"
  "$BIN" run --scene "$tmp/r.toml" --ensemble "$K" --no-plots --json --out "$tmp/out" 2>/dev/null |
    python3 -c "
import json, sys
s = json.load(sys.stdin)['summary']
def f(v):
    if isinstance(v, dict):
        return '%.2f ± %.2f (%.2f–%.2f)' % tuple(1e3 * v[k] for k in ('mean', 'sd', 'min', 'max'))
    return '%.2f' % (1e3 * v)
print('%-8s %-34s %-34s' % ('$r', f(s['tip_amplitude_steady']), f(s['tip_rms_steady'])))
"
done
"$BIN" run --scene scenes/tuned.toml --kind locked --no-plots --json --out "$tmp/out" 2>/dev/null |
  python3 -c "
import json, sys
s = json.load(sys.stdin)['summary']
print('locked   %.2f                               %.2f' % (1e3 * s['tip_amplitude_steady'], 1e3 * s['tip_rms_steady']))
"
