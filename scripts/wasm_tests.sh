#!/usr/bin/env bash
# Runs the core's platform tests (the recorded bit digests of the fits) and its `math::` tests
# (where wasm takes its own path) compiled for
# wasm32-wasip1, under Node.js's WASI, so that native and wasm are checked against the same
# recorded bits. Needs rustup (adds the target) and node.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if command -v rustup >/dev/null 2>&1; then
    rustup target add wasm32-wasip1
fi
out=$(cargo test -p bvseg-core --release --no-default-features --target wasm32-wasip1 --lib \
    --no-run --message-format=json |
    sed -n 's/.*"executable":"\([^"]*\.wasm\)".*/\1/p' | tail -n 1)
if [ -z "$out" ]; then
    echo "wasm_tests.sh: no test module built" >&2
    exit 1
fi
node --no-warnings - "$out" same_bits math:: <<'JS'
const { WASI } = require('node:wasi');
const { readFileSync } = require('node:fs');
const [file, ...args] = process.argv.slice(2);
// Without threads, libtest runs the tests one after another.
const wasi = new WASI({ version: 'preview1', args: [file, '--test-threads=1', ...args], env: {}, returnOnExit: true });
WebAssembly.instantiate(readFileSync(file), wasi.getImportObject()).then(({ instance }) => {
  process.exitCode = wasi.start(instance);
});
JS
