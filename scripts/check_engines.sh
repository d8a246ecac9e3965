#!/usr/bin/env bash
# Checks bvseg's engine outputs with the clients people load them with:
# - GLB: the Khronos glTF validator (npm gltf-validator, its validateBytes API, through
#   scripts/validate_glb.mjs) must report no error; and the KHR_physics_rigid_bodies colliders
#   must match the JSON volumes (KHR_implicit_shapes type and size, axis, convex hulls).
# - MJCF: MuJoCo's Python package loads it (MjModel.from_xml_path), steps it, and its geoms
#   (type, size, position, axes; mesh vertices in world coordinates) must match the JSON.
# The checks of both are in scripts/check_engines.py.
# - Robots: `bvseg robot` on the bundled MJCF arms (assets/robots/arm, assets/robots/arm6 as
#   written and as MuJoCo saves it, scripts/mujoco_save.py) and, when the project's shared
#   folder is there (../shared, or $BVSEG_SHARED), on the Panda URDF and on MuJoCo's save of
#   it; MuJoCo loads the original and the new URDF and MJCF, every original collision mesh
#   vertex must lie in the new geoms of its body (the world body's included), and a new MJCF
#   must keep the original's bodies, joints, actuators, sensors, inertias and visual geoms
#   (scripts/check_robot.py); with the shared folder, its judge bvrobot_mjcf.py checks each
#   new MJCF of an MJCF too.
#
#   scripts/check_engines.sh BVSEG_BINARY [OUTDIR]
#
# Each bundled mesh is segmented at the defaults and at --k 16 with every engine target and
# a few --bv kinds, and the bundled CesiumMan at the defaults and with --bv capsule (its GLB
# skinned and animated, its MJCF a ragdoll), writing OUTDIR/<mesh>_<config>.{json,glb,xml}
# (OUTDIR defaults to a temporary folder, removed at the end). Prints one line per file, OK or FAIL with the
# reasons, and exits 1 if any failed.
#
# The clients are installed on first use, from the npm registry and PyPI only, into
# $BVSEG_ENGINE_CACHE (default ~/.cache/bvseg-engines): needs node/npm and python3 (venv).
set -euo pipefail

GLTF_VALIDATOR_VERSION=2.0.0-dev.3.10
MUJOCO_VERSION=4.0.0

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
    echo "usage: $0 BVSEG_BINARY [OUTDIR]" >&2
    exit 2
