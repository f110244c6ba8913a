#!/usr/bin/env bash
# Regenerates the measured sections of docs/embedded.md: instructions per `step` (exact, QEMU
# TCG plugin), a cycle/µs estimate, flash and RAM of the model, the stack high-water mark of
# `step`, and the panic/heap check of the step path, for the free-ball (full and modified
# Newton, and with the on-device monitor, whose `Monitor::record` is also counted on its own),
# beam-only and locked-ball scenes.
#
# Writes docs/embedded.md's generated section and docs/embedded.json (per scene: mean and worst
# instructions per step, static stack bound, flash at opt 3 and s), then checks them against
# firmware/budget.toml. With --check (CI) the docs are left alone: the figures go to the target
# directory and only the budget check counts.
#
# Usage: scripts/embedded-report.sh [--check]   (needs what .ci/embedded.sh installs, plus gcc and python3)
set -euo pipefail
check_only=0
[ "${1:-}" = "--check" ] && check_only=1
cd "$(dirname "$0")/.."
root=$PWD
target=thumbv7em-none-eabihf
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target}
tdir=$CARGO_TARGET_DIR
work=$tdir/embedded-report
mkdir -p "$work"

for tool in qemu-system-arm arm-none-eabi-size arm-none-eabi-nm arm-none-eabi-objdump gcc python3; do
    command -v "$tool" >/dev/null || { echo "embedded-report: $tool missing (run .ci/embedded.sh first)"; exit 1; }
done

# Same flags as .ci/embedded.sh, so the measured binaries are the tested ones.
export CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="--remap-path-prefix=${CARGO_HOME:-$HOME/.cargo}=/cargo --remap-path-prefix=$root=/absorber"
cargo build -q --release -p absorber-firmware
for profile in fw fw-size; do
    cargo build -q -p absorber-firmware --target "$target" --profile "$profile" --config firmware/fw-profile.toml
done
gcc -O2 -Wall -Wextra -shared -fPIC -fvisibility=hidden -o "$work/step-counter.so" scripts/qemu-step-counter.c

qemu() {
    timeout 600 qemu-system-arm -M mps2-an386 -nographic -monitor none \
        -semihosting-config enable=on,target=native "$@"
}

# count_calls <elf> <stem> <hash> <nm -C pattern of the function> <suffix>: runs the firmware
# under the plugin, counting the instructions of every call of the one function whose demangled
# name matches, from its entry to the return address of any of its `bl` call sites.
count_calls() {
    local elf=$1 stem=$2 hash=$3 pattern=$4 sfx=$5 entry rets site
    entry=$(awk -v p="$pattern" '$0 ~ p {print "0x" $1}' "$stem.nm" | sed 's/^0x0*/0x/')
    [ -n "$entry" ] || { echo "embedded-report: no symbol matching '$pattern' in $elf"; exit 1; }
    [ "$(wc -w <<<"$entry")" = 1 ] || { echo "embedded-report: several symbols match '$pattern' in $elf"; exit 1; }
    rets=""
    for site in $(awk -v e="${entry#0x}" '$2 == "bl" && $3 == e {sub(":", "", $1); print $1}' "$stem.dis"); do
        rets+=$(printf ',ret=0x%x' $((0x$site + 4)))   # bl is a 32-bit instruction
    done
    [ -n "$rets" ] || { echo "embedded-report: no call of '$pattern' in $elf"; exit 1; }
    echo "$entry" >"$stem$sfx.entry"
    qemu -kernel "$elf" -append "expect=$hash" \
        -plugin "$work/step-counter.so,entry=$entry$rets,out=$stem$sfx.counts,prof=$stem$sfx.prof" >"$stem$sfx.qemu"
}

for profile in fw fw-size; do
    for scene in free free-rolling free-flight free-modified free-step-end free-flight-step-end free-monitor free-n6 beam locked estimator empty; do
        elf=$tdir/$target/$profile/fw-$scene
        stem=$work/$profile-$scene
        "$tdir/release/fw-$scene" >"$stem.host"
        hash=$(sed -n 's/^state_hash=//p' "$stem.host")
        arm-none-eabi-nm -C "$elf" >"$stem.nm"
        arm-none-eabi-size -A "$elf" >"$stem.size"
        [ "$scene" = empty ] && continue
        arm-none-eabi-objdump -d --no-show-raw-insn "$elf" >"$stem.dis"
        # Instructions of every call of `Sim::step` -> $stem.{entry,counts,prof,qemu}.
        count_calls "$elf" "$stem" "$hash" ' as absorber_firmware::Sim>::step$' ""
        # The monitor's share of the step, counted on its own -> $stem.record.{entry,counts,prof,qemu}.
        if [ "$scene" = free-monitor ]; then
            count_calls "$elf" "$stem" "$hash" ' absorber_firmware::monitor_record$' .record
        fi
        qemu -kernel "$elf" -append "expect=$hash stack" >"$stem.stack"
    done
done

if [ $check_only = 1 ]; then
    cp docs/embedded.md "$work/embedded.md"
    python3 scripts/embedded-report.py "$work" "$work/embedded.md" "$work/embedded.json"
    python3 scripts/embedded-budget.py "$work/embedded.json"
else
    python3 scripts/embedded-report.py "$work" docs/embedded.md docs/embedded.json
    echo "embedded-report: docs/embedded.md and docs/embedded.json updated"
    python3 scripts/embedded-budget.py docs/embedded.json
fi
