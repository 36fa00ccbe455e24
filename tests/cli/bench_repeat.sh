#!/usr/bin/env bash
# strata_bench --repeat N: N reconstructions with one solver object, each run's time listed, the
# reported times their median, the runs identical (else an error); a bad count is a usage error.
# --min-run-seconds S: more runs past --repeat until their wall times add up to S (100 at most).
# --rounds R: the sizes R times over, interleaved, each size's runs of all rounds taken together.
# Usage: bash bench_repeat.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: bench_repeat.sh <path-to-strata> <tests/data dir>}
BENCH=$(dirname "$STRATA")/strata_bench
fail() { echo "FAIL: $*" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

"$BENCH" --sizes 3000 --jitter 0.4 --solver multigrid --repeat 3 --min-run-seconds 0 --out "$TMP/r.json" >/dev/null 2>"$TMP/err" ||
  fail "strata_bench --repeat 3 exited non-zero: $(cat "$TMP/err")"
python3 - "$TMP/r.json" <<'PY' || fail "report check"
import json, sys
d = json.load(open(sys.argv[1]))
r = d["results"][0]
assert r["repeat"] == 3 and r["runs"] == 3, (r["repeat"], r["runs"])
runs = r["seconds"]["reconstruct_runs"]
assert len(runs) == 3 and all(t > 0 for t in runs), runs
assert r["seconds"]["reconstruct"] == sorted(runs)[1], (runs, r["seconds"]["reconstruct"])
assert len(r["cpu_seconds"]["reconstruct_runs"]) == 3
# A first reconstruction: the solver's setup plus the first run.
first = r["seconds"]["first_reconstruction"]
assert abs(first - (r["seconds"]["setup"] + runs[0])) <= 1e-9 * first, (first, r["seconds"])
assert r["targets"]["all"], r["targets"]
# Memory per prism: the peak's growth over the floor run's (a smaller pipeline in its own child),
# per prism added; and the whole process's peak per prism.
m, f = r["memory"], d["memory_floor"]
assert 0 < f["prisms"] < r["prisms"] and 0 < f["peak_rss_bytes"] <= m["peak_rss_bytes"], (f, m)
slope = (m["peak_rss_bytes"] - f["peak_rss_bytes"]) / (r["prisms"] - f["prisms"])
assert abs(m["bytes_per_prism"] - slope) <= 1e-9 * slope, (m, f)
assert abs(m["whole_process_bytes_per_prism"] - m["peak_rss_bytes"] / r["prisms"]) <= 1e-6, m
assert d["targets"]["memory_le_1kb_per_prism"]["values"]["3000"] == m["bytes_per_prism"]
for k in ("max_error_relative_to_own_target", "rms_error_relative_to_own_target"):
    assert r["accuracy"]["volumes"][k] > 0, r["accuracy"]
# No --round-trip: no round trip measured, and its target not judged.
assert r["accuracy"]["round_trip"] is None, r["accuracy"]
assert d["targets"]["round_trip_within_half_a_percent"]["pass"] is None, d["targets"]
PY
grep -q "reconstruct run 3 in" "$TMP/err" || fail "no progress line for the third run"

# --round-trip: one more clean start over the unedited base, its largest vertex distance from the
# rest detail over the diagonal (the multigrid preset comes back well within 0.5% at this size).
"$BENCH" --sizes 3000 --jitter 0.4 --solver multigrid --repeat 1 --min-run-seconds 0 --round-trip \
  --out "$TMP/t.json" >/dev/null 2>"$TMP/err" || fail "strata_bench --round-trip exited non-zero: $(cat "$TMP/err")"
python3 - "$TMP/t.json" <<'PY' || fail "--round-trip report check"
import json, sys
d = json.load(open(sys.argv[1]))
r = d["results"][0]
t = r["accuracy"]["round_trip"]
assert t["converged"] and t["new_pairs"] == 0 and t["within_half_a_percent"], t
assert 0 < t["max_vertex_distance"] <= 0.005 * t["bbox_diagonal"], t
assert abs(t["max_vertex_distance_over_diagonal"] * t["bbox_diagonal"] - t["max_vertex_distance"]) <= 1e-12, t
assert r["seconds"]["round_trip"] > 0, r["seconds"]
g = d["targets"]["round_trip_within_half_a_percent"]
assert g["pass"] is True and g["values"]["3000"] == t["max_vertex_distance_over_diagonal"], g
PY

# One run asked for, but at least 0.3 s of runs: more runs, the median of them all (one run only if
# it alone took 0.3 s, as the first can under the sanitizers).
"$BENCH" --sizes 3000 --jitter 0.4 --solver multigrid --repeat 1 --min-run-seconds 0.3 --out "$TMP/m.json" \
  >/dev/null 2>"$TMP/err" || fail "strata_bench --min-run-seconds 0.3 exited non-zero: $(cat "$TMP/err")"
python3 - "$TMP/m.json" <<'PY' || fail "--min-run-seconds report check"
import json, statistics, sys
d = json.load(open(sys.argv[1]))
assert d["min_run_seconds"] == 0.3, d["min_run_seconds"]
r = d["results"][0]
runs = r["seconds"]["reconstruct_runs"]
assert r["repeat"] == 1 and r["runs"] == len(runs) and (len(runs) > 1 or runs[0] >= 0.3), (r["runs"], runs)
# The runs stop as soon as they add up to 0.3 s (or at 100): without the last one they did not.
assert sum(runs[:-1]) < 0.3 and (sum(runs) >= 0.3 or len(runs) == 100), runs
assert r["seconds"]["reconstruct"] == statistics.median(runs), (runs, r["seconds"]["reconstruct"])
assert len(r["cpu_seconds"]["reconstruct_runs"]) == len(runs)
PY

# Two rounds of two sizes: the children run 2000, 3000, 2000, 3000; each size's runs are both
# children's, its times their medians, and each child's own medians are listed.
"$BENCH" --sizes 2000,3000 --jitter 0.4 --solver multigrid --repeat 2 --min-run-seconds 0 --rounds 2 \
  --out "$TMP/rounds.json" >/dev/null 2>"$TMP/err" || fail "strata_bench --rounds 2 exited non-zero: $(cat "$TMP/err")"
[ "$(grep -o 'size [0-9]* (bumps), round [12] of 2' "$TMP/err" | tr '\n' ' ')" = \
  "size 2000 (bumps), round 1 of 2 size 3000 (bumps), round 1 of 2 size 2000 (bumps), round 2 of 2 size 3000 (bumps), round 2 of 2 " ] ||
  fail "--rounds 2: the children did not run interleaved: $(grep 'round' "$TMP/err")"
python3 - "$TMP/rounds.json" <<'PY' || fail "--rounds report check"
import json, statistics, sys
d = json.load(open(sys.argv[1]))
assert d["rounds"] == 2, d["rounds"]
for r in d["results"]:
    runs = r["seconds"]["reconstruct_runs"]
    assert r["runs"] == len(runs) == 4 and len(r["rounds"]) == 2, (r["runs"], runs, r["rounds"])
    assert r["seconds"]["reconstruct"] == statistics.median(runs), (runs, r["seconds"]["reconstruct"])
    assert len(r["seconds"]["solve_runs"]) == 4 and r["seconds"]["solve"] == statistics.median(r["seconds"]["solve_runs"])
    assert r["cpu_seconds"]["reconstruct"] == statistics.median(r["cpu_seconds"]["reconstruct_runs"])
    firsts = [c["first_reconstruction"] for c in r["rounds"]]
    assert r["seconds"]["first_reconstruction"] == statistics.median(firsts), (firsts, r["seconds"])
    assert r["memory"]["peak_rss_bytes"] == max(c["peak_rss_bytes"] for c in r["rounds"])
    thr = r["throughput"]["prisms_per_second_per_multigrid_pass"]
    assert abs(thr - r["prisms"] / r["seconds"]["solve"]) <= 1e-9 * thr, (thr, r["seconds"]["solve"])
    assert r["targets"]["all"], r["targets"]
PY

set +e
for bad in 0 -1 x 21 2x; do
  err=$("$BENCH" --sizes 3000 --rounds "$bad" 2>&1 >/dev/null); rc=$?
  [ "$rc" -eq 2 ] || fail "--rounds $bad exited $rc, expected 2"
  grep -qF -- "--rounds is a whole number from 1 to 20, got '$bad'" <<<"$err" || fail "--rounds $bad: $err"
done
for bad in 0 -1 x 101 99999999999 2x; do
  err=$("$BENCH" --sizes 3000 --repeat "$bad" 2>&1 >/dev/null); rc=$?
  [ "$rc" -eq 2 ] || fail "--repeat $bad exited $rc, expected 2"
  grep -qF -- "--repeat is a whole number from 1 to 100, got '$bad'" <<<"$err" || fail "--repeat $bad: $err"
done
for bad in -1 x 3601 nan 1s; do
  err=$("$BENCH" --sizes 3000 --min-run-seconds "$bad" 2>&1 >/dev/null); rc=$?
  [ "$rc" -eq 2 ] || fail "--min-run-seconds $bad exited $rc, expected 2"
  grep -qF -- "--min-run-seconds is a number of seconds from 0 to 3600, got '$bad'" <<<"$err" ||
    fail "--min-run-seconds $bad: $err"
done
set -e
echo "bench_repeat: all checks passed"
