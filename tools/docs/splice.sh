# Sourced by the scripts beside it, which rewrite the generated blocks of the docs.
#
# splice FILE NAME CONTENT: replaces the lines between `<!-- NAME -->` and `<!-- /NAME -->` in
# FILE by the lines of the file CONTENT, keeping the markers; fails where FILE lacks them.
splice() {
    local file=$1 name=$2 content=$3
    if ! grep -qxF "<!-- $name -->" "$file" || ! grep -qxF "<!-- /$name -->" "$file"; then
        echo "$(basename "$0"): $file lacks the <!-- $name --> … <!-- /$name --> markers" >&2
        exit 1
    fi
    local spliced
    spliced=$(mktemp)
    awk -v name="$name" -v content="$content" '
        $0 == "<!-- " name " -->" { print; while ((getline line < content) > 0) print line; skipping = 1; next }
        $0 == "<!-- /" name " -->" { skipping = 0 }
        !skipping
    ' "$file" >"$spliced"
    cat "$spliced" >"$file"
    rm -f "$spliced"
}
