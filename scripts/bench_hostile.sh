#!/usr/bin/env bash
# Wall time and peak memory of the whole CLI process on the awkward inputs of
# tests/support/hostile.rs, each family at about BYTES (default 10,000,000), with the default
# parameters. Every run must end (exit 0, or exit 2 with a one-line error) within 5 s.
#
#   scripts/bench_hostile.sh [BYTES]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bytes=${1:-10000000}
cargo build --release --bin bvseg --example hostile_inputs
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
target/release/examples/hostile_inputs "$dir" "$bytes" >/dev/null
printf '%-22s %10s %8s %8s %5s  %s\n' file bytes seconds MB exit message
for f in "$dir"/*; do
    start=$(date +%s.%N)
    code=0
    /usr/bin/time -f '%M' -o "$dir/rss" target/release/bvseg segment "$f" -q -o "$dir/out.json" \
        >/dev/null 2>"$dir/err" || code=$?
    end=$(date +%s.%N)
    msg=$(grep -m1 -o 'error: .*' "$dir/err" | cut -c1-60 || true)
    printf '%-22s %10d %8.2f %8.0f %5d  %s\n' "$(basename "$f")" "$(stat -c %s "$f")" \
        "$(echo "$end - $start" | bc)" "$(($(tail -n1 "$dir/rss") / 1024))" "$code" "$msg"
done
