#!/usr/bin/env bash
# Peak memory and time of every case of the second hardening round, on the release build:
#
#   LODLAB_HARDENING_DIR=/tmp/hard cargo test --test malformed second_round::odd_and_hostile
#   cargo build --release && tools/hardening-time.sh /tmp/hard
#
# prints one line a case: its name, exit code, wall seconds and peak resident set
# (`/usr/bin/time -v`), and fails if any case used more than 2 GB or 60 s.
set -euo pipefail
dir="${1:?usage: tools/hardening-time.sh DIR (from LODLAB_HARDENING_DIR)}"
bin="$(dirname "$0")/../target/release/lodlab"
[ -x "$bin" ] || { echo "build the release binary first: cargo build --release" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "needs GNU time: apt-get install time" >&2; exit 1; }
worst=0
printf '%-40s %5s %8s %9s\n' case exit seconds peak-MB
while IFS=$'\t' read -r name args; do
    IFS=$'\t' read -r -a argv <<<"$args"
    log="$(mktemp)"
    set +e
    /usr/bin/time -v timeout 120 "$bin" "${argv[@]}" >/dev/null 2>"$log"
    code=$?
    set -e
    wall="$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$log")"
    seconds="$(awk -F: '{ s = 0; for (i = 1; i <= NF; i++) s = s * 60 + $i; print s }' <<<"$wall")"
    kb="$(awk -F': ' '/Maximum resident set size/ {print $2}' "$log")"
    rm -f "$log"
    printf '%-40s %5s %8.2f %9.1f\n' "$name" "$code" "$seconds" "$((kb))e-3"
    if [ "$kb" -gt 2097152 ] || awk -v s="$seconds" 'BEGIN { exit !(s > 60) }'; then worst=1; fi
done <"$dir/commands.txt"
exit "$worst"
