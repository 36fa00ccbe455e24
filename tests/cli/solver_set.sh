#!/usr/bin/env bash
# `--set NAME=VALUE` on strata reconstruct and deform: the option reaches the solver (the result
# changes, the report lists it), and a bad name or value is a usage error naming it, with no
# output written. Usage: bash solver_set.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: solver_set.sh <path-to-strata> <tests/data dir>}
DATA=${2:?usage: solver_set.sh <path-to-strata> <tests/data dir>}
fail() { echo "FAIL: $*" >&2; exit 1; }
source "$(dirname "${BASH_SOURCE[0]}")/lib/expect.sh"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

"$STRATA" generate --case bumps --triangles 2000 --out-dir "$TMP/case" >/dev/null
rec() {  # rec NAME [options...]
  local name=$1
  shift
  "$STRATA" reconstruct --detail "$TMP/case/detail.obj" --base "$TMP/case/base.obj" \
    --edited-base "$TMP/case/edited_base.obj" -o "$TMP/$name.obj" --report "$TMP/$name.json" -q "$@" >/dev/null
}
rec default
rec set --set volume_scales=2 --set retry_volume_iterations=0
cmp -s "$TMP/default.obj" "$TMP/set.obj" && fail "--set volume_scales=2 left the result unchanged"
python3 - "$TMP" <<'PY' || fail "report check"
import json, sys
t = sys.argv[1]
d, s = json.load(open(t + "/default.json")), json.load(open(t + "/set.json"))
assert d["set"] == [], d["set"]
assert s["set"] == ["volume_scales=2", "retry_volume_iterations=0"], s["set"]
assert s["volume_metrics"]["max_relative_error"] <= 1e-3, s["volume_metrics"]
PY
# The same options again give the same file: --set is applied the same way every time.
rec set2 --set volume_scales=2 --set retry_volume_iterations=0
cmp -s "$TMP/set.obj" "$TMP/set2.obj" || fail "the same --set gave another result"

set +e
for bad in "frob=1:unknown reconstruction option 'frob'" "volume_scales=two:'two' is not a whole number" \
  "tolerance:not NAME=VALUE" "step_solver=fast:is not jacobi_cg, direct or multigrid"; do
  kv=${bad%%:*} want=${bad#*:}
  err=$(rec bad --set "$kv" 2>&1); rc=$?
  [ "$rc" -eq 2 ] || fail "--set $kv exited $rc, expected 2"
  grep -qF -- "$want" <<<"$err" || fail "--set $kv: message does not say '$want': $err"
  [ ! -e "$TMP/bad.obj" ] || fail "--set $kv wrote an output"
done
# Parsed, but out of the solver's range: a usage error too, found before any input is read (it
# was found in the solve, after reading, encoding and counting intersections), and with
# --method vectors, which runs no volume solve (it passed unused).
set -e
expect_exit 2 "reconstruction option volume_scales = 0 is out of range (1-1000) (with the legacy solver)" \
  "$TMP/err.txt" rec range --set volume_scales=0
[ ! -e "$TMP/range.obj" ] || fail "--set volume_scales=0 wrote an output"
expect_exit 2 "tolerance = -1 is out of range" "$TMP/err.txt" rec range --method vectors --set tolerance=-1
expect_exit 2 "tolerance = -1 is out of range" "$TMP/err.txt" \
  "$STRATA" reconstruct --detail "$TMP/missing.obj" --base "$TMP/missing.obj" --edited-base "$TMP/missing.obj" \
  -o "$TMP/m.obj" --set tolerance=-1
# deform takes it too.
expect_exit 2 "unknown reconstruction option 'frob'" "$TMP/err.txt" \
  "$STRATA" deform "$TMP/case/detail.obj" --edit "$DATA/edits/man_arm.json" --set frob=1 -o "$TMP/d.obj"
[ ! -e "$TMP/d.obj" ] || fail "deform --set frob=1 wrote an output"
echo "solver_set: all checks passed"
