#!/usr/bin/env bash
# Rebuilds the table of how far a method's error curve moves with the order a file lists its
# vertices in, and with the tie order, in docs/levels.md (between its `<!-- order-spread -->`
# markers), from `examples/order_probe.rs`.
#
#   tools/docs/order-spread.sh     (about 10 min on 2 cores)
#
# Fox.glb is read from ../shared/models where it is there, and left out where not.
set -euo pipefail
cd "$(dirname "$0")/../.."
. tools/docs/splice.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
models=(walker horse robot mocap knight patchwork)
if [[ -f ../shared/models/Fox.glb ]]; then
    models=(walker horse ../shared/models/Fox.glb robot mocap knight patchwork)
else
    echo "order-spread: ../shared/models/Fox.glb is missing; its rows are left out" >&2
fi
cargo build -q --release --example order_probe
target/release/examples/order_probe "${models[@]}" >"$work/rows.md"
{
    echo "Measured $(date +%Y-%m-%d), lodlab $(git rev-parse --short HEAD), release build; \`tools/docs/order-spread.sh\` wrote this table. Each figure is the median over the curve (or its coarsest tenth) of one curve's error over the other's at equal influence counts, each measured by its own probe: the widest of three random file orders against the file's own, and of tie orders 1 to 4 against order 0."
    echo
    sed 's#\.\./shared/models/##' "$work/rows.md"
} >"$work/table.md"
splice docs/levels.md order-spread "$work/table.md"
echo "order-spread: rewrote the table in docs/levels.md" >&2