fi
start=$SECONDS
bvseg=$(realpath "$1")
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cache="${BVSEG_ENGINE_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/bvseg-engines}"
if [ $# -ge 2 ]; then
    out=$2
    mkdir -p "$out"
    out=$(realpath "$out")
else
    out=$(mktemp -d)
    trap 'rm -rf "$out"' EXIT
fi
mkdir -p "$cache"

# --- clients ------------------------------------------------------------------------------
validator="$cache/gltf-$GLTF_VALIDATOR_VERSION"
if [ ! -f "$validator/node_modules/gltf-validator/package.json" ]; then
    echo "installing gltf-validator@$GLTF_VALIDATOR_VERSION into $validator"
    npm install --prefix "$validator" --no-save --no-audit --no-fund --loglevel=error \
        "gltf-validator@$GLTF_VALIDATOR_VERSION" >"$cache/npm.log" 2>&1 ||
        { cat "$cache/npm.log" >&2; exit 2; }
fi
venv="$cache/mujoco-$MUJOCO_VERSION-venv"
py="$venv/bin/python"
if ! "$py" -c "import mujoco, sys; sys.exit(mujoco.__version__ != '$MUJOCO_VERSION')" 2>/dev/null; then
    echo "installing mujoco==$MUJOCO_VERSION into $venv"
    rm -rf "$venv"
    python3 -m venv "$venv"
    "$py" -m pip install --quiet --disable-pip-version-check "mujoco==$MUJOCO_VERSION" \
        >"$cache/pip.log" 2>&1 || { cat "$cache/pip.log" >&2; exit 2; }
fi
versions=$("$py" -c "import mujoco, numpy; print(f'mujoco {mujoco.__version__} (engine {mujoco.mj_versionString()}), numpy {numpy.__version__}')")
echo "clients: gltf-validator $GLTF_VALIDATOR_VERSION, $versions, node $(node --version)"
echo "bvseg: $("$bvseg" --version)"

# --- outputs ------------------------------------------------------------------------------
configs=(
    "default|"
    "gltf|--k 16 --target gltf"
    "gltf-hull|--k 16 --target gltf-hull"
    "mujoco|--k 16 --target mujoco"
    "mujoco-hull|--k 16 --target mujoco-hull"
    "hull|--k 16 --bv hull"
    "capsule|--k 16 --bv capsule"
    "ellipsoid|--k 16 --bv ellipsoid"
)
bases=() failed=0
for mesh in "$root"/assets/meshes/{bunny,spot,fourleg_2}.obj; do
    name=$(basename "$mesh" .obj)
    for entry in "${configs[@]}"; do
        tag=${entry%%|*} args=${entry#*|}
        base="$out/${name}_$tag"
        rm -f "$base".{json,glb,xml}
        # shellcheck disable=SC2086
        if "$bvseg" segment "$mesh" -q $args -o "$base.json" -o "$base.glb" -o "$base.xml" \
            >"$base.log" 2>&1; then
            bases+=("$base")
        else
            echo "FAIL ${name}_$tag: bvseg segment $args exited $?: $(tail -n 3 "$base.log" | tr '\n' ' ')"
            failed=1
        fi
    done
done

# A skinned character: the GLB with its skinned mesh and animation (--with-mesh), its
# colliders under the joints; the MJCF a ragdoll of one body per bone.
for entry in "default|" "capsule|--bv capsule"; do
    tag=${entry%%|*} args=${entry#*|}
    base="$out/CesiumMan_$tag"
    rm -f "$base".{json,glb,xml}
    # shellcheck disable=SC2086
    if "$bvseg" segment "$root/assets/characters/CesiumMan.glb" -q $args --with-mesh \
        -o "$base.json" -o "$base.glb" -o "$base.xml" >"$base.log" 2>&1; then
        bases+=("$base")
    else
        echo "FAIL CesiumMan_$tag: bvseg segment $args exited $?: $(tail -n 3 "$base.log" | tr '\n' ' ')"
        failed=1
    fi
done

# --- checks -------------------------------------------------------------------------------
if [ ${#bases[@]} -gt 0 ]; then
    glbs=()
    for base in "${bases[@]}"; do glbs+=("$base.glb"); done
    node "$root/scripts/validate_glb.mjs" "$validator" "$out/validator.json" "${glbs[@]}"
    "$py" "$root/scripts/check_engines.py" "$out/validator.json" "${bases[@]}" || failed=1
fi
checked=$(( ${#bases[@]} * 2 ))

# --- robots -------------------------------------------------------------------------------
# robot NAME ORIGINAL STEM [bvseg robot options]: segments ORIGINAL into $out/robot_NAME and
# checks the new STEM.xml and STEM.urdf against it.
robot() {
    local name=$1 original=$2 stem=$3
    shift 3
    local dir="$out/robot_$name"
    rm -rf "$dir"
    local code=0
    "$bvseg" robot "$original" -o "$dir" -q "$@" >"$dir.log" 2>&1 || code=$?
    if [ $code != 0 ]; then
        echo "FAIL robot $name: bvseg robot $* exited $code: $(tail -n 3 "$dir.log" | tr '\n' ' ')"
        failed=1
        return
    fi
    for new in "$dir/$stem.xml" "$dir/$stem.urdf"; do
        if report=$("$py" "$root/scripts/check_robot.py" "$original" "$new" 2>&1); then
            echo "OK robot $name $(basename "$new"): $(grep -v '^kept: ' <<<"$report" | tail -n 1)"
            grep '^kept: ' <<<"$report" | sed 's/^/   /' || true
        else
            echo "FAIL robot $name $(basename "$new"):"
            sed 's/^/  /' <<<"$report"
            failed=1
        fi
        checked=$((checked + 1))
    done
    # The shared judge of MJCF robots, on a new MJCF of an MJCF.
    if [ -n "$judge" ] && [ "${original##*.}" = xml ]; then
        local verdict
        local summary='import json, sys
r = json.loads(sys.argv[1].splitlines()[-1])
m, n, left = r["min_enclosed"], r["bodies_with_meshes"], r["mesh_geoms_left"]
print(f"min_enclosed {m} over {n} bodies, mesh geoms left {left}")
sys.exit(not (r["min_enclosed"] >= 1.0 and r["mesh_geoms_left"] == 0))'
        if verdict=$("$py" "$judge" "$original" "$dir/$stem.xml" --json 2>>"$dir.log") &&
            line=$("$py" -c "$summary" "$verdict"); then
            echo "OK robot $name $stem.xml by bvrobot_mjcf.py: $line"
        else
            echo "FAIL robot $name $stem.xml by bvrobot_mjcf.py: ${line:-$(tail -n 3 "$dir.log")}"
            failed=1
        fi
        checked=$((checked + 1))
    fi
}
shared="${BVSEG_SHARED:-$root/../shared}"
judge=""
if [ -f "$shared/tools/bvrobot_mjcf.py" ]; then
    judge="$shared/tools/bvrobot_mjcf.py"
fi
robot arm "$root/assets/robots/arm/arm.xml" bvseg_arm --max-parts 6 --samples 4000
robot arm6 "$root/assets/robots/arm6/arm6.xml" arm6 --samples 4000
# MuJoCo's own save of arm6: what a robot saved by MuJoCo looks like.
mkdir -p "$out/saved"
if "$py" "$root/scripts/mujoco_save.py" "$root/assets/robots/arm6/arm6.xml" "$out/saved/arm6.xml" \
    >"$out/saved/arm6.log" 2>&1; then
    robot arm6_saved "$out/saved/arm6.xml" arm6 --samples 4000
else
    echo "FAIL robot arm6_saved: scripts/mujoco_save.py: $(tail -n 3 "$out/saved/arm6.log")"
    failed=1
fi
if [ -f "$shared/robots/panda/panda.urdf" ]; then
    robot panda "$shared/robots/panda/panda.urdf" panda
    # MuJoCo's save of the Panda URDF: its base fused into the world body, its hand in frames.
    if "$py" "$root/scripts/mujoco_save.py" "$shared/robots/panda/panda.urdf" "$out/saved/panda.xml" \
        >"$out/saved/panda.log" 2>&1; then
        robot panda_saved "$out/saved/panda.xml" panda
    else
        echo "FAIL robot panda_saved: scripts/mujoco_save.py: $(tail -n 3 "$out/saved/panda.log")"
        failed=1
    fi
else
    echo "skipped robot panda: no $shared/robots/panda/panda.urdf (the project's shared folder)"
fi
echo "$checked files checked in $(( SECONDS - start )) s: $([ $failed = 0 ] && echo all OK || echo FAILURES)"
exit $failed
