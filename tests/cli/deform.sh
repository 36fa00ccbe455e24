#!/usr/bin/env bash
# `strata deform`: an elbow bend of a generated bumpy cylinder by volumes and by vectors, the JSON
# report's fields and figures; then bad edit scripts and bad selections, each a clear error
# naming the script, a non-zero exit and no output file.
# Usage: bash deform.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: deform.sh <path-to-strata> <tests/data dir>}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
source "$(dirname "${BASH_SOURCE[0]}")/lib/expect.sh"

"$STRATA" generate --case bumps --triangles 8000 --out-dir "$TMP/case" >/dev/null
MESH="$TMP/case/detail.obj"
cat >"$TMP/bend.json" <<'JSON'
{"region": {"halfspace": {"point": [0, 0, 2], "normal": [0, 0, 1]}},
 "handle": {"halfspace": {"point": [0, 0, 3.5], "normal": [0, 0, 1]}},
 "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 90, "pivot": [1.2, 0, 2.5]}}}
JSON
for m in volumes vectors; do
  "$STRATA" deform "$MESH" --edit "$TMP/bend.json" --method "$m" -o "$TMP/$m.obj" --write-base "$TMP/base_$m.obj" \
    --report "$TMP/$m.json" >"$TMP/$m.stdout" 2>"$TMP/$m.stderr"
  grep -q "intersections" "$TMP/$m.stdout" || { echo "FAIL: no summary for $m" >&2; exit 1; }
  "$STRATA" stats "$TMP/$m.obj" >/dev/null
done

python3 - "$TMP" <<'PY'
import json, sys
tmp = sys.argv[1]
errors = []
for method in ("volumes", "vectors"):
    r = json.load(open(f"{tmp}/{method}.json"))
    e = r["edits"][0]
    for key in ("region_vertices", "handle_vertices", "region_faces", "encoding", "volume_metrics", "timing_seconds", "iterations"):
        if key not in e:
            errors.append(f"{method}: edits[0] lacks {key}")
    for key in ("select", "decompose", "encode", "setup", "edit", "solve", "metrics"):
        if key not in e["timing_seconds"]:
            errors.append(f"{method}: no timing of {key}")
    if not (0 < e["handle_vertices"] < e["region_vertices"]):
        errors.append(f"{method}: sizes {e['handle_vertices']} / {e['region_vertices']}")
    if method == "volumes":
        vm = e["volume_metrics"]
        if not (vm["max_relative_error"] <= 1e-3 and vm["rms_relative_error"] <= 1e-4):
            errors.append(f"volumes: prism errors {vm['max_relative_error']} / {vm['rms_relative_error']}")
        if r["intersections"]["new_pairs"] != 0:
            errors.append(f"volumes: {r['intersections']['new_pairs']} new pairs")
    else:
        if e["iterations"] is not None:
            errors.append("vectors: iterations should be null")
        if not e["volume_metrics"]["max_relative_error"] > 1.0:
            errors.append("vectors: volumes unexpectedly kept")
if errors:
    print("\n".join("FAIL: " + x for x in errors), file=sys.stderr)
    sys.exit(1)
PY

# --strict: exit 3 (outputs written) exactly when the report has warnings; the bend above has
# none, and a solve stopped short (one cycle, no polish, no retry) misses the tolerance, which a
# warning naming the edit says (on stderr too, without --strict).
got=0
"$STRATA" deform "$MESH" --edit "$TMP/bend.json" --strict -q -o "$TMP/strict_ok.obj" --report "$TMP/strict_ok.json" \
  >/dev/null 2>"$TMP/strict_ok.err" || got=$?
[ "$got" = 0 ] || { echo "FAIL: --strict on the bend exited $got: $(cat "$TMP/strict_ok.err")" >&2; exit 1; }
SHORT=(--set max_cycles=1 --set final_max_cycles=1 --set max_final_steps=0 --set fallback_schedule=false
  --set retry_on_new_intersections=false --set fold_repair_rounds=0)
"$STRATA" deform "$MESH" --edit "$TMP/bend.json" "${SHORT[@]}" -q -o "$TMP/short.obj" --report "$TMP/short.json" \
  >/dev/null 2>"$TMP/short.err" || { echo "FAIL: a short solve without --strict failed" >&2; exit 1; }
got=0
"$STRATA" deform "$MESH" --edit "$TMP/bend.json" "${SHORT[@]}" --strict -q -o "$TMP/short_strict.obj" \
  >/dev/null 2>"$TMP/short_strict.err" || got=$?
[ "$got" = 3 ] && [ -s "$TMP/short_strict.obj" ] || { echo "FAIL: --strict on a short solve exited $got" >&2; exit 1; }
python3 - "$TMP" <<'PY'
import json, re, sys
tmp = sys.argv[1]
ok, short = json.load(open(tmp + "/strict_ok.json")), json.load(open(tmp + "/short.json"))
err, strict_err = open(tmp + "/short.err").read(), open(tmp + "/short_strict.err").read()
problems = []
if ok["warnings"] != []: problems.append("warnings on the bend: %r" % ok["warnings"])
it = short["edits"][0]["iterations"]
pairs = short["intersections"]["new_pairs"]
w = short["warnings"]
m = re.fullmatch(r"edit 1: not converged: the max relative prism volume error (\S+) is above the tolerance (\S+)",
                 w[0] if w else "")
if it["converged"] or not m or float(m.group(1)) != it["solver_max_relative_error"] or \
        len(w) != 1 + (pairs > 0) or (pairs > 0 and w[1] != "%d new intersecting pairs of triangles" % pairs):
    problems.append("short: warnings %r (converged %r, new pairs %d)" % (w, it["converged"], pairs))
for x in w:
    if "strata: warning: " + x not in err: problems.append("stderr lacks the warning %r" % x)
    if "strata: error: --strict: " + x not in strict_err: problems.append("--strict stderr lacks %r" % x)
if problems:
    print("FAIL (--strict):\n  " + "\n  ".join(problems), file=sys.stderr)
    sys.exit(1)
PY

# Bad scripts and selections: exit 1, the script's name and the problem on stderr, no output.
expect_error() {  # <name> <expected text> <script text>
  printf '%s' "$3" >"$TMP/$1.json"
  rm -f "$TMP/out.obj"
  expect_exit 1 "$1.json" "$TMP/err" "$STRATA" deform "$MESH" --edit "$TMP/$1.json" -o "$TMP/out.obj" -q
  grep -q "$2" "$TMP/err" || { echo "FAIL: $1: expected '$2' in: $(cat "$TMP/err")" >&2; exit 1; }
  [ ! -e "$TMP/out.obj" ] || { echo "FAIL: $1 left an output file" >&2; exit 1; }
  ls "$TMP" | grep -q '\.tmp' && { echo "FAIL: $1 left a temporary file" >&2; exit 1; }
  return 0
}
H='"handle": {"halfspace": {"point": [0, 0, 3.5], "normal": [0, 0, 1]}}'
R='"region": {"halfspace": {"point": [0, 0, 2], "normal": [0, 0, 1]}}'
T='"transform": {"rotate": {"axis": [0, 1, 0], "degrees": 90}}'
expect_error truncated "not valid JSON" "{$R, $H, \"transform\": {\"rot"
expect_error typo 'unknown key "rotat"' "{$R, $H, \"transform\": {\"rotat\": {}}}"
expect_error empty_region "region selects no vertex" "{\"region\": {\"sphere\": {\"center\": [50, 0, 0], \"radius\": 1}}, $H, $T}"
expect_error empty_handle "handle selects no vertex" "{$R, \"handle\": {\"sphere\": {\"center\": [50, 0, 0], \"radius\": 1}}, $T}"
expect_error whole_handle "handle is the whole region" "{$R, \"handle\": {\"halfspace\": {\"point\": [0, 0, 1], \"normal\": [0, 0, 1]}}, $T}"
expect_error whole_mesh "whole mesh" "{\"region\": {\"box\": {\"min\": [-9, -9, -9], \"max\": [9, 9, 9]}}, $H, $T}"
expect_error bad_index "out of range" "{$R, \"handle\": {\"vertices\": [99999999]}, $T}"
expect_error zero_axis "must not be zero" "{$R, $H, \"transform\": {\"rotate\": {\"axis\": [0, 0, 0], \"degrees\": 90}}}"
# A result the writer refuses is named as the edited mesh, not as the output file ("out.obj: face 0
# has zero area"); a solver failure names the edit (a fairing system that could not be factorized
# was reported without either).
expect_error huge_scale "the mesh edited by .*huge_scale.json: face [0-9]* has zero area for the mesh's size (area [-+.e0-9]*, bounding-box diagonal [-+.e0-9]*; vertex [0-9]* at (.*) is the farthest from the others' median: an outlier?) (not written to .*out.obj)" \
  "{$R, $H, \"transform\": {\"scale\": [1e6, 1e6, 1e6]}}"
expect_error far_then_near "far_then_near.json: edit 2: the region's fairing system could not be factorized" \
  "{\"edits\": [{$R, $H, \"transform\": {\"translate\": [1e6, 0, 0]}}, {$R, $H, \"transform\": {\"translate\": [1, 0, 0]}}]}"
rm -f "$TMP/out.obj"
expect_exit 1 "missing.json" "$TMP/err" "$STRATA" deform "$MESH" --edit "$TMP/missing.json" -o "$TMP/out.obj" -q
[ ! -e "$TMP/out.obj" ] || { echo "FAIL: missing script left an output" >&2; exit 1; }
# Two outputs on one file are refused before any work.
for opt in "--report" "--write-base"; do
  expect_exit 1 "same file" "$TMP/err" "$STRATA" deform "$MESH" --edit "$TMP/bend.json" -o "$TMP/same.obj" $opt "$TMP/same.obj" -q
  [ ! -e "$TMP/same.obj" ] || { echo "FAIL: $opt left an output" >&2; exit 1; }
done
# A region with a sharp corner: the vertices above z = 2 and the one just below that line whose
# x is largest, which is then the only region vertex of three faces. By default the outside
# vertices of those faces are solved too (EditOptions::fill_region_corners: the report's region
# grows); --exact-region edits the selection as it is.
python3 - "$MESH" "$TMP/corner.json" <<'PY'
import json, sys
verts = [tuple(map(float, l.split()[1:4])) for l in open(sys.argv[1]) if l.startswith("v ")]
region = [i for i, v in enumerate(verts) if v[2] >= 2.0]
below = max((v[2] for v in verts if v[2] < 2.0))
region.append(max((i for i, v in enumerate(verts) if v[2] == below), key=lambda i: verts[i][0]))
json.dump({"region": {"vertices": region}, "handle": {"halfspace": {"point": [0, 0, 3.5], "normal": [0, 0, 1]}},
           "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 45, "pivot": [1.2, 0, 2.5]}}},
          open(sys.argv[2], "w"))
print(len(region), file=open(sys.argv[2] + ".count", "w"))
PY
for x in filled exact; do
  flag=""
  [ "$x" = exact ] && flag="--exact-region"
  "$STRATA" deform "$MESH" --edit "$TMP/corner.json" $flag -o "$TMP/corner_$x.obj" --report "$TMP/corner_$x.json" -q >/dev/null
done
python3 - "$TMP" <<'PY'
import json, sys
tmp = sys.argv[1]
selected = int(open(f"{tmp}/corner.json.count").read())
filled = json.load(open(f"{tmp}/corner_filled.json"))["edits"][0]["region_vertices"]
exact = json.load(open(f"{tmp}/corner_exact.json"))["edits"][0]["region_vertices"]
if exact != selected or not filled > selected:
    print(f"FAIL: corner region: selected {selected}, --exact-region {exact}, filled {filled}", file=sys.stderr)
    sys.exit(1)
PY
echo "deform: ok"
