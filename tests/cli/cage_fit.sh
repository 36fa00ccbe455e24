#!/usr/bin/env bash
# `strata cage fit` writes a Loop cage that `strata stats` reads back, and a JSON report of the
# fitting error. Usage: bash cage_fit.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: cage_fit.sh <path-to-strata> <tests/data dir>}
STRATA=$(cd "$(dirname "$STRATA")" && pwd)/$(basename "$STRATA")
source "$(dirname "${BASH_SOURCE[0]}")/lib/expect.sh"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
cd "$TMP"
fail() { echo "FAIL: $*" >&2; exit 1; }

"$STRATA" generate --case bumps --out-dir case >/dev/null 2>&1
"$STRATA" cage fit case/base.obj --faces 300 -o cage.obj --report fit.json -q >summary.txt
[ -s cage.obj ] || fail "no cage written"
"$STRATA" stats --json cage.obj >stats.json || fail "the cage does not read back"
python3 - <<'PY' || fail "report or cage check failed"
import json
r = json.load(open("fit.json"))
s = json.load(open("stats.json"))
assert r["cage"]["faces"] == s["faces"], (r["cage"], s["faces"])
assert 250 <= s["faces"] <= 300, s["faces"]
assert not s["closed"], "the tube's cage must stay open"
f = r["fit"]
assert 0 < f["rms_error"] <= f["max_error"] < 1e-2, f
assert 0 < f["scan_rms_distance"] < 1e-2, f
assert f["scan_projection_fallback"] == 0, f
for k in ("read", "smooth", "decimate", "fit", "write"):
    assert r["timing"][k] >= 0, k
PY
grep -q "^cage " summary.txt || fail "no summary printed"

# deform over the fitted cage's limit surface: the selections pick cage vertices
cat >bend.json <<'JSON'
{"region": {"halfspace": {"point": [0, 0, 1.6], "normal": [0, 0, 1]}},
 "handle": {"halfspace": {"point": [0, 0, 2.8], "normal": [0, 0, 1]}},
 "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 30, "pivot": [0, 0, 1.6]}}}
JSON
"$STRATA" deform case/detail.obj --edit bend.json --base subdiv --cage cage.obj --method vectors -o bent.obj \
  --write-base bent_cage.obj --report deform.json -q >/dev/null || fail "deform --base subdiv failed"
python3 - <<'PY' || fail "deform --base subdiv report check failed"
import json
r = json.load(open("deform.json"))
assert r["base"] == "subdiv" and r["cage"]["fitted"] is False, r["cage"]
e = r["edits"][0]
assert e["region_vertices"] > e["handle_vertices"] > 0, e
assert 0 < e["region_faces"] < r["input"]["faces"], e
PY
[ -s bent_cage.obj ] || fail "no edited cage written"
cmp -s cage.obj bent_cage.obj && fail "the edited cage equals the cage"
expect_exit 2 "need --base subdiv" err.txt "$STRATA" deform case/detail.obj --edit bend.json --cage cage.obj -o x.obj
[ ! -e x.obj ] || fail "an output was written for --cage without --base subdiv"
expect_exit 2 "cage-tags needs --cage" err.txt "$STRATA" deform case/detail.obj --edit bend.json --base subdiv \
  --cage-tags tags.json -o x.obj
expect_exit 2 "cage-faces applies to a fitted cage, not to --cage" err.txt "$STRATA" deform case/detail.obj \
  --edit bend.json --base subdiv --cage cage.obj --cage-faces 100 -o x.obj
[ ! -e x.obj ] || fail "an output was written after a usage error"
# a quad cage from a file is a Catmull-Clark cage; --write-base keeps its quads
python3 - <<'PY'
import math
n, m = 8, 7
with open("quad.obj", "w") as f:
    for k in range(m):
        for i in range(n):
            a = 2 * math.pi * i / n
            f.write(f"v {1.08 * math.cos(a)} {1.08 * math.sin(a)} {6.0 * k / (m - 1)}\n")
    for k in range(m - 1):
        for i in range(n):
            a, b = k * n + i + 1, k * n + (i + 1) % n + 1
            f.write(f"f {a} {b} {b + n} {a + n}\n")
PY
"$STRATA" deform case/detail.obj --edit bend.json --base subdiv --cage quad.obj -o bent_q.obj \
  --write-base bent_quad.obj --report deform_q.json -q >/dev/null || fail "deform over a quad cage failed"
python3 - <<'PY' || fail "quad cage check failed"
import json
r = json.load(open("deform_q.json"))
assert r["cage"]["scheme"] == "catmull-clark" and r["cage"]["faces"] == 48, r["cage"]
assert r["intersections"]["new_pairs"] == 0, r["intersections"]
faces = [l.split()[1:] for l in open("bent_quad.obj") if l.startswith("f ")]
assert len(faces) == 48 and all(len(f) == 4 for f in faces), "the edited cage lost its quads"
moved = [l for l, k in zip(open("quad.obj"), open("bent_quad.obj")) if l.startswith("v ") and l.split() != k.split()]
assert moved, "the edited quad cage did not move"
PY
# --handle-rings: negative solves every vertex over a cage; rejected over the faired base
"$STRATA" deform case/detail.obj --edit bend.json --base subdiv --cage quad.obj --handle-rings -1 -o all.obj \
  -q >/dev/null || fail "--handle-rings -1 over a cage failed"
expect_exit 2 "handle-rings must be >= 0" err.txt "$STRATA" deform case/detail.obj --edit bend.json --handle-rings -1 -o x.obj
[ ! -e x.obj ] || fail "an output was written for a negative --handle-rings"
ls -A | grep -q '\.tmp' && fail "temporary file left behind"
echo "cage_fit: all checks passed"
