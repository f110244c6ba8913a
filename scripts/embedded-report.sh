#!/usr/bin/env bash
# Regenerates the measured sections of docs/embedded.md and docs/embedded.json: instructions per
# `step` (exact, QEMU TCG plugin) with the expensive operations counted per step (assembly,
# factorization, pivoting fallback, residual, back-substitution), the static work bound of each
# bin (its work cap times the measured cost of a work unit, plus the step's other code), the
# stress set (scripts: firmware/src/stress.rs) run under QEMU bit for bit against the host, a
# cycle/µs estimate, flash and RAM of the model, the stack of `step` (static bound and
# high-water) and of the boot (from reset to the end of the scene's construction), and the
# panic/heap check of the step path (with `fw-planted`, whose planted panic it must find).
#
# Writes docs/embedded.md's generated section and docs/embedded.json, then checks them against
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
rm -rf "$work"
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

# plugin_args <stem> <nm -C pattern> [op patterns...]: the plugin's entry=/ret= of the counted
# function and one op=<entry>/<ret>… per symbol matching each op pattern (every instance).
plugin_args() {
    python3 scripts/embedded-report.py --plugin-args "$@"
}

# count <elf> <stem> <args> <suffix> <plugin args>: one QEMU run under the plugin.
count() {
    local elf=$1 stem=$2 args=$3 sfx=$4 pargs=$5
    qemu -kernel "$elf" -append "$args" \
        -plugin "$work/step-counter.so,$pargs,out=$stem$sfx.counts,prof=$stem$sfx.prof" >"$stem$sfx.qemu"
}

# The operations the work cap counts (their instructions per call, per step).
ops=(' absorber_core::step::system::System<T,S,_,_>::residual_and_jacobian$'
    ' absorber_core::step::linalg::BandMatrix<T,_>::factor$'
    '::pivot_fallback$'
    ' absorber_core::step::system::System<T,S,_,_>::residual$'
    ' absorber_core::step::newton::Workspace<T,_>::solve$')
step=' as absorber_firmware::sim::Sim>::step$'
scenes=(free free-rolling free-flight free-modified free-monitor free-n6 beam locked estimator monitor-loop)
for profile in fw fw-size; do
    for scene in "${scenes[@]}" empty planted; do
        elf=$tdir/$target/$profile/fw-$scene
        stem=$work/$profile-$scene
        arm-none-eabi-nm -C "$elf" >"$stem.nm"
        arm-none-eabi-size -A "$elf" >"$stem.size"
        [ "$scene" = empty ] && continue
        arm-none-eabi-objdump -d --no-show-raw-insn "$elf" >"$stem.dis"
        [ "$scene" = planted ] && continue
        "$tdir/release/fw-$scene" >"$stem.host"
        hash=$(sed -n 's/^state_hash=//p' "$stem.host")
        echo "$profile-$scene" >&2
        if [ "$profile" = fw ]; then
            count "$elf" "$stem" "expect=$hash" "" "$(plugin_args "$stem" "$step" "${ops[@]}")"
        else
            count "$elf" "$stem" "expect=$hash" "" "$(plugin_args "$stem" "$step")"
        fi
        # The monitor's share of the step, counted on its own -> $stem.record.{counts,prof,qemu}.
        if [ "$scene" = free-monitor ]; then
            count "$elf" "$stem" "expect=$hash" .record "$(plugin_args "$stem" ' absorber_firmware::monitored::monitor_record$')"
        fi
        qemu -kernel "$elf" -append "expect=$hash stack" >"$stem.stack"
    done
done

# The stress set (profile fw): every scene on the free ball, three on every other bin (six on the
# estimator). Each run must reproduce the host's fingerprint (the firmware exits 0 only then).
python3 scripts/embedded-report.py --stress-list >"$work/stress.tsv"
while IFS=$'\t' read -r key scene stress; do
    stem=$work/stress-$key
    "$tdir/release/fw-$scene" "stress=$stress" >"$stem.host"
    hash=$(sed -n 's/^state_hash=//p' "$stem.host")
    echo "stress $key" >&2
    count "$tdir/$target/fw/fw-$scene" "$stem" "expect=$hash stress=$stress" "" \
        "$(plugin_args "$work/fw-$scene" "$step" "${ops[@]}")"
done <"$work/stress.tsv"

if [ $check_only = 1 ]; then
    cp docs/embedded.md "$work/embedded.md"
    python3 scripts/embedded-report.py "$work" "$work/embedded.md" "$work/embedded.json"
    python3 scripts/embedded-budget.py "$work/embedded.json"
else
    python3 scripts/embedded-report.py "$work" docs/embedded.md docs/embedded.json
    echo "embedded-report: docs/embedded.md and docs/embedded.json updated"
    python3 scripts/embedded-budget.py docs/embedded.json
fi
