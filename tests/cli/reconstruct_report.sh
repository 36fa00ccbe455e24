#!/usr/bin/env bash
# `strata generate` a small paper case, then `strata reconstruct` it by volumes and by vectors and
# check the JSON reports: every documented field present, volumes fold-free and volume-exact,
# vectors folding. Usage: bash reconstruct_report.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: reconstruct_report.sh <path-to-strata> <tests/data dir>}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
source "$(dirname "${BASH_SOURCE[0]}")/lib/expect.sh"

"$STRATA" generate --case bumps --triangles 2000 --out-dir "$TMP/case" >/dev/null
for m in volumes vectors; do
  "$STRATA" reconstruct --detail "$TMP/case/detail.obj" --base "$TMP/case/base.obj" \
    --edited-base "$TMP/case/edited_base.obj" --method "$m" -o "$TMP/$m.obj" --report "$TMP/$m.json" \
    >"$TMP/$m.stdout" 2>"$TMP/$m.stderr"
  grep -q "prism volumes" "$TMP/$m.stdout" || { echo "FAIL: no human summary for $m" >&2; exit 1; }
  # The output is a valid mesh that strata reads back.
  "$STRATA" stats --json "$TMP/$m.obj" >"$TMP/$m.stats.json"
done

# A detail far from its base (another placement) is not a displacement of it: a warning says so
# (the solve still runs; its report counts the fallbacks), and a detail over its base gets none.
grep -q "warning" "$TMP/volumes.stderr" && { echo "FAIL: a warning on the paper's case" >&2; exit 1; }
python3 - "$TMP/case/detail.obj" "$TMP/far.obj" <<'PY'
import sys
out = open(sys.argv[2], "w")
for line in open(sys.argv[1]):
    if line.startswith("v "):
        x, y, z = map(float, line.split()[1:4])
        line = "v %r %r %r\n" % (x + 100.0, y, z)
    out.write(line)
PY
"$STRATA" reconstruct -q --detail "$TMP/far.obj" --base "$TMP/case/base.obj" --edited-base "$TMP/case/base.obj" \
  --method vectors -o "$TMP/far_out.obj" >/dev/null 2>"$TMP/far.stderr"
grep -q "far.obj does not look like a displacement of" "$TMP/far.stderr" ||
  { echo "FAIL: no warning for a detail far from its base:" >&2; cat "$TMP/far.stderr" >&2; exit 1; }

# A base of polygons is cut into triangles by its shape: an edited base listing the same quad, but
# shaped so that its other diagonal cuts it better, takes the base's triangles (it was refused:
# "face 0 of the edited base is (1,2,3), in base ... it is (0,1,2)").
printf 'v 0 0 0\nv 1 0 0\nv 1.5 1.5 0\nv 0 1 0\nf 1 2 3 4\n' >"$TMP/quad_base.obj"
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv -0.5 1.5 0\nf 1 2 3 4\n' >"$TMP/quad_edited.obj"
python3 - "$TMP/quad_detail.obj" <<'PY'
import sys
out = open(sys.argv[1], "w")
n = 4
for j in range(n + 1):
    for i in range(n + 1):
        out.write("v %r %r 0.05\n" % (0.2 + 0.6 * i / n, 0.2 + 0.6 * j / n))
for j in range(n):
    for i in range(n):
        a = j * (n + 1) + i + 1
        out.write("f %d %d %d\nf %d %d %d\n" % (a, a + 1, a + n + 2, a, a + n + 2, a + n + 1))
PY
for m in vectors volumes; do
  "$STRATA" reconstruct -q --detail "$TMP/quad_detail.obj" --base "$TMP/quad_base.obj" \
    --edited-base "$TMP/quad_edited.obj" --method $m -o "$TMP/quad_$m.obj" >/dev/null 2>"$TMP/quad.stderr" ||
    { echo "FAIL: a quad base and its edit cut along other diagonals ($m):" >&2; cat "$TMP/quad.stderr" >&2; exit 1; }
done

# --strict: exit 3 once the result misses a target (the report's "warnings"), outputs written;
# 0 when it holds them. A run stopped short (one cycle, no polish, no retry) misses two.
strict() {  # strict <expected status> <stem> <reconstruct arguments...>
  local want=$1 stem=$2 got=0
  shift 2
  "$STRATA" reconstruct -q --strict "$@" -o "$TMP/$stem.obj" --report "$TMP/$stem.json" \
    >/dev/null 2>"$TMP/$stem.stderr" || got=$?
  [ "$got" = "$want" ] || { echo "FAIL: --strict $stem exited $got, expected $want" >&2; cat "$TMP/$stem.stderr" >&2; exit 1; }
  [ -s "$TMP/$stem.obj" ] && [ -s "$TMP/$stem.json" ] || { echo "FAIL: --strict $stem wrote no output" >&2; exit 1; }
}
strict 0 strict_ok --detail "$TMP/case/detail.obj" --base "$TMP/case/base.obj" --edited-base "$TMP/case/edited_base.obj"
strict 3 strict_far --detail "$TMP/far.obj" --base "$TMP/case/base.obj" --edited-base "$TMP/case/base.obj" \
  --method vectors
