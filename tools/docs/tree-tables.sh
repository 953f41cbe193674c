#!/usr/bin/env bash
# Rebuilds the built-in trees' tables in docs/trees.md from `lodlab report` on each, so that
# the figures the page gives are what this build measures:
#
#   tools/docs/tree-tables.sh [LODLAB]    (default: target/release/lodlab; needs jq; about 7 min)
#
# LODLAB_DOCS_REPORTS=DIR keeps the reports in DIR/TREE, and reads those already there instead
# of running them again.
#
# - `<!-- tree-levels -->`: every level of broadleaf, conifer and sapling (report.json);
# - `<!-- tree-thesis -->`: their colour errors at the thesis's billboard counts
#   (against-thesis.md);
# - `<!-- tree-lighting -->`: each cloud level lit beside the full tree (lighting.md).
set -euo pipefail
cd "$(dirname "$0")/../.."
. tools/docs/splice.sh
lodlab=${1:-target/release/lodlab}
command -v jq >/dev/null || { echo "tree-tables: needs jq" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
reports=${LODLAB_DOCS_REPORTS:-$work}
trees=(broadleaf conifer sapling)
for tree in "${trees[@]}"; do
    if [ -f "$reports/$tree/report.json" ] && [ -f "$reports/$tree/lighting.md" ]; then
        echo "tree-tables: $tree's report read from $reports/$tree" >&2
        continue
    fi
    echo "tree-tables: lodlab report $tree" >&2
    "$lodlab" report "$tree" --out "$reports/$tree" >/dev/null 2>"$work/err" || { cat "$work/err" >&2; exit 1; }
done
stamp="$(date +%Y-%m-%d), lodlab $(git rev-parse --short HEAD), release build; \`tools/docs/tree-tables.sh\` wrote this table"

# A Markdown table's rows (the lines after its separator) with a first cell put before each.
rows_with() {
    awk -v first="$1" 'seen && /^\|/ { print "| " first substr($0, 2); next } /^\|[-:|]+\|$/ { seen = 1 }' "$2"
}
# A Markdown table's header and separator, with a first column put before them.
header_with() {
    awk -v first="$1" '/^\|/ && !done { print "| " first substr($0, 2); getline; print "|---" $0; done = 1 }' "$2"
}

{
    echo "Measured $stamp. $(jq -r '"Colour error: \(.metric)."' "$reports/broadleaf/report.json") Billboards are those a view draws (a clump level draws one plane of each clump; it holds four)."
    echo
    echo "| tree | level | ε (× height) | grouping | billboards drawn | colour error | from its switch distance | at its switch size | switch size (px) |"
    echo "|---|---:|---:|---|---:|---:|---:|---:|---:|"
    for tree in "${trees[@]}"; do
        jq -r --arg tree "$tree" '
            def r3: (. * 1000 | round) as $m | "\($m / 1000 | floor).\($m % 1000 + 1000 | tostring | .[1:])";
            def r1: (. * 10 | round) / 10 | tostring;
            .levels | to_entries[] | select(.key > 0) | .key as $i | .value
            | "| \(if $i == 1 then $tree else "" end) | L\($i) | \(.epsilon) | \(.grouping) | \(.drawn_billboards) | \(.colour_error | r3) | \(.colour_error_from_switch | r3) | \(.colour_error_at_switch | r3) | \(.switch_px | r1) |"
        ' "$reports/$tree/report.json"
    done
} >"$work/levels.md"

{
    echo "Measured $stamp; each tree's \`against-thesis.md\` says how each column is read."
    echo
    header_with "tree |" "$reports/broadleaf/against-thesis.md"
    for tree in "${trees[@]}"; do rows_with "$tree |" "$reports/$tree/against-thesis.md"; done
} >"$work/thesis.md"

{
    echo "Measured $stamp; each tree's \`lighting.md\` says how it is measured."
    echo
    header_with "tree |" "$reports/broadleaf/lighting.md"
    for tree in "${trees[@]}"; do rows_with "$tree |" "$reports/$tree/lighting.md"; done
} >"$work/lighting.md"

splice docs/trees.md tree-levels "$work/levels.md"
splice docs/trees.md tree-thesis "$work/thesis.md"
splice docs/trees.md tree-lighting "$work/lighting.md"
echo "tree-tables: rewrote three tables in docs/trees.md" >&2
