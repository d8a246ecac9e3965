#!/usr/bin/env bash
# CI of the Python package (python/): installs it with pip into a fresh virtual environment,
# as a user would (`pip install "./python[ray,test]"`: maturin, pyo3 and numpy from PyPI and
# crates.io), lints its crate, and runs its pytest suite (python/tests), the Ray Data test
# included. Compares with the command-line binary $BVSEG_CLI (default target/release/bvseg,
# which the "tests" check of .ci/run has built); under CI a missing binary fails the suite.
#
#   bash python/ci.sh
#
# Environment: BVSEG_PY_VENV (where to make the venv; default a temporary directory, removed
# at the end), CARGO_TARGET_DIR (default target/python, beside the workspace's builds).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
start=$SECONDS

if [ -n "${BVSEG_PY_VENV:-}" ]; then
    venv=$BVSEG_PY_VENV
    rm -rf "$venv"
else
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    venv="$tmp/venv"
fi
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target/python}"
export BVSEG_CLI="${BVSEG_CLI:-$root/target/release/bvseg}"

echo "+ python3 -m venv $venv"
python3 -m venv "$venv"
py="$venv/bin/python"
"$py" --version
echo "+ pip install ./python[ray,test]"
"$py" -m pip install --quiet --disable-pip-version-check "./python[ray,test]"
"$py" -m pip list --disable-pip-version-check 2>/dev/null | grep -iE '^(bvseg|numpy|ray|pyarrow|pandas|trimesh|pytest) ' || true
echo "pip install took $((SECONDS - start)) s"

echo "+ (cd python && cargo fmt --check && cargo clippy --all-targets --locked -- -D warnings)"
(cd python && cargo fmt --check && cargo clippy --quiet --all-targets --locked -- -D warnings)

echo "+ pytest python/tests (BVSEG_CLI=$BVSEG_CLI)"
# Any exit status but 0 fails the step, 5 (no test collected) included.
"$py" -m pytest -q -p no:cacheprovider python/tests
echo "python package: $((SECONDS - start)) s in all"
