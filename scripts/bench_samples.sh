#!/usr/bin/env bash
# Time and peak memory of whole `bvseg segment` runs on the bundled bunny at growing sample
# counts (issue 16's multi-grid report), as a Markdown table.
#
# Usage: scripts/bench_samples.sh [BVSEG] [K] [COUNTS...]
#   defaults: target/release/bvseg, k = 64, 10000 100000 1000000 5000000
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/bvseg}
k=${2:-64}
shift $(( $# > 2 ? 2 : $# ))
counts=("$@")
[ ${#counts[@]} -gt 0 ] || counts=(10000 100000 1000000 5000000)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "| --samples | samples | k | TOV | seconds | peak MB |"
echo "|---:|---:|---:|---:|---:|---:|"
for n in "${counts[@]}"; do
    /usr/bin/time -f "%e %M" -o "$tmp/t" "$bin" segment assets/meshes/bunny.obj --samples "$n" \
        --k "$k" --quiet -o "$tmp/v.json" >"$tmp/out"
    read -r secs kb <"$tmp/t"
    samples=$(awk '$1 == "samples" { print $2 }' "$tmp/out")
    tov=$(awk '$1 == "TOV" { print $2 }' "$tmp/out")
    echo "| $n | $samples | $k | $tov | $secs | $((kb / 1024)) |"
done
