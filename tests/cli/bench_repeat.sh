#!/usr/bin/env bash
# strata_bench --repeat N: N reconstructions with one solver object, each run's time listed, the
# reported times their median, the runs identical (else an error); a bad count is a usage error.
# Usage: bash bench_repeat.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: bench_repeat.sh <path-to-strata> <tests/data dir>}
BENCH=$(dirname "$STRATA")/strata_bench
fail() { echo "FAIL: $*" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

"$BENCH" --sizes 3000 --jitter 0.4 --solver multigrid --repeat 3 --out "$TMP/r.json" >/dev/null 2>"$TMP/err" ||
  fail "strata_bench --repeat 3 exited non-zero: $(cat "$TMP/err")"
python3 - "$TMP/r.json" <<'PY' || fail "report check"
import json, sys
d = json.load(open(sys.argv[1]))
r = d["results"][0]
assert r["repeat"] == 3, r["repeat"]
runs = r["seconds"]["reconstruct_runs"]
assert len(runs) == 3 and all(t > 0 for t in runs), runs
assert r["seconds"]["reconstruct"] == sorted(runs)[1], (runs, r["seconds"]["reconstruct"])
assert len(r["cpu_seconds"]["reconstruct_runs"]) == 3
# A first reconstruction: the solver's setup plus the first run.
first = r["seconds"]["first_reconstruction"]
assert abs(first - (r["seconds"]["setup"] + runs[0])) <= 1e-9 * first, (first, r["seconds"])
assert r["targets"]["all"], r["targets"]
PY
grep -q "reconstruct run 3 in" "$TMP/err" || fail "no progress line for the third run"

set +e
for bad in 0 -1 x 101 99999999999 2x; do
  err=$("$BENCH" --sizes 3000 --repeat "$bad" 2>&1 >/dev/null); rc=$?
  [ "$rc" -eq 2 ] || fail "--repeat $bad exited $rc, expected 2"
  grep -qF -- "--repeat is a whole number from 1 to 100, got '$bad'" <<<"$err" || fail "--repeat $bad: $err"
done
set -e
echo "bench_repeat: all checks passed"
