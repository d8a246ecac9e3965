#!/usr/bin/env bash
# CI of the Blender add-on (blender/): a real Blender, headless, from PyPI's `bpy` wheel (Blender
# 4.5 LTS as a Python module, CPython 3.11 like Blender's own), in a virtual environment under
# target/ made on first use. It checks the extension's manifest and builds its zip with
# Blender's own extension tool, then runs blender/tests/test_addon.py twice: the folder enabled
# as a legacy add-on (every check; with held-out meshes and game assets of ../shared when it is
# there, or $BVSEG_SHARED), and the zip installed as an extension (one mesh).
#
#   bash blender/ci.sh [BVSEG]        # BVSEG: the release binary (default target/release/bvseg)
#
# Environment: BVSEG_BLENDER_VENV (default target/blender-venv), BVSEG_BPY_VERSION (default
# 4.5.4). Needs python3.11 (the bpy wheels are cp311 only).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
start=$SECONDS
bvseg="$(realpath "${1:-target/release/bvseg}")"
venv="${BVSEG_BLENDER_VENV:-$root/target/blender-venv}"
bpy_version="${BVSEG_BPY_VERSION:-4.5.4}"

if [ ! -x "$bvseg" ]; then
    echo "blender/ci.sh: $bvseg is not an executable (cargo build --release -p bvseg-cli)" >&2
    exit 2
fi
py=$venv/bin/python
if ! "$py" -c "import bpy, sys; sys.exit(bpy.app.version_string.split()[0] != '$bpy_version')" 2>/dev/null; then
    python=$(command -v python3.11 || command -v python3)
    if ! "$python" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
        echo "blender/ci.sh: the bpy wheel needs CPython 3.11; $python is $("$python" --version)" >&2
        exit 2
    fi
    echo "+ $python -m venv $venv && pip install bpy==$bpy_version"
    rm -rf "$venv"
    "$python" -m venv "$venv"
    "$py" -m pip install --quiet --disable-pip-version-check "bpy==$bpy_version"
    echo "bpy installed in $((SECONDS - start)) s"
fi

ext_tool=$("$py" -c 'import bpy, os; print(os.path.join(bpy.utils.system_resource("SCRIPTS"), "addons_core", "bl_pkg", "cli", "blender_ext.py"))' 2>/dev/null | tail -n 1)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "+ blender_ext.py validate / build blender/bvseg_blender"
"$py" "$ext_tool" validate blender/bvseg_blender
"$py" "$ext_tool" build --source-dir blender/bvseg_blender --output-dir "$out"
zip=$(ls "$out"/bvseg_blender-*.zip)

# The bpy module is chatty (import logs, a memory report at exit): the test's own lines stay.
run() {
    echo "+ $py blender/tests/test_addon.py --bvseg $bvseg $*"
    local status=0
    timeout 900 "$py" -u blender/tests/test_addon.py --bvseg "$bvseg" "$@" >"$out/log" 2>&1 || status=$?
    grep -vE '^(Freeing memory|Error: Not freed memory|[0-9:]+ \| INFO:|INFO |Info: |OBJ import)' "$out/log" || true
    return "$status"
}
# Held-out meshes and game assets of the project's shared test data, when it is there.
shared="${BVSEG_SHARED:-$root/../shared}"
if [ -d "$shared/meshes" ] && [ -d "$shared/assets/kenney" ]; then
    run --mode legacy --shared "$shared"
else
    echo "note: $shared/meshes or assets/kenney not found: the held-out shared cases were not run"
    run --mode legacy
fi
run --mode extension --zip "$zip"
echo "blender add-on: $((SECONDS - start)) s in all"
