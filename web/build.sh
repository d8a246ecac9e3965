#!/usr/bin/env bash
# Builds the web viewer into web/dist/ without any tool that downloads at run time:
#   1. cargo builds the viewer library for wasm32-unknown-unknown (no threads: the core's
#      `parallel` feature is off there), with egui and its text stack optimised for size;
#   2. wasm-bindgen-cli, at exactly the wasm-bindgen version of Cargo.lock, writes the JS glue
#      (installed with `cargo install` when missing; `--locked` would fail, one of its locked
#      dependencies is not on the registry);
#   3. wasm-opt from npm's binaryen package optimises the module (Debian's binaryen 108 makes a
#      module that fails to load);
#   4. the page (index.html, main.js) is copied next to it.
# Serve web/dist/ with any static server, e.g. `python3 -m http.server -d web/dist`.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
dist=web/dist

say() { printf '==> %s\n' "$*"; }

version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
if [ -z "$version" ]; then
    echo "build.sh: error: no wasm-bindgen in Cargo.lock" >&2
    exit 1
fi

say "cargo build (wasm32-unknown-unknown, release)"
if command -v rustup >/dev/null 2>&1; then
    rustup target add wasm32-unknown-unknown
fi
# egui (0.37) and its text stack (harfrust shaping, skrifa / read-fonts outlines) are built for
# size: at opt-level 3 they put the module over its budget (6.1 MB). The core, and every other
# crate, keeps the release profile's opt-level 3 (vello_cpu and fearless_simd too: their SIMD
# fallback code needs inlining, and grows by 1.7 MB without it). Only this build: the native
# viewer is built as the workspace's profile says.
size_config=()
for crate in egui epaint emath ecolor eframe egui_glow harfrust read-fonts skrifa font-types; do
    size_config+=(--config "profile.release.package.$crate.opt-level=\"z\"")
done
# No debug info in the module: the workspace's release profile keeps some for native profiling.
# WebAssembly SIMD (every current browser: Chrome 91, Firefox 89, Safari 16.4): the core runs
# about 9 % faster with it (BENCHMARKS.md), with the same results (lane-wise IEEE arithmetic;
# the browser test compares the page's JSON with the CLI's byte for byte).
CARGO_PROFILE_RELEASE_DEBUG=0 \
    CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="-C target-feature=+simd128" \
    cargo build --release --target wasm32-unknown-unknown -p bvseg-viewer --lib "${size_config[@]}"
wasm="target/wasm32-unknown-unknown/release/bvseg_viewer.wasm"

say "wasm-bindgen $version"
cargo_bin="${CARGO_HOME:-$HOME/.cargo}/bin"
export PATH="$cargo_bin:$PATH"
if [ "$(wasm-bindgen --version 2>/dev/null || true)" != "wasm-bindgen $version" ]; then
    cargo install wasm-bindgen-cli --version "=$version"
fi
rm -rf "$dist"
mkdir -p "$dist"
wasm-bindgen "$wasm" --out-dir "$dist" --out-name bvseg_viewer --target web --no-typescript \
    --remove-name-section --remove-producers-section

say "wasm-opt (npm binaryen)"
(cd web && npm ci --no-audit --no-fund --loglevel=error)
raw_size=$(stat -c %s "$dist/bvseg_viewer_bg.wasm")
# -O3, not -Oz: the module is well within its size budget, and speed is what the page needs.
web/node_modules/.bin/wasm-opt -O3 \
    --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
    --enable-mutable-globals --enable-reference-types --enable-multivalue --enable-simd \
    "$dist/bvseg_viewer_bg.wasm" -o "$dist/bvseg_viewer_bg.wasm"
size=$(stat -c %s "$dist/bvseg_viewer_bg.wasm")

cp web/index.html web/main.js "$dist/"
say "web/dist/bvseg_viewer_bg.wasm: $size bytes (before wasm-opt: $raw_size; budget: 6,000,000)"
if [ "$size" -gt 6000000 ]; then
    echo "build.sh: error: the optimised module is over 6 MB" >&2
    exit 1
fi
