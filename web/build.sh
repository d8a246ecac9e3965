#!/usr/bin/env bash
# Builds the web viewer into web/dist/ without any tool that downloads at run time:
#   1. cargo builds the viewer library for wasm32-unknown-unknown (no threads: the core's
#      `parallel` feature is off there), with egui and its text stack optimised for size;
#   2. wasm-bindgen-cli, at exactly the wasm-bindgen version of Cargo.lock, writes the JS glue
#      (installed with `cargo install` when missing; `--locked` would fail, one of its locked
#      dependencies is not on the registry);
#   3. wasm-opt from npm's binaryen package optimises the module (Debian's binaryen 108 makes a
#      module that fails to load);
#   4. the page (index.html, main.js) is copied next to it;
#   5. the same again with threads (the `threads` feature) into web/dist/threads/: the core on
#      a pool of Web Workers (wasm-bindgen-rayon). The standard library must be rebuilt with
#      WebAssembly atomics for that, which takes a nightly toolchain with rust-src (rustup
#      adds them); without one the page is built without threads, with a warning
#      (BVSEG_WEB_THREADS=0 skips it, =1 makes it an error).
# Serve web/dist/ with any static server, e.g. `python3 -m http.server -d web/dist`. The page
# runs the threaded module only when served cross-origin isolated, that is with the headers
# `Cross-Origin-Opener-Policy: same-origin` and `Cross-Origin-Embedder-Policy: require-corp`
# (browsers allow shared memory only then); otherwise the one without threads.
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
# Link-time optimisation with one codegen unit, for these builds only: it makes each module
# about 13 % smaller (threaded: 5.99 MB -> 5.22 MB) at the same speed, but for the plain
# page's first run, about 4 % slower (docs/viewer.md, "Size and speed"). The workspace's
# native builds and tests keep the profile's faster links.
web_profile=(CARGO_PROFILE_RELEASE_DEBUG=0 CARGO_PROFILE_RELEASE_LTO=fat
    CARGO_PROFILE_RELEASE_CODEGEN_UNITS=1)
# WebAssembly SIMD (every current browser: Chrome 91, Firefox 89, Safari 16.4): the core runs
# about 9 % faster with it (BENCHMARKS.md), with the same results (lane-wise IEEE arithmetic;
# the browser test compares the page's JSON with the CLI's byte for byte).
env "${web_profile[@]}" \
    CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="-C target-feature=+simd128" \
    cargo build --release --target wasm32-unknown-unknown -p bvseg-viewer --lib "${size_config[@]}"
wasm="target/wasm32-unknown-unknown/release/bvseg_viewer.wasm"

# The threaded module, from its own target directory (another toolchain, another std).
threads=${BVSEG_WEB_THREADS:-auto}
nightly=${BVSEG_NIGHTLY:-nightly}
threads_wasm=""
# Atomics in every crate, std included (build-std), and a shared memory that the JS glue
# creates and hands to each worker (imported), with the thread-local storage exports that
# wasm-bindgen's thread support calls.
threads_flags="-C target-feature=+simd128,+atomics,+bulk-memory,+mutable-globals"
for arg in --shared-memory --import-memory --max-memory=4294967296 --export=__wasm_init_tls \
    --export=__tls_size --export=__tls_align --export=__tls_base; do
    threads_flags+=" -C link-arg=$arg"
done
if [ "$threads" != 0 ]; then
    say "cargo +$nightly build --features threads (WebAssembly threads)"
    if command -v rustup >/dev/null 2>&1 &&
        rustup component add rust-src --toolchain "$nightly" &&
        rustup target add wasm32-unknown-unknown --toolchain "$nightly" &&
        env "${web_profile[@]}" \
            CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="$threads_flags" \
            cargo "+$nightly" build --release --target wasm32-unknown-unknown -p bvseg-viewer \
            --lib --features threads -Z build-std=panic_abort,std --target-dir target/wasm-threads \
            "${size_config[@]}"; then
        threads_wasm="target/wasm-threads/wasm32-unknown-unknown/release/bvseg_viewer.wasm"
    elif [ "$threads" = 1 ]; then
        echo "build.sh: error: the threaded module did not build (BVSEG_WEB_THREADS=1)" >&2
        exit 1
    else
        echo "build.sh: warning: no threaded module (needs rustup's $nightly with rust-src):" \
            "the page will run the core on one thread" >&2
    fi
fi

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
if [ -n "$threads_wasm" ]; then
    wasm-bindgen "$threads_wasm" --out-dir "$dist/threads" --out-name bvseg_viewer --target web \
        --no-typescript --remove-name-section --remove-producers-section
fi

say "wasm-opt (npm binaryen)"
(cd web && npm ci --no-audit --no-fund --loglevel=error)
# -O3, not -Oz: the module is well within its size budget, and speed is what the page needs.
# The threaded module also needs `--enable-threads` (shared memory, atomics).
# `-ocimfs 300`: a function with one caller is inlined only if small. By default binaryen
# inlines every such function, which made functions of up to 79 kB (the ellipsoid fit with
# both its solvers). The browser compiles a module's hot functions again while it runs
# (V8's optimising tier, on the same cores as the run); giant functions compile slowly, and
# the run waits in the unoptimised code meanwhile. With a limit of 1000 (and the ellipsoid's
# solvers kept apart in the source), the page's run of spot spent 0.67-0.73 s of CPU compiling
# instead of 1.01-1.09 s, and took 1.65-1.76 s instead of 1.86-2.03 s; 300 saved another
# 0.07-0.17 s of run (BENCHMARKS.md). Smaller functions did not run slower once compiled.
for module in "$dist/bvseg_viewer_bg.wasm" ${threads_wasm:+"$dist/threads/bvseg_viewer_bg.wasm"}; do
    raw_size=$(stat -c %s "$module")
    extra=()
    if [[ "$module" == */threads/* ]]; then extra=(--enable-threads); fi
    web/node_modules/.bin/wasm-opt -O3 -ocimfs 300 \
        --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
        --enable-mutable-globals --enable-reference-types --enable-multivalue --enable-simd \
        "${extra[@]}" "$module" -o "$module"
    size=$(stat -c %s "$module")
    say "$module: $size bytes (before wasm-opt: $raw_size; budget: 6,000,000)"
    if [ "$size" -gt 6000000 ]; then
        echo "build.sh: error: the optimised module is over 6 MB" >&2
        exit 1
    fi
done

cp web/index.html web/main.js "$dist/"
