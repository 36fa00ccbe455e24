#!/usr/bin/env bash
# Tests of strata-viewer's window path under Xvfb (GLFW + ImGui on Mesa llvmpipe):
#   usage: window_tests.sh VIEWER REPO_ROOT
# Builds a 3-band model of the bumps-75 detail mesh (headless), then runs the window with a
# scripted drag of the cage (--script-drag over 20 frames, then the exact solve) and checks the
# benchmark JSON (frames drawn, drag steps solved, no GL errors, the exact solve's status) and
# the screenshot of the last frame. Exits 77 (skipped) without xvfb-run.
set -euo pipefail
VIEWER=$1
ROOT=$2
command -v xvfb-run >/dev/null || { echo "SKIP: xvfb-run not installed"; exit 77; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cat > "$T/bend.json" <<'JSON'
{"region": {"halfspace": {"point": [0, 0, 2.0], "normal": [0, 0, 1]}},
 "handle": {"halfspace": {"point": [0, 0, 4.5], "normal": [0, 0, 1]}},
 "transform": {"rotate": {"axis": [1, 0, 0], "degrees": 45, "pivot": [0, 0, 3.5]}}}
JSON
"$VIEWER" "$ROOT/assets/bumps-75/detail.obj" --layers 3 --save "$T/model.strata" --screenshot "$T/rest.png" \
  --size 320x240 >/dev/null
json=$(xvfb-run -a -s "-screen 0 1280x800x24" "$VIEWER" "$T/model.strata" --band 0 --script-drag "$T/bend.json" \
  --frames 20 --benchmark --size 800x600 --screenshot "$T/window.png")
echo "$json" | python3 -c "
import json, sys
r = json.loads(sys.stdin.read())
d = r['drag_frames']
print('window: %d frames, drag frames mean %.1f ms, max %.1f ms, %d drag steps solved, %s'
      % (r['frames']['count'], d['mean_ms'], d['max_ms'], r['drag_steps_solved'], r['status']))
assert r['gl_errors'] == 0, 'GL errors'
assert d['count'] >= 19, 'drag frames missing'
assert r['drag_steps_solved'] >= 1, 'no drag step solved'
assert r['status'].startswith('exact solve'), 'the exact solve did not finish: ' + r['status']
"
# drag_keeps MODEL BAND SCRIPT FRAMES COLOUR KEY WHAT: every frame of a scripted drag that shows a
# preview draws the colour map (the benchmark's preview_frames_KEY counts them).
drag_keeps() {
  local json
  json=$(xvfb-run -a -s "-screen 0 1280x800x24" "$VIEWER" "$1" --band "$2" --script-drag "$3" \
    --frames "$4" --benchmark --size 800x600 --color "$5" --screenshot "$T/$5_window.png")
  echo "$json" | python3 -c "
import json, sys
r = json.loads(sys.stdin.read())
print('window, $7: %d of %d frames that showed a drag preview drew it' % (r['preview_frames_$6'], r['preview_frames']))
assert r['gl_errors'] == 0, 'GL errors'
assert r['preview_frames'] > 0, 'no drag preview was shown'
assert r['preview_frames_$6'] == r['preview_frames'], 'the $7 went off during the drag'
"
}
# The scan's own colours stay on during the drag (--color scan): every drag frame draws them.
awk '/^v / {print $0, 0.9, 0.05, 0.05; next} {print}' "$ROOT/assets/bumps-75/detail.obj" >"$T/red.obj"
"$VIEWER" "$T/red.obj" --layers 3 --save "$T/red.strata" --screenshot "$T/red_rest.png" --size 320x240 >/dev/null
# (60 frames: the previews arrive as the worker solves drag steps, about 0.1 s each.)
drag_keeps "$T/red.strata" 0 "$T/bend.json" 60 scan scan_colours "scan colours"
# The scan's texture stays on during the drag too (--color texture; textured_plane.py's plane,
# its right half bent up about the y axis).
python3 "$(dirname "$0")/textured_plane.py" "$T/plane"
cat >"$T/fold.json" <<'JSON'
{"region": {"halfspace": {"point": [1.2, 0, 0], "normal": [1, 0, 0]}},
 "handle": {"halfspace": {"point": [1.8, 0, 0], "normal": [1, 0, 0]}},
 "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 30, "pivot": [1.2, 0, 0]}}}
JSON
"$VIEWER" "$T/plane/plane.obj" --layers 2 --save "$T/plane.strata" --screenshot "$T/plane_rest.png" --size 320x240 >/dev/null
drag_keeps "$T/plane.strata" 1 "$T/fold.json" 30 texture texture texture
# A drag whose region selects nothing on a plain mesh: the status names the cause (it read
# "exact solve: 0.000000 s", no solve having run).
cat >"$T/nowhere.json" <<'JSON'
{"region": {"sphere": {"center": [100, 100, 100], "radius": 0.1}},
 "handle": {"sphere": {"center": [100, 100, 100], "radius": 0.05}},
 "transform": {"rotate": {"axis": [1, 0, 0], "degrees": 10, "pivot": [0, 0, 3.5]}}}
JSON
set +e
xvfb-run -a -s "-screen 0 1280x800x24" "$VIEWER" "$ROOT/assets/bumps-75/detail.obj" --script-drag "$T/nowhere.json" \
  --frames 5 --benchmark --size 320x240 --screenshot "$T/nowhere.png" >"$T/out" 2>"$T/err"
rc=$?
set -e
echo "window, a drag selecting nothing: exit $rc, $(cat "$T/err")"
[ "$rc" = 1 ] && grep -q "the region selects no vertex" "$T/err" && ! grep -q "exact solve" "$T/out" ||
  { echo "a drag selecting nothing was not reported: exit $rc"; cat "$T/out"; exit 1; }
# --save and --export are refused where nothing would write them (the scripted window ignored them).
set +e
"$VIEWER" "$T/model.strata" --script-drag "$T/bend.json" --screenshot "$T/x.png" --save "$T/never.strata" 2>"$T/err"
rc=$?
set -e
[ "$rc" = 1 ] && grep -q -- "--save and --export are for --screenshot renders" "$T/err" && [ ! -e "$T/never.strata" ] ||
  { echo "--save with --script-drag: exit $rc, $(cat "$T/err")"; exit 1; }
s=$(python3 "$(dirname "$0")/png_stats.py" "$T/window.png")
python3 -c "
import json, sys
s = json.loads(sys.argv[1])
assert s['width'] == 800 and s['height'] == 600, s
assert s['foreground'] > 0.05, s
print('window screenshot:', s)
" "$s"
echo "window tests passed"
