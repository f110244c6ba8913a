#!/usr/bin/env bash
# Paired, interleaved timing of the full solver against Exudyn (see exudyn-compare.py).
# Installs Exudyn from PyPI into a venv (default $TMPDIR/absorber-exudyn-venv, outside the repository), builds host-sim (release) and
# runs the comparison; extra arguments go to the Python script (--elements, --duration,
# --repeats, --solver, --every).
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${EXUDYN_VENV:-${TMPDIR:-/tmp}/absorber-exudyn-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install --quiet "exudyn==1.13.6" numpy
cargo build --release -p host-sim
exec "$venv/bin/python" scripts/exudyn-compare.py "$@"
