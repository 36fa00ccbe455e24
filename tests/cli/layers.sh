#!/usr/bin/env bash
# Layered models from the command line: `strata build` (one scan, a batch with a bad file),
# `strata info`, `strata export` (the finest band is the scan, number for number), `strata edit`
# at band 0, `strata amplitude` (mute and restore), and errors on bad models and arguments.
# Usage: bash layers.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: layers.sh <path-to-strata> <tests/data dir>}
STRATA=$(cd "$(dirname "$STRATA")" && pwd)/$(basename "$STRATA")
DATA=$(cd "${2:?usage: layers.sh <path-to-strata> <tests/data dir>}" && pwd)
SCANS=$(cd "$DATA/../../assets/scans" && pwd)
source "$(dirname "${BASH_SOURCE[0]}")/lib/expect.sh"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
cd "$TMP"
fail() { echo "FAIL: $*" >&2; exit 1; }

# One scan.
"$STRATA" build "$SCANS/camel.off" -o camel.strata -q --report build.json >build.txt || fail "build failed"
grep -q "1 built, 0 failed" build.txt || fail "no build summary"
"$STRATA" info camel.strata >info.txt || fail "info failed"
grep -q "3 bands" info.txt || fail "info does not list 3 bands"
"$STRATA" info camel.strata --json >info.json
"$STRATA" export camel.strata -o finest.obj >/dev/null || fail "export failed"
"$STRATA" export camel.strata --band 0 -o limit.obj >/dev/null || fail "export of band 0 failed"
"$STRATA" export camel.strata --cage -o cage.obj >/dev/null || fail "export of the cage failed"
python3 - "$SCANS/camel.off" <<'PY' || fail "info or export check failed"
import json, sys
def read_off(p):
    t = open(p).read().split()
    assert t[0] == "OFF"
    nv, nf = int(t[1]), int(t[2]); i = 4
    v = [tuple(float(x) for x in t[i + 3 * k:i + 3 * k + 3]) for k in range(nv)]; i += 3 * nv
    f = []
    for _ in range(nf):
        n = int(t[i]); f.append(tuple(int(x) for x in t[i + 1:i + 1 + n])); i += n + 1
    return v, f
def read_obj(p):
    v, f = [], []
    for line in open(p):
        s = line.split()
        if s and s[0] == "v": v.append(tuple(float(x) for x in s[1:4]))
        if s and s[0] == "f": f.append(tuple(int(x.split("/")[0]) - 1 for x in s[1:]))
    return v, f
sv, sf = read_off(sys.argv[1])
ev, ef = read_obj("finest.obj")
assert ev == sv, "exported vertices differ from the scan's"
assert ef == sf, "exported faces differ from the scan's"
info = json.load(open("info.json"))
b = info["bands"]
assert [x["kind"] for x in b] == ["cage", "triangles", "triangles"], b
assert b[0]["faces"] < b[1]["faces"] < b[2]["faces"] == len(sf), b
assert all(0 < x["detail_rms"] <= x["detail_max"] for x in b[1:]), b
assert info["history"][0]["op"] == "build"
r = json.load(open("build.json"))
assert r["models"][0]["ok"] and r["models"][0]["bytes"] > 0, r
PY

# A scan whose faces disagree in orientation (every 5th face of the camel flipped, as STL exports
# and merged scans have them): `strata stats` refuses it, `strata build` flips them back with a
# note, and the model's finest band is the camel as it was.
awk '/^3 / && n++ % 5 == 0 {print $1, $2, $4, $3; next} {print}' "$SCANS/camel.off" >shuffled.off
if "$STRATA" stats shuffled.off >/dev/null 2>stats_err.txt; then fail "stats read an inconsistently oriented scan"; fi
grep -q "inconsistently oriented faces" stats_err.txt || fail "stats: no orientation error"
"$STRATA" build shuffled.off -o shuffled.strata -q --report shuffled.json >/dev/null 2>shuffled_err.txt ||
  fail "build of the shuffled scan failed"
grep -q "shuffled.off: [0-9]* faces flipped to agree with their neighbours' orientation" shuffled_err.txt ||
  fail "build: no note of the flipped faces"
"$STRATA" export shuffled.strata -o shuffled_finest.off >/dev/null || fail "export of the shuffled model failed"
python3 - "$SCANS/camel.off" <<'PY' || fail "the shuffled scan's model differs from the camel"
import json, sys
r = json.load(open("shuffled.json"))["models"][0]
def off(p):
    t = [l.split() for l in open(p) if l.strip() and not l.startswith("#")]
    nv, nf = int(t[1][0]), int(t[1][1])
    return t[2:2 + nv], [tuple(map(int, f[1:4])) for f in t[2 + nv:2 + nv + nf]]
