#!/bin/sh
# Builds the web viewer into OUT_DIR: this crate for wasm32-unknown-unknown (WebGPU, WebGL2 as
# the fallback), then bound for the browser by wasm-bindgen (lodlab.js, lodlab_bg.wasm).
# `lodlab web --out SITE --wasm OUT_DIR` then puts them beside the page and its levels.
#
#   tools/web/build-wasm.sh OUT_DIR [--dev]
#
# Needs: rustup target add wasm32-unknown-unknown; and wasm-bindgen-cli at the version of the
# wasm-bindgen crate in Cargo.lock (cargo install wasm-bindgen-cli --version VERSION).
set -eu
out="${1:?usage: tools/web/build-wasm.sh OUT_DIR [--dev]}"
# OUT_DIR as given from where the script was run, before it moves to the repository.
mkdir -p "$out"
out=$(cd "$out" && pwd)
profile=release
if [ "${2:-}" = "--dev" ]; then profile=dev; fi
cd "$(dirname "$0")/../.."
want=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/[^0-9.]/, ""); print }' Cargo.lock)
have=$(wasm-bindgen --version 2>/dev/null | awk '{ print $2 }') || true
if [ "$have" != "$want" ]; then
    echo "build-wasm: wasm-bindgen $want is needed (found '${have:-none}'): cargo install wasm-bindgen-cli --version $want" >&2
    exit 1
fi
cargo build --profile "$profile" --target wasm32-unknown-unknown --bin lodlab
dir=$profile
if [ "$profile" = dev ]; then dir=debug; fi
target="${CARGO_TARGET_DIR:-target}"
mkdir -p "$out"
wasm-bindgen --target web --no-typescript --out-dir "$out" "$target/wasm32-unknown-unknown/$dir/lodlab.wasm"
ls -l "$out"
