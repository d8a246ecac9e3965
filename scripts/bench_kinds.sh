#!/usr/bin/env bash
# The kinds side by side (issue 14), judged by the independent bveval.py: for each mesh and
# k in 8 16 32, bvseg with ellipsoids only, each other kind alone, and --target parry /
# mujoco; then bvseg's hulls against CoACD's and V-HACD's own hulls at CoACD's own count.
# One JSON line per run in OUT/results.jsonl (resumable: done runs are skipped).
#
#   scripts/bench_kinds.sh BVSEG OUT MESH...
# Needs the judge's venv: BVTOOLS_VENV (default /work/bvtools-venv) and BVTOOLS (the
# directory of bveval.py and peers.py, default ../shared/tools).
set -euo pipefail
bin=$1 out=$2
shift 2
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tools="${BVTOOLS:-$root/../shared/tools}"
py="${BVTOOLS_VENV:-/work/bvtools-venv}/bin/python"
mkdir -p "$out"
res="$out/results.jsonl"
touch "$res"
judge() { # MESH VOLUMES NAME K CONFIG SECONDS
    "$py" "$tools/bveval.py" "$1" "$2" --grid 1000000 --surface-points 100000 --json 2>/dev/null |
        "$py" -c "
import json, sys
e = json.load(sys.stdin)
v = json.load(open('$2'))
shapes = {}
for x in v['volumes']:
    shapes[x['shape']] = shapes.get(x['shape'], 0) + 1
print(json.dumps({'mesh': '$3', 'k': $4, 'config': '$5', 'seconds': $6, 'k_out': len(v['volumes']),
  'tov': e['tov'], 'protrusion': e.get('protrusion_max_rel'), 'floats': e.get('floats'),
  'coverage': e['coverage_surface'], 'shapes': shapes}))" >> "$res"
}
done_already() { grep -q "\"mesh\": \"$1\", \"k\": $2, \"config\": \"$3\"" "$res"; }
for mesh in "$@"; do
    name=$(basename "$mesh" .obj)
    for k in 8 16 32; do
        for config in "--bv ellipsoid" "--bv sphere" "--bv capsule" "--bv cylinder" "--bv obb" \
            "--bv hull" "--target parry" "--target mujoco" "--bv primitives"; do
            done_already "$name" "$k" "$config" && continue
            f="$out/$name-$k-${config// /_}.json"
            s=$(date +%s.%N)
            # shellcheck disable=SC2086
            "$bin" segment "$mesh" -q --k "$k" $config -o "$f" >/dev/null
            e=$(date +%s.%N)
            judge "$mesh" "$f" "$name" "$k" "$config" "$(echo "$e - $s" | bc)"
        done
    done
    # Hulls against CoACD's and V-HACD's own hulls, at CoACD's own part count.
    if ! done_already "$name" 0 "coacd"; then
        f="$out/$name-coacd.json"
        s=$(date +%s.%N)
        "$py" "$tools/peers.py" "$mesh" --k 16 --method coacd --bv hull --out "$f" >/dev/null 2>&1
        e=$(date +%s.%N)
        judge "$mesh" "$f" "$name" 0 "coacd" "$(echo "$e - $s" | bc)"
    fi
    kc=$("$py" -c "import json; print(len(json.load(open('$out/$name-coacd.json'))['volumes']))")
    if ! done_already "$name" "$kc" "vhacd"; then
        f="$out/$name-vhacd.json"
        s=$(date +%s.%N)
        "$py" "$tools/peers.py" "$mesh" --k "$kc" --method vhacd --bv hull --out "$f" >/dev/null 2>&1
        e=$(date +%s.%N)
        judge "$mesh" "$f" "$name" "$kc" "vhacd" "$(echo "$e - $s" | bc)"
    fi
    if ! done_already "$name" "$kc" "--bv hull (coacd k)"; then
        f="$out/$name-hull-coacd-k.json"
        s=$(date +%s.%N)
        "$bin" segment "$mesh" -q --k "$kc" --bv hull -o "$f" >/dev/null
        e=$(date +%s.%N)
        judge "$mesh" "$f" "$name" "$kc" "--bv hull (coacd k)" "$(echo "$e - $s" | bc)"
    fi
done