def canon(f):  # a face up to rotation of its corners
    k = f.index(min(f))
    return f[k:] + f[:k]
v0, f0 = off(sys.argv[1])
v1, f1 = off("shuffled_finest.off")
flipped = sum(1 for i in range(len(f0)) if i % 5 == 0)
assert r["ok"] and r["reoriented_faces"] == flipped, (r, flipped)
assert [canon(f) for f in f1] == [canon(f) for f in f0], "faces not restored"
PY

# A 90-degree neck bend at band 0: no new intersecting pairs in the finest band.
"$STRATA" edit camel.strata --band 0 --edit "$DATA/edits/camel_neck.json" -o bent.strata --intersections \
  --report edit.json -q >edit.txt || fail "edit failed"
python3 - <<'PY' || fail "edit report check failed"
import json
r = json.load(open("edit.json"))
i = r["finest_band_intersections"]
assert i["new_pairs"] == 0, i
c = r["changes"][0]
assert [b["band"] for b in c["rebuilt"]] == [1, 2], c
for b in c["rebuilt"]:
    assert b["solved_vertices"] > 0 and b["volume_metrics"]["max_relative_error"] <= 1e-3, b
    # The solver's statistics, as deform's "iterations".
    it = b["iterations"]
    assert it["converged"] == b["solver_converged"] and it["cycles"] > 0, it
    assert abs(it["solver_max_relative_error"] - b["volume_metrics"]["max_relative_error"]) < 1e-9, it
assert r["warnings"] == [], r["warnings"]
PY
"$STRATA" info bent.strata --json | python3 -c "import json,sys; h=json.load(sys.stdin)['history']; assert h[-1]['op']=='edit' and h[-1]['edit']['script'].endswith('camel_neck.json'), h" \
  || fail "the edit is not in the history"

# Warnings and --strict: a generated tube's band 1 bent back and forth by 90 degrees, 8 times (the
# selections taken anew on the bent band each time) drifts and folds until solves miss the
# tolerance (by 45 degrees it did from the third edit on until the blend field of its open rims
# was checked; now only the tenth edit of ten does). Every solve the report lists as not converged has a warning naming its edit and
# band, and only those; --strict then exits 3 with the model written.
"$STRATA" generate --case bumps --triangles 2000 --out-dir tube >/dev/null
# A history entry is the file's text: `info` shows its control characters escaped, so that a
# newline or a terminal escape in it cannot fake lines of the output (a fuzzing pass found both).
cat >forge_history.py <<'PY'
# forge_history.py IN OUT ENTRY: IN with the text ENTRY (@FILE: FILE's text) appended to its
# history, CRCs valid.
import json, struct, sys, zlib
data = open(sys.argv[1], "rb").read()
H = struct.unpack_from("<I", data, 12)[0]
header = json.loads(data[20:20 + H])
old = [(s, data[s["offset"]:s["offset"] + s["size"]]) for s in header["sections"]]
header["model"]["history"].append(open(sys.argv[3][1:]).read() if sys.argv[3][:1] == "@" else sys.argv[3])
align = lambda n: (n + 7) // 8 * 8
length = 0
while True:
    pos = align(20 + length)
    for s, b in old:
        s["offset"] = pos
        pos = align(pos + len(b))
    text = json.dumps(header, separators=(",", ":")).encode()
    if len(text) == length:
        break
    length = len(text)
out = bytearray(data[:12]) + struct.pack("<II", len(text), zlib.crc32(text)) + text
for s, b in old:
    out += bytes(s["offset"] - len(out)) + b
open(sys.argv[2], "wb").write(bytes(out))
PY
python3 forge_history.py camel.strata forged.strata $'x\nstrata: error: forged\e[2J' || fail "could not forge"
"$STRATA" info forged.strata >forged.txt || fail "the forged history was not read"
grep -q '^strata: error' forged.txt && fail "a history entry printed a fake error line"
grep -qF 'x\x0astrata: error: forged\x1b[2J' forged.txt || fail "the history entry is not shown escaped: $(tail -2 forged.txt)"
# An entry of 100k nested brackets, which a file may hold as text, is shown as its text: `info
# --json` parsed it and dumped it recursively, and overflowed the stack (a review, thirty-eighth
# session).
python3 -c 'print("[" * 100000 + "]" * 100000, end="")' >deep_entry.txt
python3 forge_history.py camel.strata deep.strata @deep_entry.txt || fail "could not forge"
"$STRATA" info deep.strata --json >deep.json || fail "info --json failed on a deeply nested history entry"
python3 -c "import json,sys; h=json.load(open('deep.json'))['history']; assert h[-1] == '[' * 100000 + ']' * 100000" ||
  fail "the deep history entry is not shown as its text"

