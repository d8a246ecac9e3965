#!/usr/bin/env bash
# Count the instructions one `bvseg segment` run executes (valgrind's cachegrind, no cache
# simulation), on one thread. Unlike wall times on a noisy 2-core machine, the count is
# nearly deterministic (runs differ by a few in 10,000): compare binaries by it when a change
# is worth a few per cent.
#
# Usage: scripts/count_instructions.sh BIN MESH [SEGMENT ARGS...]
#   e.g. scripts/count_instructions.sh target/release/bvseg assets/meshes/spot.obj --bv cylinder
set -euo pipefail
if ! command -v valgrind >/dev/null; then
    echo "count_instructions.sh: needs valgrind (apt-get install valgrind)" >&2
    exit 2
fi
bin=$1
shift
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null \
    "$bin" segment "$@" --quiet --threads 1 -o "$tmp/out.json" 2>"$tmp/log" >/dev/null
awk '/I *refs/ { print $NF }' "$tmp/log"
