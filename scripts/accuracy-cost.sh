#!/usr/bin/env bash
# Exact cost of every configuration of docs/accuracy.md on the Cortex-M4F: instructions per step
# of the paper scene (free ball, 4.13 Hz, 10 s), counted by the QEMU TCG plugin
# (scripts/qemu-step-counter.c) on `fw-cost` (absorber_firmware::cost), which runs the
# configuration given as arguments. Each QEMU run must reproduce the host run of the same bin
# bit for bit (state_hash). Deterministic: rerunning gives the same numbers.
#
# Writes docs/accuracy-cost.json: { "<label>": { "args": …, "steps": …, "failed": …,
# "instructions_per_step": <mean>, "worst": <max>, "state_hash": … }, … } for the
# configurations `absorber-studies accuracy --firmware-configs` lists; `absorber-studies accuracy` reads it for
# its cost column (instructions per simulated second = instructions per step / h).
#
# Usage: scripts/accuracy-cost.sh   (needs what .ci/embedded.sh installs; ~1 min per 10 configs)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
target=thumbv7em-none-eabihf
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target}
tdir=$CARGO_TARGET_DIR
work=$tdir/accuracy-cost
mkdir -p "$work"
for tool in qemu-system-arm arm-none-eabi-nm arm-none-eabi-objdump gcc python3; do
    command -v "$tool" >/dev/null || { echo "accuracy-cost: $tool missing (run .ci/embedded.sh first)"; exit 1; }
done

export CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="--remap-path-prefix=${CARGO_HOME:-$HOME/.cargo}=/cargo --remap-path-prefix=$root=/absorber"
cargo build -q --release -p absorber-firmware --bin fw-cost
cargo build -q --release -p absorber-studies
cargo build -q -p absorber-firmware --target "$target" --profile fw --config firmware/fw-profile.toml --bin fw-cost
gcc -O2 -Wall -Wextra -shared -fPIC -fvisibility=hidden -o "$work/step-counter.so" scripts/qemu-step-counter.c

elf=$tdir/$target/fw/fw-cost
arm-none-eabi-nm -C "$elf" >"$work/fw-cost.nm"
arm-none-eabi-objdump -d --no-show-raw-insn "$elf" >"$work/fw-cost.dis"
entry=$(awk '$0 ~ / absorber_firmware::cost::cost_step$/ {print "0x" $1}' "$work/fw-cost.nm" | sed 's/^0x0*/0x/')
[ "$(wc -w <<<"$entry")" = 1 ] || { echo "accuracy-cost: expected one cost_step symbol, got '$entry'"; exit 1; }
rets=""
for site in $(awk -v e="${entry#0x}" '$2 == "bl" && $3 == e {sub(":", "", $1); print $1}' "$work/fw-cost.dis"); do
    rets+=$(printf ',ret=0x%x' $((0x$site + 4)))
done
[ -n "$rets" ] || { echo "accuracy-cost: no call of cost_step"; exit 1; }

"$tdir/release/absorber-studies" accuracy --firmware-configs >"$work/configs.tsv"
: >"$work/results.tsv"
while IFS=$'\t' read -r label args; do
    [ -n "$label" ] || continue
    # shellcheck disable=SC2086
    host=$("$tdir/release/fw-cost" $args | sed -n 's/^steps=//p')
    qemu_out=$(timeout 1200 qemu-system-arm -M mps2-an386 -nographic -monitor none \
        -semihosting-config enable=on,target=native -kernel "$elf" -append "$args" \
        -plugin "$work/step-counter.so,entry=$entry$rets,out=$work/one.counts" | sed -n 's/^steps=//p')
    if [ "$host" != "$qemu_out" ]; then
        echo "accuracy-cost: $label: QEMU differs from the host: '$qemu_out' vs '$host'"
        exit 1
    fi
    printf '%s\t%s\t%s\t%s\n' "$label" "$args" "$host" "$(tr '\n' ' ' <"$work/one.counts")" >>"$work/results.tsv"
    echo "accuracy-cost: $label: $host"
done <"$work/configs.tsv"

python3 - "$work/results.tsv" docs/accuracy-cost.json <<'PY'
import json, sys
out = {}
for line in open(sys.argv[1]):
    label, args, summary, counts = line.rstrip("\n").split("\t")
    fields = dict(kv.split("=") for kv in summary.split()[1:])
    c = [int(x) for x in counts.split()]
    out[label] = {
        "args": args,
        "steps": int(summary.split()[0]),
        "failed": int(fields["failed"]),
        "iterations": int(fields["iterations"]),
        "instructions_per_step": round(sum(c) / len(c), 1),
        "worst": max(c),
        "state_hash": fields["state_hash"],
    }
json.dump(out, open(sys.argv[2], "w"), indent=1, sort_keys=True)
open(sys.argv[2], "a").write("\n")
print(f"accuracy-cost: wrote {sys.argv[2]} ({len(out)} configurations)")
PY
