#!/usr/bin/env bash
# The Python package on a fresh virtual environment: builds the wheel from python/ (pip runs
# maturin, which builds the pyo3 extension with cargo), installs it with pytest and Dask into a
# new venv, and runs python/tests against the command line (host-sim, built here in release); the
# fleet test runs a small study on a two-worker Dask LocalCluster.
#
# Usage: scripts/python-test.sh      (from anywhere; honours CARGO_TARGET_DIR; needs python3 ≥ 3.10
# with venv and network access to the Python package index, as `pip install` does)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
start=$SECONDS
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target}

if ! python3 -c 'import venv, ensurepip' 2>/dev/null; then
    sudo=""
    [ "$(id -u)" = 0 ] || sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends python3-venv
fi

# The CLI (the reference) and the extension in one invocation: their shared dependencies are then
# built once, with the same features, and the wheel build below reuses them.
cargo build -q --release -p host-sim -p absorber-python
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m venv "$work/venv"
py=$work/venv/bin/python
"$py" -m pip install -q --disable-pip-version-check ./python pytest "dask[distributed]"
# The README's promise, printed beside the CLI's last CSV row.
"$py" -c "import absorber; print('python: last tip_deflection', absorber.run('paper')['tip_deflection'][-1])"
ABSORBER_CLI=$CARGO_TARGET_DIR/release/host-sim "$py" -m pytest -q -p no:cacheprovider python/tests
echo "python: done in $((SECONDS - start)) s"
