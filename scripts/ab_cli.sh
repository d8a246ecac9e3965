#!/usr/bin/env bash
# Time whole `bvseg segment` processes of two or more binaries on one mesh, alternating them
# round by round so machine drift hits all alike, and print each binary's median and best
# wall time, user time, peak memory, and whether its output matches the first binary's.
#
# Usage: scripts/ab_cli.sh ROUNDS MESH "SEGMENT ARGS" BIN...
#   e.g. scripts/ab_cli.sh 5 ../shared/meshes/human_1.obj "" /tmp/bvseg_old target/release/bvseg
# The output is a .json file; set AB_FORMAT=glb (or xml, obj) to write that format instead
# (the JSON alone carries the hierarchy, which the run then skips).
set -euo pipefail
rounds=$1 mesh=$2 args=$3 ext=${AB_FORMAT:-json}
shift 3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for r in $(seq "$rounds"); do
    i=0
    for bin in "$@"; do
        # shellcheck disable=SC2086
        /usr/bin/time -f "%e %U %M" -o "$tmp/t" "$bin" segment "$mesh" $args --quiet \
            -o "$tmp/out$i.$ext" >/dev/null
        echo "$(cat "$tmp/t")" >>"$tmp/times$i"
        i=$((i + 1))
    done
done
i=0
for bin in "$@"; do
    same=yes
    cmp -s "$tmp/out0.$ext" "$tmp/out$i.$ext" || same=no
    med() { cut -d' ' -f"$1" "$tmp/times$i" | sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
    best=$(cut -d' ' -f1 "$tmp/times$i" | sort -n | head -1)
    peak=$(cut -d' ' -f3 "$tmp/times$i" | sort -n | tail -1)
    printf "%-28s wall median %6.2f s, best %6.2f s | user median %6.2f s | peak %5.0f MB | output as the first's: %s\n" \
        "$bin" "$(med 1)" "$best" "$(med 2)" "$((peak / 1024))" "$same"
    i=$((i + 1))
done
