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

echo "==> browser test"
cd tests
npm ci --no-audit --no-fund --loglevel=error
node --test browser.test.mjs
