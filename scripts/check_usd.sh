#!/usr/bin/env bash
# Checks bvseg's USD outputs with Pixar's usd-core (PyPI), as Isaac Sim and Omniverse read them:
# - bvseg segment writes .usda (and .json) for two bundled meshes at the defaults (ellipsoids
#   become convex meshes) and with --target usd and usd-hull, and for the bundled CesiumMan
#   (volumes named by their bones); bvseg robot writes the bundled arm6's <robot>.usda.
# - scripts/check_usd.py opens each with Usd.Stage.Open and checks the stage metadata, that
#   every collider prim has UsdPhysics.CollisionAPI, a guide purpose, no non-uniform scale on
#   a Sphere, Capsule or Cylinder, at most 64 points on a convex Mesh, and one collider per
#   volume of the run's JSON.
# - When the project's shared folder is there (../shared, or $BVSEG_SHARED), its judge
#   tools/bvusd.py must find every mesh vertex and sampled surface point enclosed and no
#   problem, in its own venv ($BVTOOLS_VENV, default target/bvtools-venv, made by the shared
#   tools/setup.sh on first use); and the robot's colliders, placed at qpos0, must hold every
#   vertex of the original's collision meshes as MuJoCo places them (check_usd.py --robot).
#
#   scripts/check_usd.sh BVSEG_BINARY [OUTDIR]
#
# OUTDIR defaults to a temporary folder, removed at the end. usd-core is installed on first use
# into target/usd-venv (needs python3 with venv). Prints one line per check and exits 1 if any
# failed.
set -euo pipefail

USD_CORE_VERSION=26.11

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
    echo "usage: $0 BVSEG_BINARY [OUTDIR]" >&2
    exit 2
fi
start=$SECONDS
bvseg=$(realpath "$1")
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ $# -ge 2 ]; then
    out=$2
    mkdir -p "$out"
    out=$(realpath "$out")
else
    out=$(mktemp -d)
    trap 'rm -rf "$out"' EXIT
fi

# --- usd-core -------------------------------------------------------------------------------
venv="$root/target/usd-venv"
py="$venv/bin/python"
if ! "$py" -c "from pxr import Usd, UsdPhysics" 2>/dev/null; then
    echo "installing usd-core==$USD_CORE_VERSION into $venv"
    rm -rf "$venv"
    python3 -m venv "$venv"
    "$py" -m pip install --quiet --disable-pip-version-check "usd-core==$USD_CORE_VERSION" \
        >"$out/pip.log" 2>&1 || { cat "$out/pip.log" >&2; exit 2; }
fi
echo "usd-core: $("$py" -c 'from pxr import Usd; print(".".join(map(str, Usd.GetVersion())))')"
echo "bvseg: $("$bvseg" --version)"

# --- outputs --------------------------------------------------------------------------------
failed=0
files=()   # FILE.usda=FILE.json
judged=()  # MESH|FILE.usda
segment() {
    local name=$1 mesh=$2
    shift 2
    local base="$out/$name"
    if "$bvseg" segment "$mesh" -q -o "$base.json" -o "$base.usda" "$@" >"$base.log" 2>&1; then
        files+=("$base.usda=$base.json")
        judged+=("$mesh|$base.usda")
    else
        echo "FAIL $name: bvseg segment $* exited $?: $(tail -n 3 "$base.log" | tr '\n' ' ')"
        failed=1
    fi
}
for m in bunny spot; do
    segment "${m}_default" "$root/assets/meshes/$m.obj"
    segment "${m}_usd-hull" "$root/assets/meshes/$m.obj" --k 16 --target usd-hull \
        --up-axis Z --meters-per-unit 0.01 --usd-rigid-body
    segment "${m}_usd" "$root/assets/meshes/$m.obj" --k 16 --target usd
done
segment CesiumMan "$root/assets/characters/CesiumMan.glb" --bv capsule
arm6="$root/assets/robots/arm6/arm6.xml"
if "$bvseg" robot "$arm6" -o "$out/arm6" -q --samples 4000 >"$out/arm6.log" 2>&1; then
    files+=("$out/arm6/arm6.usda")
else
    echo "FAIL robot arm6: bvseg robot exited $?: $(tail -n 3 "$out/arm6.log" | tr '\n' ' ')"
    failed=1
fi

# --- usd-core -------------------------------------------------------------------------------
if [ ${#files[@]} -gt 0 ]; then
    "$py" "$root/scripts/check_usd.py" "${files[@]}" || failed=1
fi

# --- the shared judge -----------------------------------------------------------------------
shared="${BVSEG_SHARED:-$root/../shared}"
if [ -f "$shared/tools/bvusd.py" ]; then
    export BVTOOLS_VENV=${BVTOOLS_VENV:-$root/target/bvtools-venv}
    [ -x "$BVTOOLS_VENV/bin/python" ] || bash "$shared/tools/setup.sh" >"$out/setup.log" 2>&1 ||
        { echo "FAIL: $shared/tools/setup.sh: $(tail -n 3 "$out/setup.log")"; exit 1; }
    judge="$BVTOOLS_VENV/bin/python"
    verdict='import json, sys
r = json.loads(sys.argv[1].splitlines()[-1])
ok = r["vertices_enclosed"] == 1 and r["surface_enclosed"] == 1 and not r["problems"]
print("%d colliders %s, vertices_enclosed %s, surface_enclosed %s, problems %s" % (
    r["colliders"], r["kinds"], r["vertices_enclosed"], r["surface_enclosed"], r["problems"][:3]))
sys.exit(0 if ok else 1)'
    for entry in "${judged[@]}"; do
        mesh=${entry%%|*} usd=${entry#*|}
        if report=$("$judge" "$shared/tools/bvusd.py" "$mesh" "$usd" --json 2>>"$out/bvusd.log") &&
            line=$("$judge" -c "$verdict" "$report"); then
            echo "OK $(basename "$usd") by bvusd.py: $line"
        else
            echo "FAIL $(basename "$usd") by bvusd.py: ${line:-$(tail -n 3 "$out/bvusd.log")}"
            failed=1
        fi
        line=""
    done
    if [ -f "$out/arm6/arm6.usda" ]; then
        "$judge" "$root/scripts/check_usd.py" --robot "$arm6" "$out/arm6/arm6.usda" || failed=1
    fi
else
    echo "skipped bvusd.py: no $shared/tools/bvusd.py (the project's shared folder)"
fi
echo "USD check done in $((SECONDS - start)) s: $([ $failed = 0 ] && echo all OK || echo FAILURES)"
exit $failed