"$STRATA" build tube/detail.obj -o tube.strata -q >/dev/null || fail "build of the tube failed"
python3 - <<'PY' || fail "could not write the back-and-forth script"
import json
json.dump([{"region": {"halfspace": {"point": [0, 0, 2.5], "normal": [0, 0, 1]}},
            "handle": {"halfspace": {"point": [0, 0, 4.5], "normal": [0, 0, 1]}},
            "transform": {"rotate": {"axis": [1, 0, 0], "degrees": 90 * (-1) ** i, "pivot": [0, 0, 3.5]}}}
           for i in range(8)], open("back_and_forth.json", "w"))
PY
status=0
"$STRATA" edit tube.strata --band 1 --edit back_and_forth.json --strict -o drift.strata --report drift.json \
  -q >/dev/null 2>drift.err || status=$?
[ -s drift.strata ] || fail "--strict did not write the model"
python3 - "$status" <<'PY' || fail "warnings do not match the unconverged solves"
import json, sys
r = json.load(open("drift.json"))
expected = []
for i, c in enumerate(r["changes"]):
    if not c["edit_solver_converged"]:
        expected.append("edit %d: band %d: not converged" % (i + 1, c["edited_band"]))
    for b in c["rebuilt"]:
        if b["solved_prisms"] > 0 and not b["solver_converged"]:
            expected.append("edit %d: band %d rebuilt: not converged" % (i + 1, b["band"]))
w = r["warnings"]
assert expected, "no solve missed the tolerance: the case no longer tests the warnings"
assert len(w) == len(expected) and all(a.startswith(b) for a, b in zip(w, expected)), (w, expected)
assert int(sys.argv[1]) == 3, "--strict exited %s" % sys.argv[1]
err = open("drift.err").read()
assert all("strata: error: --strict: " + x in err for x in w), err
PY

# Mute band 2 and restore it: the finest band comes back as it was.
"$STRATA" amplitude bent.strata --band 2 --scale 0 -o muted.strata -q >/dev/null || fail "mute failed"
"$STRATA" amplitude muted.strata --band 2 --scale 1 -o restored.strata -q >/dev/null || fail "restore failed"
"$STRATA" export bent.strata -o a.obj >/dev/null && "$STRATA" export muted.strata -o b.obj >/dev/null &&
  "$STRATA" export restored.strata -o c.obj >/dev/null || fail "exports failed"
cmp -s a.obj c.obj || fail "muting and restoring band 2 changed the finest band"
cmp -s a.obj b.obj && fail "muting band 2 changed nothing"
# A model that a command replaces keeps its permission bits, as `export`'s meshes do (a private
# model became world-readable: a review, thirty-eighth session).
cp muted.strata private.strata && chmod 600 private.strata
"$STRATA" amplitude bent.strata --band 2 --scale 0.5 -o private.strata -q >/dev/null || fail "amplitude into a private file failed"
[ "$(stat -c %a private.strata)" = 600 ] || fail "the replaced model's permissions became $(stat -c %a private.strata)"

# Batch: a bad file is reported and skipped, the others are built, the exit code is 1.
printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n' >broken.off
rc=0
"$STRATA" build "$SCANS/bear.off" broken.off --out-dir models -q >batch.txt 2>batch.err || rc=$?
[ "$rc" -eq 1 ] || fail "a batch with a broken file exited $rc, expected 1: $(cat batch.err)"
grep -q "^strata: error: broken.off: truncated: header declares 3 vertices, file holds 2" batch.err || fail "the broken file's error is not named: $(cat batch.err)"
[ -s models/bear.strata ] || fail "the good scan of the batch was not built"
[ -e models/broken.strata ] && fail "a model was written for the broken scan"
grep -q "1 built, 1 failed" batch.txt || fail "no batch summary"
grep -q "broken.off" batch.txt || fail "the summary does not name the broken file"

