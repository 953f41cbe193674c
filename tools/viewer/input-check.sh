#!/usr/bin/env bash
# Drives the viewer with real X input, as a user would: a file dragged from another program and
# dropped on the window, F12, F11 under a window manager, Ctrl+Q and Esc. Not part of `cargo test`
# (it needs a window manager and a GTK drag source); run it after changing the viewer:
#
#   sudo apt-get install xdotool openbox python3-gi gir1.2-gtk-3.0   # besides the README's line
#   cargo build --release && tools/viewer/input-check.sh [MODEL.glb]
#
# Prints one line per check and exits 1 if any failed.
set -u
here=$(cd "$(dirname "$0")" && pwd)
lodlab=${LODLAB:-$here/../../target/release/lodlab}
model=$(realpath "${1:-$here/../../../shared/models/Fox.glb}")
for tool in Xvfb xdotool openbox; do
    command -v $tool >/dev/null || { echo "input-check: $tool is not installed"; exit 1; }
done
python=${PYTHON:-/usr/bin/python3}
$python -c 'import gi' 2>/dev/null || { echo "input-check: $python has no GTK bindings (python3-gi)"; exit 1; }
work=$(mktemp -d)
export DISPLAY=:$((90 + RANDOM % 100)) WGPU_BACKEND=${WGPU_BACKEND:-vulkan}
export XDG_RUNTIME_DIR=$work/xdg && mkdir -m 700 "$XDG_RUNTIME_DIR"
Xvfb "$DISPLAY" -screen 0 1400x900x24 >/dev/null 2>&1 &
xvfb=$!
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$work"' EXIT
sleep 1
openbox >/dev/null 2>&1 &
failed=0
check() { if eval "$2"; then echo "ok    $1"; else echo "FAIL  $1"; failed=1; fi; }
# Waits up to $2 seconds for the command $1 to succeed.
until_ok() { for _ in $(seq $(($2 * 2))); do eval "$1" && return 0; sleep 0.5; done; return 1; }
viewer() {
    local args=("$@")
    [ ${#args[@]} -gt 0 ] || args=(--scene crowd --count 20)
    (cd "$work" && "$lodlab" view "${args[@]}" --size 1000x700 >"$work/log" 2>&1; echo "exit $?" >>"$work/log") &
    until_ok 'grep -q "first frame" "$work/log"' 120
    win=$(xdotool search --name "^lodlab$" | tail -1)
    xdotool windowactivate --sync "$win" 2>/dev/null || xdotool windowfocus "$win"
    sleep 2
}
size() { xdotool getwindowgeometry "$win" | awk '/Geometry/ {print $2}'; }

viewer
$python "$here/drag_source.py" "$model" >/dev/null 2>&1 &
until_ok 'xdotool search --name "^drag source$" >/dev/null' 20
src=$(xdotool search --name '^drag source$' | tail -1)
eval "$(xdotool getwindowgeometry --shell "$src")"
xdotool mousemove $((X + WIDTH / 2)) $((Y + HEIGHT / 2)) mousedown 1
for step in 1 2 3 4 5 6; do xdotool mousemove $((X - step * 120)) $((Y - step * 60)); sleep 0.2; done
xdotool mouseup 1
check "a dropped file opens" 'until_ok "grep -q \"opened $model\" \"$work/log\"" 60'

xdotool windowactivate --sync "$win" 2>/dev/null
xdotool key F12
check "F12 writes a screenshot in the working folder" 'until_ok "test -s \"$work/lodlab-screenshot-1.png\"" 30'
before=$(size)
xdotool key F11
check "F11 makes the window fullscreen" 'until_ok "test \"\$(size)\" = 1400x900" 20'
xdotool key F11
check "F11 again gives it back its size" 'until_ok "test \"\$(size)\" = $before" 20'
xdotool key ctrl+q
check "Ctrl+Q quits with exit 0" 'until_ok "grep -q \"^exit 0\" \"$work/log\"" 30'

rm -f "$work/log"
viewer
xdotool key Escape
check "Esc quits with exit 0" 'until_ok "grep -q \"^exit 0\" \"$work/log\"" 30'

# One horse standing in the middle of the view: a click there selects it, F frames it (the
# camera comes close), B prints the camera, Ctrl+C prints the view as a shot command.
rm -f "$work/log"
viewer --scene study --count 1
xdotool key space
eval "$(xdotool getwindowgeometry --shell "$win")"
# The 3D view is right of the 270-point panel; the wheel backs away from the horse first.
xdotool mousemove $((X + 270 + (WIDTH - 270) / 2)) $((Y + HEIGHT / 2))
for _ in 1 2 3 4 5 6 7 8; do xdotool click 5; sleep 0.2; done
sleep 1
xdotool click 1
sleep 1
xdotool key ctrl+c
check "Ctrl+C prints the view as a shot command" 'until_ok "grep -q \"this view as a command: lodlab shot\" \"$work/log\"" 20'
far=$(grep -o -- "--camera [^ ]*" "$work/log" | tail -1 | cut -d, -f3)
xdotool key f
sleep 1
xdotool key ctrl+c
sleep 1
near=$(grep -o -- "--camera [^ ]*" "$work/log" | tail -1 | cut -d, -f3)
check "a click selects the horse and F frames it ($far m -> $near m)" 'awk -v a="$far" -v b="$near" "BEGIN { exit !(b < a * 0.8) }"'
xdotool key b
check "B prints the camera as --camera" 'until_ok "grep -q \"camera bookmarked: --camera\" \"$work/log\"" 20'
xdotool key Escape
[ $failed = 0 ] || cat "$work/log"
exit $failed
