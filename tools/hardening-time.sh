#!/usr/bin/env bash
# Peak memory and time of every case of the hardening corpus, on the release build:
#
#   LODLAB_HARDENING_DIR=/tmp/hard cargo test --test malformed second_round::odd_and_hostile
#   LODLAB_MALFORMED_DIR=/tmp/first cargo test --test malformed every_malformed_file
#   cargo build --release && tools/hardening-time.sh /tmp/hard /tmp/first
#
# A folder with `commands.txt` (the second round) runs each line's command; any other runs
# `lodlab bake` on each of its .glb and .gltf files (the first round's corpus). One line a
# case: its name, exit code, wall seconds and peak resident set (`/usr/bin/time -v`); fails if
# any case used more than 2 GB or 60 s.
set -euo pipefail
[ $# -gt 0 ] || { echo "usage: tools/hardening-time.sh DIR... (from LODLAB_HARDENING_DIR or LODLAB_MALFORMED_DIR)" >&2; exit 1; }
bin="$(dirname "$0")/../target/release/lodlab"
[ -x "$bin" ] || { echo "build the release binary first: cargo build --release" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "needs GNU time: apt-get install time" >&2; exit 1; }
worst=0
printf '%-40s %5s %8s %9s\n' case exit seconds peak-MB
# One case: its name, then the arguments.
measure() {
    local name="$1"
    shift
    local log
    log="$(mktemp)"
    set +e
    /usr/bin/time -v timeout 120 "$bin" "$@" >/dev/null 2>"$log"
    local code=$?
    set -e
    local wall seconds kb
    wall="$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$log")"
    seconds="$(awk -F: '{ s = 0; for (i = 1; i <= NF; i++) s = s * 60 + $i; print s }' <<<"$wall")"
    kb="$(awk -F': ' '/Maximum resident set size/ {print $2}' "$log")"
    rm -f "$log"
    printf '%-40s %5s %8.2f %9.1f\n' "$name" "$code" "$seconds" "$(awk -v k="$kb" 'BEGIN { print k / 1024 }')"
    if [ "$kb" -gt 2097152 ] || awk -v s="$seconds" 'BEGIN { exit !(s > 60) }'; then worst=1; fi
}
for dir in "$@"; do
    if [ -f "$dir/commands.txt" ]; then
        while IFS=$'\t' read -r name args; do
            IFS=$'\t' read -r -a argv <<<"$args"
            measure "$name" "${argv[@]}"
        done <"$dir/commands.txt"
    else
        for f in "$dir"/*.glb "$dir"/*.gltf; do
            [ -e "$f" ] || continue
            measure "$(basename "$f")" bake --cache "$dir/cache" "$f"
        done
    fi
done
exit "$worst"
