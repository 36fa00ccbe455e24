#!/usr/bin/env bash
# `strata generate` writes all three paper cases, `strata stats` reads them, and a tiny
# `strata demo` writes every mesh, the table and demo_report.json.
# Usage: bash generate_stats_demo.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: generate_stats_demo.sh <path-to-strata> <tests/data dir>}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

for c in bumps rings cuboid; do
  "$STRATA" generate --case "$c" --triangles 1000 --bend-degrees 45 --out-dir "$TMP/$c" >/dev/null
  for f in detail base edited_base; do
    "$STRATA" stats --json "$TMP/$c/$f.obj" >"$TMP/$c/$f.json"
  done
done
"$STRATA" stats "$TMP/bumps/detail.obj" | grep -q "self-intersecting pairs"

# An empty assets dir plus one asset triple (a copy of a generated case) to exercise --assets-dir.
mkdir -p "$TMP/assets/mycase"
cp "$TMP/rings/detail.obj" "$TMP/rings/base.obj" "$TMP/rings/edited_base.obj" "$TMP/assets/mycase/"
mkdir -p "$TMP/assets/incomplete"
"$STRATA" demo -q --triangles 800 --assets-dir "$TMP/assets" --out-dir "$TMP/demo" >"$TMP/demo.txt"
grep -q "max rel err" "$TMP/demo.txt" || { echo "FAIL: demo printed no table" >&2; cat "$TMP/demo.txt" >&2; exit 1; }

python3 - "$TMP" <<'PY'
import json, os, sys
tmp = sys.argv[1]
errors = []
for c in ("bumps", "rings", "cuboid"):
    s = {f: json.load(open(f"{tmp}/{c}/{f}.json")) for f in ("detail", "base", "edited_base")}
    for f, st in s.items():
        for key in ("vertices", "faces", "boundary_edges", "bbox_diagonal", "signed_volume",
                    "self_intersecting_pairs", "intersection_seconds"):
            if key not in st:
                errors.append(f"{c}/{f}: stats has no {key}")
        if st.get("self_intersecting_pairs") != 0:
            errors.append(f"{c}/{f}: {st.get('self_intersecting_pairs')} self-intersecting pairs, expected 0")
        if st.get("boundary_edges", 0) <= 0:
            errors.append(f"{c}/{f}: an open tube must have boundary edges")
    if s["base"]["vertices"] != s["edited_base"]["vertices"] or s["base"]["faces"] != s["edited_base"]["faces"]:
        errors.append(f"{c}: base and edited base differ in size")
    if not 500 <= s["detail"]["faces"] <= 2000:
        errors.append(f"{c}: --triangles 1000 gave {s['detail']['faces']} detail faces")

demo = f"{tmp}/demo"
r = json.load(open(f"{demo}/demo_report.json"))
names = [c["name"] for c in r["cases"]]
if names != ["bumps", "rings", "cuboid", "mycase"]:
    errors.append(f"demo cases are {names}")
for c in r["cases"]:
    if "error" in c:
        errors.append(f"demo case {c['name']} failed: {c['error']}")
        continue
    for m in ("volumes", "vectors"):
        for key in ("volume_metrics", "intersections", "timing_seconds", "iterations"):
            if key not in c["methods"][m]:
                errors.append(f"demo {c['name']}/{m}: no {key}")
    for suffix in ("volumes", "vectors", "edited_base"):
        if not os.path.isfile(f"{demo}/{c['name']}_{suffix}.obj"):
            errors.append(f"demo: {c['name']}_{suffix}.obj not written")
if len(r["summary"]) != 8:
    errors.append(f"demo summary has {len(r['summary'])} rows, expected 8")
if errors:
    print("FAIL:\n  " + "\n  ".join(errors), file=sys.stderr)
    sys.exit(1)
print("generate_stats_demo: all checks passed")
PY
