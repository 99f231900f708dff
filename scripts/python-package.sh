#!/usr/bin/env bash
# Builds the Python package's wheel with maturin (crates/python), installs it in a fresh
# virtual environment with the test requirements (numpy, pytest, and the peers of the
# worked example: SALib, OpenTURNS; versions pinned in crates/python/requirements-*.txt),
# and runs crates/python/tests against this checkout's rvtol binary.
#
# Usage: scripts/python-package.sh   (needs python3 with venv and pip; PyPI reachable)
set -euo pipefail
cd "$(dirname "$0")/.."
started=$(date +%s)
work=$(mktemp -d /tmp/rvtol-python.XXXXXX)
trap 'rm -rf "$work"' EXIT

python3 -m venv "$work/build"
"$work/build/bin/pip" install -q --disable-pip-version-check -r crates/python/requirements-build.txt
"$work/build/bin/maturin" build --release --locked --quiet -m crates/python/Cargo.toml -o "$work/wheels"
# The wheel is tagged for any x86-64 CPU: its module must hold no instruction beyond the
# baseline outside the dependencies' run-time dispatched functions.
python3 scripts/check-baseline.py "$work"/wheels/rvtol-*.whl

python3 -m venv "$work/test"
"$work/test/bin/pip" install -q --disable-pip-version-check "$work"/wheels/rvtol-*.whl \
    -r crates/python/requirements-test.txt

cargo build --release --locked -q -p rvtol --bin rvtol
RVTOL_CLI=$PWD/target/release/rvtol "$work/test/bin/python" -m pytest -q -p no:cacheprovider \
    crates/python/tests
echo "python-package: wheel built, installed and tested in $(( $(date +%s) - started )) s"