# Bad models and arguments: exit 1 (2 for usage), a message naming the file, no output written.
head -c 1000 camel.strata >cut.strata
for bad in "cut.strata: truncated: the header ends at byte [0-9]*, file has 1000 bytes" \
  "broken.off: not a Strata model file (bad magic)" "missing.strata: cannot open: No such file"; do
  expect_exit 1 "^strata: error: $bad" err.txt "$STRATA" info "${bad%%:*}"
  expect_exit 1 "^strata: error: $bad" err.txt "$STRATA" amplitude "${bad%%:*}" --band 1 --scale 0 -o out.strata
  [ -e out.strata ] && fail "an output was written for ${bad%%:*}"
done
expect_exit 1 "--band 7 is out of range: camel.strata has bands 0 to 2" err.txt \
  "$STRATA" edit camel.strata --band 7 --edit "$DATA/edits/camel_neck.json" -o out.strata
expect_exit 2 "--band: must be above 0, not 0" err.txt "$STRATA" amplitude camel.strata --band 0 --scale 0 -o out.strata
[ -e out.strata ] && fail "an output was written after an error"
# Found by a fuzzing pass (2026-11-28).
# An empty amplitude was read as 0 (muting the band), and 1e308 overflowed the solve.
expect_exit 2 "--scale: '' is not a number" err.txt "$STRATA" amplitude camel.strata --band 1 --scale "" -o out.strata
expect_exit 2 "--scale: must be -1000 to 1000, not 1e308" err.txt \
  "$STRATA" amplitude camel.strata --band 1 --scale 1e308 -o out.strata
expect_exit 2 "--scale: 'nan' is not a number" err.txt "$STRATA" amplitude camel.strata --band 1 --scale nan -o out.strata
# CLI11's bound printed DBL_MAX in full.
expect_exit 2 "--band: must be above 0, not 0" err.txt "$STRATA" amplitude camel.strata --band 0 --scale 1 -o out.strata
# A tessellation of 100 million triangles was written (2.8 GB at resolution 1000 for a small cage).
expect_exit 1 "camel.strata: band 0 at --resolution 100000: .* would have .* triangles, over 5e+07" err.txt \
  "$STRATA" export camel.strata --band 0 --resolution 100000 -o out.obj
# Found by a documentation check (2026-11-28): these were exit 1, or named no option.
expect_usage() {  # expect_usage <text the message must contain> <strata arguments...>
  local needle=$1 code=0
  shift
  "$STRATA" "$@" >/dev/null 2>err.txt || code=$?
  [ "$code" = 2 ] || fail "'$*' should be a usage error (exit 2), got $code: $(cat err.txt)"
  grep -qF -- "$needle" err.txt || fail "'$*': the message does not mention '$needle': $(cat err.txt)"
}
expect_usage "give -o MODEL.strata or --out-dir DIR" build "$SCANS/camel.off"
expect_usage "several scans need --out-dir" build "$SCANS/camel.off" "$SCANS/bear.off" -o out.strata
expect_usage "give either -o or --out-dir, not both" build "$SCANS/camel.off" -o out.strata --out-dir models2
expect_usage "--scale: must be -1000 to 1000, not 2000" amplitude camel.strata --band 1 --scale 2000 -o out.strata
expect_usage "--threads: must be 0 to 1024, not 2000" deform "$SCANS/camel.off" --edit "$DATA/edits/camel_neck.json" \
  --threads 2000 -o out.obj
expect_usage "--handle-rings: must be -1000 to 1000, not 5000" deform "$SCANS/camel.off" \
  --edit "$DATA/edits/camel_neck.json" --handle-rings 5000 -o out.obj
[ -e models2 ] && fail "the output directory was made after a usage error"
# Two scans of one name would be built into one model, the second over the first.
mkdir -p a b
cp "$SCANS/bear.off" a/bear.off
cp "$SCANS/bear.off" b/bear.off
expect_exit 1 "would both be built into same/bear.strata" err.txt "$STRATA" build a/bear.off b/bear.off --out-dir same -q
[ -e same ] && fail "the output directory was made for duplicate names"
# A model is written as .strata (any name was taken).
expect_exit 1 "out.xyz: a layered model is written as a .strata file" err.txt \
  "$STRATA" amplitude camel.strata --band 1 --scale 2 -o out.xyz
[ -e out.xyz ] && fail "out.xyz was written"
[ -e out.strata ] && fail "an output was written after an error"
[ -e out.obj ] && fail "an output was written after an error"
echo "layers CLI: ok"
