#!/usr/bin/env bash
# The core's speed in the browser's WebAssembly engine against native code, without a browser:
# builds examples/repeat_runs.rs natively and for wasm32-wasip1 (with the page's SIMD flag),
# runs both on one thread, alternating, ROUNDS times, and prints the median of the later runs
# (the engine's optimised code) and their ratio. Node.js runs the module: it has Chromium's
# engine (V8), in an older version. Needs rustup (adds the target) and node.
#
#   scripts/wasm_vs_native.sh [MESH] [ROUNDS]     (default: the bundled spot, 3 rounds)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
mesh=$(realpath "${1:-assets/meshes/spot.obj}")
rounds=${2:-3}
if command -v rustup >/dev/null 2>&1; then
    rustup target add wasm32-wasip1 >/dev/null
fi
cargo build --release --example repeat_runs
CARGO_TARGET_WASM32_WASIP1_RUSTFLAGS="-C target-feature=+simd128" \
    cargo build --release --target wasm32-wasip1 --no-default-features --example repeat_runs
native=target/release/examples/repeat_runs
wasm=target/wasm32-wasip1/release/examples/repeat_runs.wasm
runner=$(mktemp)
trap 'rm -f "$runner"' EXIT
cat >"$runner" <<'JS'
const { WASI } = require('node:wasi');
const { readFileSync } = require('node:fs');
const path = require('node:path');
const [file, mesh, runs] = process.argv.slice(2);
const dir = path.dirname(mesh);
const wasi = new WASI({ version: 'preview1', args: ['repeat_runs', `/mesh/${path.basename(mesh)}`, runs],
  env: {}, preopens: { '/mesh': dir }, returnOnExit: true });
const instance = new WebAssembly.Instance(new WebAssembly.Module(readFileSync(file)), wasi.getImportObject());
process.exitCode = wasi.start(instance);
JS
later() { tail -n +2 | awk '{ print $2 }'; }
n_all="" w_all=""
for r in $(seq 1 "$rounds"); do
    n=$("$native" "$mesh" 3 | later)
    w=$(node --no-warnings "$runner" "$wasm" "$mesh" 3 | later)
    echo "round $r: native $(echo $n) s, wasm $(echo $w) s"
    n_all+="$n"$'\n' w_all+="$w"$'\n'
done
median() { sort -g | awk 'NF { a[n++] = $1 } END { print (n % 2 ? a[(n - 1) / 2] : (a[n / 2 - 1] + a[n / 2]) / 2) }'; }
nm=$(printf '%s' "$n_all" | median)
wm=$(printf '%s' "$w_all" | median)
echo "median later run, one thread: native ${nm} s, wasm ${wm} s, ratio $(awk -v w="$wm" -v n="$nm" 'BEGIN { printf "%.2f", w / n }')"