grep -q "strata: error: --strict: .*far.obj does not look like a displacement of" "$TMP/strict_far.stderr" ||
  { echo "FAIL: --strict does not name the far detail" >&2; exit 1; }
strict 3 strict_short --detail "$TMP/case/detail.obj" --base "$TMP/case/base.obj" \
  --edited-base "$TMP/case/edited_base.obj" --set max_cycles=1 --set final_max_cycles=1 --set max_final_steps=0 \
  --set fallback_schedule=false --set retry_on_new_intersections=false
python3 - "$TMP" <<'PY'
import json, sys
tmp = sys.argv[1]
ok = json.load(open(tmp + "/strict_ok.json"))["warnings"]
far = json.load(open(tmp + "/strict_far.json"))["warnings"]
short = json.load(open(tmp + "/strict_short.json"))["warnings"]
err = open(tmp + "/strict_short.stderr").read()
problems = []
if ok != []: problems.append("warnings on the paper's case: %r" % ok)
if len(far) != 1 or "does not look like a displacement" not in far[0]: problems.append("far: %r" % far)
# The solve stopped short does not converge; its new pairs, if any, are the second reason.
pairs = json.load(open(tmp + "/strict_short.json"))["intersections"]["new_pairs"]
if not short or not short[0].startswith("not converged") or len(short) != 1 + (pairs > 0) or \
        (pairs > 0 and short[1] != "%d new intersecting pairs of triangles" % pairs):
    problems.append("short: %r (new pairs %d)" % (short, pairs))
for w in short:
    if "--strict: " + w not in err: problems.append("stderr lacks %r" % w)
if problems:
    print("FAIL (--strict):\n  " + "\n  ".join(problems), file=sys.stderr)
    sys.exit(1)
PY

python3 - "$TMP" <<'PY'
import json, math, sys
tmp = sys.argv[1]
errors = []
def check(cond, msg):
    if not cond:
        errors.append(msg)

def need(obj, path):
    cur = obj
    for key in path.split("."):
        if not isinstance(cur, dict) or key not in cur:
            errors.append("missing field " + path)
            return None
        cur = cur[key]
    return cur

reports = {}
for method in ("volumes", "vectors"):
    with open(f"{tmp}/{method}.json") as f:
        r = json.load(f)
    reports[method] = r
    check(r.get("method") == method, f"{method}: method is {r.get('method')!r}")
    for mesh in ("detail", "base", "edited_base"):
        for key in ("vertices", "faces"):
            v = need(r, f"inputs.{mesh}.{key}")
            check(isinstance(v, int) and v > 0, f"{method}: inputs.{mesh}.{key} = {v!r}")
    check(need(r, "inputs.base.vertices") == need(r, "inputs.edited_base.vertices"), "base/edited base sizes differ")
    check(need(r, "output.faces") == need(r, "inputs.detail.faces"), f"{method}: output faces != detail faces")
    for key in ("projected", "fallback", "ambiguous"):
        v = need(r, "encoding." + key)
        check(isinstance(v, int) and v >= 0, f"{method}: encoding.{key} = {v!r}")
    check(need(r, "encoding.projected") + need(r, "encoding.fallback") == need(r, "inputs.detail.vertices"),
          f"{method}: projected + fallback != detail vertices")
    for key in ("max_relative_error", "rms_relative_error", "total_volume_change"):
        v = need(r, "volume_metrics." + key)
        check(isinstance(v, (int, float)) and math.isfinite(v), f"{method}: volume_metrics.{key} = {v!r}")
    # The result's smoothness against the detail: percentiles in order, every interior edge measured.
    dc = [need(r, "dihedral_change_degrees." + k) for k in ("median", "p90", "p99", "max")]
    check(all(isinstance(v, (int, float)) and 0 <= v <= 180 for v in dc) and dc == sorted(dc),
          f"{method}: dihedral_change_degrees {dc!r}")
    edges = need(r, "dihedral_change_degrees.edges")
    check(isinstance(edges, int) and 0 < edges <= 3 * need(r, "output.faces") // 2,
          f"{method}: dihedral_change_degrees.edges = {edges!r}")
    for key in ("input_pairs", "output_pairs", "new_pairs"):
        v = need(r, "intersections." + key)
        check(isinstance(v, int) and v >= 0, f"{method}: intersections.{key} = {v!r}")
    for key in ("read", "encode", "setup", "frames", "solve", "metrics", "write", "total"):
        v = need(r, "timing_seconds." + key)
        check(isinstance(v, (int, float)) and v >= 0, f"{method}: timing_seconds.{key} = {v!r}")
    with open(f"{tmp}/{method}.stats.json") as f:
        s = json.load(f)
    check(s["faces"] == need(r, "output.faces"), f"{method}: output mesh has {s['faces']} faces")

vol, vec = reports["volumes"], reports["vectors"]
# No --solver: auto, which takes the default options for a detail this small.
for method, r in reports.items():
    check(r.get("solver_requested") == "auto", f"{method}: solver_requested is {r.get('solver_requested')!r}")
    check(r.get("solver") == "legacy", f"{method}: auto chose {r.get('solver')!r} for {need(r, 'inputs.detail.faces')} faces")
