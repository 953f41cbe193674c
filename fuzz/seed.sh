#!/usr/bin/env bash
# Seeds the importer's fuzz corpus: the project's own models (assets/) and the malformed files
# tests/malformed.rs makes from its tiny model.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
corpus=$root/fuzz/corpus/import_gltf
mkdir -p "$corpus"
cp "$root"/assets/split-tube.glb "$root"/assets/patchwork.glb "$corpus"/
LODLAB_MALFORMED_DIR="$corpus" cargo test --manifest-path "$root/Cargo.toml" --test malformed \
    every_malformed_file >/dev/null
echo "fuzz/seed.sh: $(ls "$corpus" | wc -l) files in $corpus"
