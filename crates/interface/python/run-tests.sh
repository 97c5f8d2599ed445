#!/usr/bin/env bash
# Tests of pendkit's Python package: makes a venv (target/python-venv, or $PENDKIT_PY_VENV),
# installs maturin, numpy, pytest, mypy, python-control, Dask distributed, pygwinc 0.6.2 and
# (on Python 3.11 and later) Finesse 3.0.2 with finesse-ligo 1.0.15
# from PyPI, pip-installs the package from this folder (a build with the `python` profile: thin
# LTO), builds the `pendkit` command line the tests compare with, and runs pytest.
#
#   crates/interface/python/run-tests.sh [pytest arguments...]
#
# PENDKIT_PY_GWINC=0 leaves pygwinc out (its tests are then skipped); PYTHON picks the
# interpreter that makes the venv (default python3, 3.9 or later).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../../.." && pwd)"
target="${CARGO_TARGET_DIR:-$repo/target}"
venv="${PENDKIT_PY_VENV:-$target/python-venv}"

if [ ! -x "$venv/bin/python" ]; then
    "${PYTHON:-python3}" -m venv "$venv"
fi
packages=(maturin numpy pytest mypy control "dask[distributed]" "finesse==3.0.2; python_version >= '3.11'" "finesse-ligo==1.0.15; python_version >= '3.11'")
if [ "${PENDKIT_PY_GWINC:-1}" != 0 ]; then
    packages+=("gwinc==0.6.2")
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check "${packages[@]}"
# the package as a user installs it (pyproject.toml: maturin, profile `python`)
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --force-reinstall \
    --no-deps "$here"
# the reference the tests compare with
(cd "$repo" && cargo build --quiet -p pendkit-cli)
cd "$here"
PENDKIT_CLI="$target/debug/pendkit" "$venv/bin/python" -m pytest tests -q "$@"