it = need(vol, "iterations") or {}
for key in ("levels", "cycles", "volume_sweeps", "regularization_sweeps", "cg_iterations", "final_sweeps"):
    check(isinstance(it.get(key), int) and it[key] >= 0, f"volumes: iterations.{key} = {it.get(key)!r}")
check(isinstance(it.get("level_vertices"), list) and len(it["level_vertices"]) == it.get("levels"),
      "volumes: iterations.level_vertices does not have one entry per level")
check(isinstance(it.get("converged"), bool), "volumes: iterations.converged is not a bool")
check("iterations" in vec and vec["iterations"] is None, "vectors: iterations should be null")

# The paper's claims on this case (Fig. 6): volumes keep every prism volume and add no fold,
# vectors fold on the inner side of the bend.
vmax = vol["volume_metrics"]["max_relative_error"]
check(vmax <= 1e-3, f"volumes: max relative prism volume error {vmax:.3e} > 1e-3")
check(vol["intersections"]["new_pairs"] == 0,
      f"volumes: {vol['intersections']['new_pairs']} new intersecting pairs, expected 0")
check(vec["intersections"]["new_pairs"] > 0, "vectors: no new intersecting pairs, expected the bend to fold them")

if errors:
    print("FAIL:\n  " + "\n  ".join(errors), file=sys.stderr)
    sys.exit(1)
print("reconstruct_report: all checks passed")
PY

# The scan-like triangulation of the same case (--jitter) rebuilt by the multigrid solver and by
# the same in the paper's schedule (cycles: a cycle per volume scale): the report names the
# solver, the result holds the volumes without new pairs and without a factorization of the whole
# level.
"$STRATA" generate --case cuboid --triangles 3000 --jitter 0.4 --out-dir "$TMP/irregular" >/dev/null
for solver in multigrid cycles; do
"$STRATA" reconstruct --detail "$TMP/irregular/detail.obj" --base "$TMP/irregular/base.obj" \
  --edited-base "$TMP/irregular/edited_base.obj" --solver $solver -o "$TMP/mg.obj" --report "$TMP/mg.json" -q \
  >/dev/null
python3 - "$TMP/mg.json" $solver <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
solver = sys.argv[2]
errors = []
if r.get("solver") != solver: errors.append("solver is %r" % r.get("solver"))
if not r["volume_metrics"]["max_relative_error"] <= 1e-3: errors.append("max error %g" % r["volume_metrics"]["max_relative_error"])
if r["intersections"]["new_pairs"] != 0: errors.append("%d new pairs" % r["intersections"]["new_pairs"])
it = r["iterations"]
# A neighbourhood's small factorizations (the polish's local end) are allowed, a whole level's not.
if it["factorizations"] != it["local_factorizations"]: errors.append("%d whole-level factorizations" % (it["factorizations"] - it["local_factorizations"]))
# The paper's schedule solves the finest level at every volume scale (20), the multigrid preset at
# its last of 3 only.
per_scale = it["finest_cycles_per_scale"]
want = 20 if solver == "cycles" else 3
if len(per_scale) != want or sum(1 for c in per_scale if c > 0) != (want if solver == "cycles" else 1):
    errors.append("finest cycles per scale %r" % per_scale)
if errors:
    print("FAIL (%s):\n  " % solver + "\n  ".join(errors), file=sys.stderr)
    sys.exit(1)
print("reconstruct_report: %s checks passed" % solver)
PY
done
# auto over a detail of at least 80,000 triangles takes the multigrid preset (the displacement
# vectors, which need no solver, keep this check cheap; the report names the solver either way).
"$STRATA" generate --case bumps --triangles 90000 --out-dir "$TMP/large" >/dev/null
"$STRATA" reconstruct --detail "$TMP/large/detail.obj" --base "$TMP/large/base.obj" \
  --edited-base "$TMP/large/edited_base.obj" --method vectors -o "$TMP/large.obj" --report "$TMP/large.json" -q \
  >/dev/null
python3 - "$TMP/large.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
faces = r["inputs"]["detail"]["faces"]
if not (faces >= 80000 and r.get("solver") == "multigrid" and r.get("solver_requested") == "auto"):
    print("FAIL (auto): %d faces, solver %r, requested %r" % (faces, r.get("solver"), r.get("solver_requested")),
          file=sys.stderr)
    sys.exit(1)
print("reconstruct_report: auto checks passed")
PY
expect_exit 2 "^strata: error: --solver: magic not in {auto,legacy,multigrid,cycles}" "$TMP/err.txt" \
  "$STRATA" reconstruct --detail "$TMP/irregular/detail.obj" --base "$TMP/irregular/base.obj" \
  --edited-base "$TMP/irregular/edited_base.obj" --solver magic -o "$TMP/x.obj"
[ ! -e "$TMP/x.obj" ] || { echo "FAIL: output written for a bad --solver" >&2; exit 1; }
