#!/usr/bin/env bash
# Rebuilds the table of error curves and bake times in docs/levels.md (between its
# `<!-- error-table -->` markers) from the row `lodlab report` writes for each model
# (docs-row.md), so that the table's figures are what the report measured on this machine.
#
#   tools/docs/error-table.sh [LODLAB]     (default: target/release/lodlab; about 10 min)
#
# Fox.glb is read from ../shared/models where it is there, and left out where not.
set -euo pipefail
cd "$(dirname "$0")/../.."
. tools/docs/splice.sh
lodlab=${1:-target/release/lodlab}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows="$work/rows.md"
: >"$rows"
# One line a row: the name the table gives it, then the report's arguments.
entries=(
    "horse|horse"
    "walker|walker"
    "Fox.glb|../shared/models/Fox.glb"
    "robot|robot"
    "mocap (2-key T-pose clip)|mocap"
    "mocap, \`--clips mocap-walk\`|mocap --clips mocap-walk"
    "lowpoly|lowpoly"
    "knight|knight"
    "armour|armour"
    "patchwork|patchwork"
    "split-tube|split-tube"
)
for entry in "${entries[@]}"; do
    label=${entry%%|*}
    read -r -a args <<<"${entry#*|}"
    if [[ ${args[0]} == *.glb && ! -f ${args[0]} ]]; then
        echo "error-table: ${args[0]} is missing; its row is left out" >&2
        continue
    fi
    out="$work/report-$(wc -l <"$rows")"
    echo "error-table: lodlab report ${args[*]}" >&2
    "$lodlab" report "${args[@]}" --out "$out" --cache "$work/cache" >/dev/null 2>&1
    # The row under the table's own name for it.
    sed "s/^| [^|]* |/| ${label//\//\\/} |/" "$out/docs-row.md" >>"$rows"
done
{
    echo "| model | triangles | bake rest / AS / AS+IS (s) | coarsest level (rest / AS / AS+IS) | band over 5 tie orders (rest / AS / AS+IS) | AS better than rest-pose where the bands separate (share of the curve apart) | the same down to the coarsest level | AS / rest-pose (median) | AS+IS better than AS where the bands separate (apart) | AS+IS lighting / AS's |"
    echo "|---|---|---|---|---|---|---|---|---|---|"
    cat "$rows"
} >"$work/table.md"
splice docs/levels.md error-table "$work/table.md"
echo "error-table: rewrote the table in docs/levels.md ($(wc -l <"$rows") rows)" >&2
