#!/usr/bin/env bash
# The FMUs in CI: builds host-sim (and with it the FMU's shared library) and the C API,
# packages the paper scene as an FMI 3.0 and an FMI 2.0 co-simulation FMU with `host-sim fmu`,
# installs FMPy into a fresh virtual environment and runs scripts/fmu-check.py (validation,
# FMPy simulation = `host-sim run` to the CSV's printed digits, state save/restore bit for bit,
# refused bad input), then the docs' example (examples/fmu/simulate.py: the chaotic free-ball
# figure with its ensemble spread) and host-sim's run and ensemble of it. Last, the step's cost
# through the FMU against the C API: examples/fmu/overhead.c (dlopen of the FMU's library with
# the standard's function types; the C API linked statically) under valgrind, instructions of
# 2000 steps minus those of none, per step; fails above 5 % more through the FMU.
#
# Usage: scripts/fmu-test.sh        (from anywhere; honours CARGO_TARGET_DIR; needs python3 with
# venv, gcc and valgrind, installed with apt when missing, and the Python package index)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
start=$SECONDS
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target}

missing=()
python3 -c 'import venv, ensurepip' 2>/dev/null || missing+=(python3-venv)
command -v gcc >/dev/null || missing+=(gcc)
command -v valgrind >/dev/null || missing+=(valgrind)
if ((${#missing[@]})); then
    sudo=""
    [ "$(id -u)" = 0 ] || sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# host-sim and, as its dependency, the FMU's cdylib (built with the same packages as
# scripts/python-test.sh, so that CI builds them once); the C API's static library for the host.
cargo build -q --release -p host-sim -p absorber-python
cargo build -q --release -p absorber-ffi
hs=$CARGO_TARGET_DIR/release/host-sim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "fmu: packaging the paper scene"
"$hs" fmu --scene paper --fmi-version 3 --out "$work/absorber3.fmu"
"$hs" fmu --scene paper --fmi-version 2 --out "$work/absorber2.fmu"
"$hs" run --scene paper --no-plots --out "$work/run" >/dev/null

python3 -m venv "$work/venv"
py=$work/venv/bin/python
"$py" -m pip install -q --disable-pip-version-check fmpy numpy
"$py" scripts/fmu-check.py --fmu3 "$work/absorber3.fmu" --fmu2 "$work/absorber2.fmu" \
    --csv "$work/run/paper.csv" --amplitude 0.5e-3 --frequency 4.13
echo "fmu: the docs' FMPy example"
"$py" examples/fmu/simulate.py "$work/absorber3.fmu"
# The same chaotic figure from host-sim (the FMU's model, f64): its own run and an ensemble
# from perturbed initial ball states, to read the example's figures against.
echo "fmu: host-sim run --scene paper --ensemble 8 (tip amplitude: member 0, then the ensemble)"
"$hs" run --scene paper --no-plots --out "$work/run1" | grep '^tip amplitude'
"$hs" run --scene paper --ensemble 8 --no-plots --out "$work/ens" | grep '^tip amplitude'

echo "fmu: step overhead over the C API (instructions under valgrind)"
gcc -std=c11 -O2 -Wall -Wextra -Werror -Iabsorber-ffi/include -Iabsorber-fmu/include/fmi \
    examples/fmu/overhead.c "$CARGO_TARGET_DIR/release/libabsorber_ffi.a" \
    -ldl -lm -lpthread -o "$work/overhead"
"$py" -m zipfile -e "$work/absorber3.fmu" "$work/x3"
token=$("$py" -c "import sys; from fmpy import read_model_description as r; print(r(sys.argv[1]).guid)" "$work/absorber3.fmu")
lib=$work/x3/binaries/x86_64-linux/absorber.so
count() { valgrind --tool=callgrind --callgrind-out-file=/dev/null "$@" 2>&1 >/dev/null | sed -n 's/.*Collected : //p'; }
n=2000
"$py" - "$n" "$(count "$work/overhead" capi 0)" "$(count "$work/overhead" capi $n)" \
    "$(count "$work/overhead" fmu 0 "$lib" "$token" "$work/x3/resources/")" \
    "$(count "$work/overhead" fmu $n "$lib" "$token" "$work/x3/resources/")" \
    "$(count "$work/overhead" capi 0 read)" "$(count "$work/overhead" capi $n read)" \
    "$(count "$work/overhead" fmu 0 "$lib" "$token" "$work/x3/resources/" read)" \
    "$(count "$work/overhead" fmu $n "$lib" "$token" "$work/x3/resources/" read)" \
    "$(count "$work/overhead" fmu 0 "$lib" "$token" "$work/x3/resources/" load)" \
    "$(count "$work/overhead" fmu $n "$lib" "$token" "$work/x3/resources/" load)" <<'EOF'
import sys
n, c0, cn, f0, fn, rc0, rcn, rf0, rfn, l0, ln = (int(x) for x in sys.argv[1:])
capi, fmu = (cn - c0) / n, (fn - f0) / n
rcapi, rfmu = (rcn - rc0) / n, (rfn - rf0) / n
print(f"step (input + step + monitor), instructions per step over {n} steps of the paper scene (f64):")
print(f"  C API {capi:.0f}, FMU {fmu:.0f}: FMU overhead {100 * (fmu / capi - 1):+.2f} %")
print(f"  with the outputs read every step: C API {rcapi:.0f}, FMU {rfmu:.0f}: {100 * (rfmu / rcapi - 1):+.2f} %")
print(f"  FMU with a tip load (the loaded scene; no C API counterpart): {(ln - l0) / n:.0f}, {100 * ((ln - l0) / n / capi - 1):+.2f} % over the C API without")
if fmu > 1.05 * capi:
    sys.exit("FAILED: the FMU's step costs more than 5 % over the C API's")
EOF
echo "fmu: done in $((SECONDS - start)) s"
