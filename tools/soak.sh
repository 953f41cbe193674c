#!/usr/bin/env bash
# The long soak: 10,000 frames of the mixed scene through every method, transition, foliage
# policy, character count and frame size (0×0 included), memory read every 500 frames; exit 1
# on a GPU error, on GPU memory that differs between readings after the first cycle, or on
# resident growth past 5 MB after it. The scene is small (COUNT=30 characters, TREES=20
# trees): the same code paths as the default one, at a frame rate that fits the run in about
# 15 minutes on lavapipe with 2 cores (COUNT=300 TREES=500, the default scene, takes about an
# hour). CI runs a short version (tests/integration/soak.rs). Extra arguments go to `lodlab soak`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cargo build --release --manifest-path "$root/Cargo.toml"
exec "$root/target/release/lodlab" soak --frames 10000 --every 500 \
    --count "${COUNT:-30}" --trees "${TREES:-20}" --csv soak.csv "$@"
