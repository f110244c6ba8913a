#!/usr/bin/env bash
# The core on a Cortex-M4F. Installs what it needs (quick when present), builds the firmware
# (profile `fw`: opt-level 3, fat LTO) for thumbv7em-none-eabihf, runs every firmware bin under
# `qemu-system-arm -M mps2-an386` (each scene's paper run; `fw-cost` with its default
# configuration) and fails unless every run reproduces the host f32 run of the same source bit
# for bit (the firmware checks the host's state fingerprint, which covers every step's full state,
# and exits 0 only on a match; this script also diffs the printed time histories). Then
# scripts/embedded-report.sh --check measures the budgets of firmware/budget.toml afresh: the
# instructions per step, the static work bound of every bin, the stress set (again bit for bit
# under QEMU), boot RAM, stack, flash and the panic check (which must find fw-planted's panic).
#
# Usage: .ci/embedded.sh            (from anywhere; uses $CARGO_TARGET_DIR or ./target)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
start=$SECONDS
target=thumbv7em-none-eabihf

# --- tools ------------------------------------------------------------------------------------
if ! rustup target list --installed | grep -qx "$target"; then
    rustup target add "$target"
fi
missing=()
command -v qemu-system-arm >/dev/null || missing+=(qemu-system-arm)
command -v arm-none-eabi-size >/dev/null || missing+=(binutils-arm-none-eabi)
command -v gcc >/dev/null || missing+=(gcc)
command -v python3 >/dev/null || missing+=(python3)
if ((${#missing[@]})); then
    sudo=""
    [ "$(id -u)" = 0 ] || sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# --- build ------------------------------------------------------------------------------------
tdir=${CARGO_TARGET_DIR:-$root/target}
export CARGO_TARGET_DIR=$tdir
# Registry and checkout paths end up in panic locations: remap them so sizes are reproducible.
export CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="--remap-path-prefix=${CARGO_HOME:-$HOME/.cargo}=/cargo --remap-path-prefix=$root=/absorber"
cargo build -q --release -p absorber-firmware
cargo build -q -p absorber-firmware --target "$target" --profile fw --config firmware/fw-profile.toml

# --- run --------------------------------------------------------------------------------------
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail=0
# Every bin but fw-planted (never run: its planted panic is only analysed).
for scene in free free-rolling free-flight free-modified free-monitor free-n6 beam locked estimator monitor-loop cost empty; do
    "$tdir/release/fw-$scene" >"$out/$scene.host"
    hash=$(sed -n 's/^\(.* \)\{0,1\}state_hash=//p' "$out/$scene.host")
    # fw-cost takes its configuration as arguments (none: its default) and checks no
    # fingerprint itself: the diff below is its check.
    args="expect=$hash"
    [ "$scene" = cost ] && args=""
    set +e
    timeout 300 qemu-system-arm -M mps2-an386 -nographic -monitor none \
        -semihosting-config enable=on,target=native \
        -kernel "$tdir/$target/fw/fw-$scene" -append "$args" >"$out/$scene.qemu" 2>&1
    rc=$?
    set -e
    if [ $rc -ne 0 ]; then
        echo "embedded: fw-$scene exited $rc under QEMU (0 = matches the host bit for bit)"
        tail -n 5 "$out/$scene.qemu"
        fail=1
    elif ! diff <(cat "$out/$scene.host") <(grep -v '^#' "$out/$scene.qemu") >"$out/$scene.diff"; then
        echo "embedded: fw-$scene output differs from the host reference:"
        head -n 20 "$out/$scene.diff"
        fail=1
    else
        echo "embedded: fw-$scene bit-identical to the host ($(grep -c '^k=' "$out/$scene.host") samples," \
            "$(sed -n 's/^impacts=\([0-9]*\) stuck=[0-9]* iterations=\([0-9]*\) .*/\1 impacts, \2 Newton iterations/p' "$out/$scene.host"), state_hash=$hash)"
    fi
done
[ $fail = 0 ] || exit $fail
# Budgets: exact instruction counts per step, static work bound, stress set, boot RAM, static
# stack bound, flash, no panic path (firmware/budget.toml; measured afresh, docs not touched).
scripts/embedded-report.sh --check || fail=1
echo "embedded: done in $((SECONDS - start)) s"
exit $fail
