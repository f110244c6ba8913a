#!/usr/bin/env bash
# The C firmware example (examples/c/) against the Rust firmware: builds the C API's static
# library for thumbv7em-none-eabihf with the firmware's profile (`fw`: opt-level 3, fat LTO) and
# only the variant the example uses, compiles and links the plain-C example with Debian's
# arm-none-eabi-gcc, runs it under `qemu-system-arm -M mps2-an386` (the Rust firmware's board)
# and fails unless it reproduces the state fingerprints of the Rust bins fw-free and
# fw-free-monitor bit for bit. Then counts, with the QEMU plugin scripts/qemu-step-counter.c,
# the instructions of every `absorber_step_f32` call (C API entry to return) against those of
# fw-free's `Sim::step` (the Rust firmware's call of the same `Model::step`), and fails if the
# C wrapper's own instructions (handle checks, dispatch, the report; the plugin's per-function
# profile) exceed 2 % of the step, or the whole difference 5 % (it also carries the static
# library's own inlining of the core, which moves by a few percent either way).
#
# Installs what it needs when missing (Rust target; apt: gcc-arm-none-eabi,
# binutils-arm-none-eabi, qemu-system-arm, gcc). Writes its figures to
# $CARGO_TARGET_DIR/c-example/report.txt.
#
# Usage: scripts/c-example.sh        (from anywhere; honours CARGO_TARGET_DIR)
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
command -v arm-none-eabi-gcc >/dev/null || missing+=(gcc-arm-none-eabi)
command -v arm-none-eabi-nm >/dev/null || missing+=(binutils-arm-none-eabi)
command -v qemu-system-arm >/dev/null || missing+=(qemu-system-arm)
command -v gcc >/dev/null || missing+=(gcc)
if ((${#missing[@]})); then
    sudo=""
    [ "$(id -u)" = 0 ] || sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# --- build ------------------------------------------------------------------------------------
tdir=${CARGO_TARGET_DIR:-$root/target}
export CARGO_TARGET_DIR=$tdir
out=$tdir/c-example
mkdir -p "$out"
# The same flags as .ci/embedded.sh, so the library is built like the measured Rust firmware.
export CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="--remap-path-prefix=${CARGO_HOME:-$HOME/.cargo}=/cargo --remap-path-prefix=$root=/absorber"
cargo build -q -p absorber-ffi --target "$target" --profile fw --config firmware/fw-profile.toml \
    --no-default-features --features free-n3-f32
cargo build -q --release -p absorber-firmware --bin fw-free --bin fw-free-monitor
cargo build -q -p absorber-firmware --target "$target" --profile fw --config firmware/fw-profile.toml --bin fw-free --bin fw-free-monitor
lib=$tdir/$target/fw/libabsorber_ffi.a

cpu=(-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard)
# -ffp-contract=off: no fused multiply-add, so float arithmetic rounds as Rust's does.
cflags=(-std=c11 -O2 -g -Wall -Wextra -Werror -ffreestanding -ffp-contract=off -ffunction-sections -fdata-sections)
arm-none-eabi-gcc "${cpu[@]}" "${cflags[@]}" -Iabsorber-ffi/include -c examples/c/main.c -o "$out/main.o"
arm-none-eabi-gcc "${cpu[@]}" "${cflags[@]}" -c examples/c/startup.c -o "$out/startup.o"
arm-none-eabi-gcc "${cpu[@]}" -nostdlib -nostartfiles -T examples/c/link.ld -Wl,--gc-sections \
    -Wl,-z,noexecstack -o "$out/absorber-c" "$out/startup.o" "$out/main.o" "$lib" -lgcc
gcc -O2 -Wall -Wextra -shared -fPIC -fvisibility=hidden -o "$out/step-counter.so" scripts/qemu-step-counter.c

# --- run and compare --------------------------------------------------------------------------
"$tdir/release/fw-free" >"$out/fw-free.host"
"$tdir/release/fw-free-monitor" >"$out/fw-free-monitor.host"
h_free=$(sed -n 's/^state_hash=//p' "$out/fw-free.host")
h_mon=$(sed -n 's/^state_hash=//p' "$out/fw-free-monitor.host")
qemu() {
    timeout 600 qemu-system-arm -M mps2-an386 -nographic -monitor none \
        -semihosting-config enable=on,target=native "$@"
}
set +e
qemu -kernel "$out/absorber-c" -append "expect=$h_free expect-monitor=$h_mon" >"$out/run.txt" 2>&1
rc=$?
set -e
c_free=$(sed -n 's/^state_hash=//p' "$out/run.txt")
c_mon=$(sed -n 's/^monitor_state_hash=//p' "$out/run.txt")
if [ $rc -ne 0 ] || [ "$c_free" != "$h_free" ] || [ "$c_mon" != "$h_mon" ]; then
    echo "c-example: the C firmware does not reproduce the Rust firmware (exit $rc):"
    echo "  fw-free         $h_free, C $c_free"
    echo "  fw-free-monitor $h_mon, C $c_mon"
    tail -n 5 "$out/run.txt"
    exit 1
fi
echo "c-example: C firmware bit-identical to the Rust firmware (fw-free state_hash=$h_free," \
    "fw-free-monitor state_hash=$h_mon)"

# --- instructions per step --------------------------------------------------------------------
# count <elf> <symbol (nm -C, exact)> <out>: instructions of every call, entry to return address.
count() {
    local elf=$1 sym=$2 counts=$3 entry rets="" site
    arm-none-eabi-nm -C "$elf" >"$counts.nm"
    arm-none-eabi-objdump -d --no-show-raw-insn "$elf" >"$counts.dis"
    entry=$(awk -v s="$sym" '{ n = $0; sub(/^[0-9a-f]+ [A-Za-z] /, "", n) } n == s { print $1 }' "$counts.nm" | sed 's/^0*//')
    [ -n "$entry" ] && [ "$(wc -w <<<"$entry")" = 1 ] || { echo "c-example: symbol '$sym' not found once in $elf"; exit 1; }
    for site in $(awk -v e="$entry" '$2 == "bl" && $3 == e {sub(":", "", $1); print $1}' "$counts.dis"); do
        rets+=$(printf ',ret=0x%x' $((0x$site + 4)))
    done
    [ -n "$rets" ] || { echo "c-example: no call of '$sym' in $elf"; exit 1; }
    qemu -kernel "$elf" -append "$4" -plugin "$out/step-counter.so,entry=0x$entry$rets,out=$counts,prof=$counts.prof" >/dev/null 2>&1
}
rust_elf=$tdir/$target/fw/fw-free
rust_step=$(arm-none-eabi-nm -C "$rust_elf" | sed -n 's/^[0-9a-f]* [Tt] \(<.* as absorber_firmware::sim::Sim>::step\)$/\1/p')
count "$rust_elf" "$rust_step" "$out/rust-step.counts" "expect=$h_free"
count "$out/absorber-c" absorber_step_f32 "$out/c-step.counts" "expect=$h_free expect-monitor=$h_mon"
for elf in "$rust_elf" "$tdir/$target/fw/fw-free-monitor" "$out/absorber-c"; do
    arm-none-eabi-size -A "$elf" | awk '$1 == ".text" {print $2}'
done >"$out/text-sizes"
python3 - "$out" <<'PY'
import bisect, re, sys, pathlib
out = pathlib.Path(sys.argv[1])
rust = [int(x) for x in (out / "rust-step.counts").read_text().split()]
# The C firmware runs the model twice (alone, then with the monitor): 2 × 6667 calls, of which
# the first 6667 are fw-free's run; the profile below covers every call.
c_all = [int(x) for x in (out / "c-step.counts").read_text().split()]
c = c_all[: len(rust)]
assert len(rust) == 6667 and len(c_all) == 2 * 6667, (len(rust), len(c_all))
mr, mc = sum(rust) / len(rust), sum(c) / len(c)
extra = [b - a for a, b in zip(rust, c)]
share = (mc - mr) / mr


def profile(stem, calls):
    """Exclusive instructions per call of each function (the plugin's per-block profile)."""
    syms = sorted(
        (int(f[0], 16) & ~1, f[2])
        for f in (l.split(" ", 2) for l in (out / f"{stem}.nm").read_text().splitlines())
        if len(f) == 3 and f[1] in "tTwW"
    )
    starts = [a for a, _ in syms]
    per = {}
    for line in (out / f"{stem}.prof").read_text().splitlines():
        addr, _, total = line.split()
        i = bisect.bisect_right(starts, int(addr, 16)) - 1
        name = syms[i][1] if i >= 0 else "?"
        name = re.sub(r"::h[0-9a-f]{16}$", "", name)
        per[name] = per.get(name, 0) + int(total) / calls
    return per


prust, pc = profile("rust-step.counts", len(rust)), profile("c-step.counts", len(c_all))
# The wrapper's own instructions: the functions that are not the core, libm or the compiler's
# runtime, i.e. the C API layer itself.
core = re.compile(r"absorber_core::|libm::|compiler_builtins::|^__aeabi|^core::|absorber_firmware::")
own = sum(v for k, v in pc.items() if not core.search(k))
# Where the rest of the difference is: the same core functions compiled into the library.
def short(n):
    return re.sub(r"<[^<>]*>", "", re.sub(r"<[^<>]*>", "", n))[-60:]
same = {}
for k in set(prust) | set(pc):
    if core.search(k) and "absorber_firmware::" not in k:
        same[short(k)] = same.get(short(k), 0) + pc.get(k, 0) - prust.get(k, 0)
top = sorted(same.items(), key=lambda kv: -abs(kv[1]))[:4]
sizes = [int(x) for x in (out / "text-sizes").read_text().split()]
boot = re.findall(r"^# boot stack from reset, (.*) = (\d+) bytes$", (out / "run.txt").read_text(), re.M)
assert len(boot) == 2, boot
text = (
    f"instructions per step, free ball N = 3 f32, profile fw, mean over 6667 steps:\n"
    f"  Rust firmware fw-free, Sim::step       {mr:,.1f} (worst {max(rust):,})\n"
    f"  C example, absorber_step_f32           {mc:,.1f} (worst {max(c):,})\n"
    f"  the C API's own instructions per step  {own:,.1f} ({100 * own / mr:.3f} %)\n"
    f"  difference of the two per step         {mc - mr:+,.1f} ({100 * share:+.3f} %; "
    f"per-step difference min {min(extra):+,}, max {max(extra):+,})\n"
    f"  of which the core compiled into the library, largest per function: "
    + ", ".join(f"{n} {d:+,.1f}" for n, d in top) + "\n"
    f".text of the images: fw-free {sizes[0]:,}, fw-free-monitor {sizes[1]:,}, C example {sizes[2]:,}\n"
    f"boot stack from reset of the C example (model and monitor built in place): "
    + ", ".join(f"{what} {int(b):,} B" for what, b in boot) + "\n"
)
(out / "report.txt").write_text(text)
print(text, end="")
# The wrapper (handle checks, dispatch, the report) must stay below 2 % of a step. The whole
# difference also carries the static library's own compilation of the core: the same source
# inlined and register-allocated otherwise than in the firmware (measured over builds of the
# same source: -0.4 … +3.3 %), bounded at 5 %.
if own / mr > 0.02:
    print("c-example: the C wrapper's own instructions exceed 2 % of the step's")
    sys.exit(1)
if share > 0.05:
    print("c-example: the C example's step costs more than 5 % over the firmware's")
    sys.exit(1)
PY
echo "c-example: done in $((SECONDS - start)) s"
