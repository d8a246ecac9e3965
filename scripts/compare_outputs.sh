#!/usr/bin/env bash
# Byte-compares the outputs of two bvseg binaries on the same inputs: the bundled meshes and,
# when present, the shared test meshes (../shared/meshes or $BVSEG_SHARED/meshes), each at the
# defaults and at `--k 16 --bv mixed`. For refactors that must not change any output.
#
#   scripts/compare_outputs.sh OLD_BVSEG NEW_BVSEG [EXTRA SEGMENT OPTIONS...]
#
# Build the old binary from a worktree, e.g.
#   git worktree add /tmp/base <commit> && (cd /tmp/base && cargo build --release --bin bvseg)
# Prints one line per run and exits 1 if any output differs.
set -euo pipefail
if [ $# -lt 2 ]; then
    echo "usage: $0 OLD_BVSEG NEW_BVSEG [OPTIONS...]" >&2
    exit 2
fi
old=$1 new=$2
shift 2
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
shared="${BVSEG_SHARED:-$root/../shared}/meshes"
meshes=("$root"/assets/meshes/*.obj)
if [ -d "$shared" ]; then
    meshes+=("$shared"/*.obj)
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
differ=0 runs=0
for mesh in "${meshes[@]}"; do
    for config in "" "--k 16 --bv mixed"; do
        # shellcheck disable=SC2086
        "$old" segment "$mesh" -q $config "$@" -o "$out/old.json" >/dev/null
        # shellcheck disable=SC2086
        "$new" segment "$mesh" -q $config "$@" -o "$out/new.json" >/dev/null
        runs=$((runs + 1))
        if cmp -s "$out/old.json" "$out/new.json"; then
            echo "same    $(basename "$mesh") ${config:-defaults}"
        else
            echo "DIFFERS $(basename "$mesh") ${config:-defaults}"
            differ=$((differ + 1))
        fi
    done
done
echo "$runs runs, $differ with different outputs"
[ "$differ" -eq 0 ]
