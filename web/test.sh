#!/usr/bin/env bash
# Builds the web viewer and runs its browser test (headless Chromium from Debian, driven by
# playwright-core from npm). Installs Chromium with apt-get when it is missing.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")"

if [ ! -x /usr/bin/chromium ]; then
    echo "==> installing chromium (apt-get)"
    sudo_cmd=()
    if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
    "${sudo_cmd[@]}" apt-get update
    "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y chromium
fi

./build.sh

# The CLI's volumes for the bundled mesh of the timed run, to compare byte for byte with the
# page's download (same mesh, parameters and seed: same bytes on native and wasm).
echo "==> the CLI's JSON for the page test"
mesh=${BVSEG_TEST_MESH:-spot}
(cd .. && cargo build --release --bin bvseg)
mkdir -p tests/cli-json
../target/release/bvseg segment "../assets/meshes/$mesh.obj" -q -o "tests/cli-json/$mesh.json" >/dev/null

echo "==> browser test"
cd tests
npm ci --no-audit --no-fund --loglevel=error
node --test browser.test.mjs
