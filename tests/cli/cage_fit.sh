#!/usr/bin/env bash
# `strata cage fit` writes a Loop cage that `strata stats` reads back, and a JSON report of the
# fitting error. Usage: bash cage_fit.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: cage_fit.sh <path-to-strata> <tests/data dir>}
STRATA=$(cd "$(dirname "$STRATA")" && pwd)/$(basename "$STRATA")
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
ls -A | grep -q '\.tmp' && fail "temporary file left behind"
echo "cage_fit: all checks passed"
