#!/usr/bin/env bash
# The long soak: 10,000 frames of the default mixed scene through every method, transition,
# foliage policy, character count and frame size (0×0 included), memory read every 500
# frames; exit 1 on a GPU error, on GPU memory that differs between readings after the first
# cycle, or on resident growth past 5 MB after it. About 15 minutes on lavapipe with 2 cores.
# CI runs a short version (tests/soak.rs). Extra arguments go to `lodlab soak`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cargo build --release --manifest-path "$root/Cargo.toml"
exec "$root/target/release/lodlab" soak --frames 10000 --every 500 --csv soak.csv "$@"
