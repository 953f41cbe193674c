#!/usr/bin/env bash
# Rebuilds the frame-time tables of docs/speed.md and the example bench of docs/benchmarks.md
# from `lodlab bench` runs on this machine, so that the figures the pages give are what this
# build measures here:
#
#   tools/docs/speed-tables.sh [LODLAB]    (default: target/release/lodlab; needs jq;
#                                           about 8 min on lavapipe with an empty cache)
#
# The adapter picks the table: `<!-- speed-table lavapipe -->` on a CPU adapter (llvmpipe),
# `<!-- speed-table gpu -->` on any other; the example bench is rewritten on lavapipe only.
# Bakes go to a cache of their own (LODLAB_DOCS_CACHE to reuse one): the benches time frames
# only, never bakes.
set -euo pipefail
cd "$(dirname "$0")/../.."
. tools/docs/splice.sh
lodlab=${1:-target/release/lodlab}
command -v jq >/dev/null || { echo "speed-tables: needs jq" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cache=${LODLAB_DOCS_CACHE:-$work/cache}

# One line a run: the scene as the table names it, then bench's arguments. Measured by time
# (`--seconds`), so a fast adapter measures more frames in the same time.
runs=(
    "one character|--scene crowd --count 1 --method as+is --seconds 10 --no-coverage"
    "1,000 characters|--scene crowd --count 1000 --method none,rest-pose,as,as+is --seconds 40 --no-coverage"
    "1,000 characters, MSAA 4×|--scene crowd --count 1000 --msaa 4 --method none,as+is --seconds 20 --no-coverage"
    "1,000 characters, popping|--scene crowd --count 1000 --method as+is --transition pop --seconds 15 --no-coverage"
    "1,000 characters, alpha blend|--scene crowd --count 1000 --method as+is --transition alpha --seconds 15 --no-coverage"
    "1,000 characters, dither|--scene crowd --count 1000 --method as+is --transition dither --seconds 15 --no-coverage"
    "10,000 characters|--scene crowd --count 10000 --method as+is --seconds 20 --no-coverage"
    "10,000 characters, no impostors|--scene crowd --count 10000 --method as+is --impostors off --seconds 20 --no-coverage"
    "default mixed scene|--method none,as+is --seconds 30"
    "500-tree forest|--scene forest --method none,as+is --seconds 30"
)

# A row per method of a run: its median, FPS, triangles and influences a frame, and its passes
# from the dearest, the foliage's with how many times over it shades the pixels it covers.
rows() {
    jq -r --arg scene "$1" --arg command "$2" '
        def r1: (. * 10 | round) / 10;
        def ms: if . >= 100 then round else r1 end;
        def k: if . >= 1000000 then "\((. / 10000 | round) / 100) M"
               elif . >= 1000 then "\(. / 1000 | round) k" else "\(.)" end;
        . as $r
        | [.order[] as $m | $r.methods[$m] | {m: $m} + .]
        | to_entries[]
        | .key as $i | .value as $f
        | ($f.passes | to_entries | sort_by(-.value)
            | map("\(.key) \(.value | ms)"
                  + (if .key == "foliage" and ($f.fragments_by_pass.foliage // null) != null
                     then " (\($f.fragments_by_pass.foliage.per_covered_pixel | round) a covered pixel)"
                     else "" end))
            | join(", ")) as $passes
        | "| \(if $i == 0 then $scene else "" end) | \(if $i == 0 then "`bench \($command)`" else "(same run)" end) | `\($f.m)` | \($f.median_ms | ms) | \($f.fps | r1) | \($f.triangles | k) | \($f.influences | k) | \($passes) |"
    ' "$3"
}

table="$work/table.md"
first=""
for entry in "${runs[@]}"; do
    label=${entry%%|*}
    args=${entry#*|}
    read -r -a argv <<<"$args"
    echo "speed-tables: lodlab bench $args" >&2
    "$lodlab" bench "${argv[@]}" --cache "$cache" --json="$work/run.json" >/dev/null 2>"$work/run.err" \
        || { cat "$work/run.err" >&2; exit 1; }
    [ -n "$first" ] || first=$(cat "$work/run.json")
    rows "$label" "$args" "$work/run.json" >>"$table"
done

adapter=$(jq -r .adapter <<<"$first")
case $adapter in
    *llvmpipe*) kind=lavapipe ;;
    *) kind=gpu ;;
esac
header=$(jq -r --arg date "$(date +%Y-%m-%d)" --arg rev "$(git rev-parse --short HEAD)" '
    "Measured \($date) by `tools/docs/speed-tables.sh` (lodlab \($rev), release build) on \(.adapter) (\(.backend), driver \(.driver)), \(.size[0])×\(.size[1]), the adapter'"'"'s default MSAA (\(.msaa)) unless the command says otherwise; median over the frames of the camera path, GPU time (\(.timing)):"
' <<<"$first")


{
    echo "$header"
    echo
    echo "| scene | command | method | median ms | FPS | triangles | influences | by pass (ms) |"
    echo "|---|---|---|---:|---:|---:|---:|---|"
    cat "$table"
} >"$work/speed.md"
splice docs/speed.md "speed-table $kind" "$work/speed.md"
echo "speed-tables: rewrote the $kind table in docs/speed.md ($(wc -l <"$table") rows)" >&2

if [ "$kind" = lavapipe ]; then
    # The example of docs/benchmarks.md: a bench as a user runs it, its Markdown as printed.
    example=(--scene crowd --count 1000)
    echo "speed-tables: lodlab bench ${example[*]}" >&2
    "$lodlab" bench "${example[@]}" --cache "$cache" --markdown "$work/example.md" \
        >/dev/null 2>"$work/run.err" || { cat "$work/run.err" >&2; exit 1; }
    {
        echo "\`lodlab bench ${example[*]}\`, $(date +%Y-%m-%d), lodlab $(git rev-parse --short HEAD), run by \`tools/docs/speed-tables.sh\` with every bake in the cache; its Markdown as printed:"
        echo
        sed 's/^/> /; s/^> $/>/' "$work/example.md"
    } >"$work/example-block.md"
    splice docs/benchmarks.md "bench-example" "$work/example-block.md"
    echo "speed-tables: rewrote the example in docs/benchmarks.md" >&2
fi
