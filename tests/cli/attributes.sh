#!/usr/bin/env bash
# A scan's vertex colours and texture coordinates through the CLI: `stats` reports them; `deform`,
# `reconstruct`, `build` + `edit` + `export` write the result's moved vertices with the scan's
# values, exactly, in PLY, OBJ and OFF; STL, which stores none, gets a warning; a textured OBJ
# keeps its seams and materials, and its material library and images go beside outputs elsewhere
# (a model carries them); its diffuse images go to PLY (TextureFile) and from there back to OBJ;
# and what a file holds that cannot be kept is a note naming it.
# Usage: bash attributes.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: attributes.sh <path-to-strata> <tests/data dir>}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
source "$(dirname "${BASH_SOURCE[0]}")/lib/expect.sh"

# STRATA_TEST_SANITIZERS (the sanitizer stage sets it): the same paths on a smaller scan; under the
# sanitizers the script took 241 s at 8,000 triangles and 52 s at 2,000 (2026-11-30).
triangles=8000
if [ -n "${STRATA_TEST_SANITIZERS:-}" ]; then triangles=2000; fi
"$STRATA" generate --case bumps --triangles "$triangles" --out-dir "$TMP/case" >/dev/null
cat >"$TMP/bend.json" <<'JSON'
{"region": {"halfspace": {"point": [0, 0, 2], "normal": [0, 0, 1]}},
 "handle": {"halfspace": {"point": [0, 0, 3.5], "normal": [0, 0, 1]}},
 "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 60, "pivot": [1.2, 0, 2.5]}}}
JSON

# The generated detail as a scanner would write it: binary PLY, float positions, uchar colours
# from the position, float u v. Written and read by this script's own code (mesh.py).
cat >"$TMP/mesh.py" <<'PY'
import struct, sys

def read_obj(path):
    v, f = [], []
    for line in open(path):
        t = line.split()
        if t and t[0] == "v": v.append(tuple(float(x) for x in t[1:4]))
        if t and t[0] == "f": f.append(tuple(int(x.split("/")[0]) - 1 for x in t[1:]))
    return v, f

def write_scan_ply(obj, out):
    v, f = read_obj(obj)
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
            "property float u\nproperty float v\nelement face %d\nproperty list uchar int vertex_indices\n"
            "end_header\n" % (len(v), len(f)))
    with open(out, "wb") as o:
        o.write(head.encode())
        for i, p in enumerate(v):
            o.write(struct.pack("<fff", *p))
            o.write(struct.pack("<BBB", i % 256, (7 * i) % 256, int(40 * (p[2] + 3)) % 256))
            o.write(struct.pack("<ff", (i % 101) / 100.0, p[2] / 8.0))
        for t in f:
            o.write(struct.pack("<B", 3) + struct.pack("<iii", *t))

def read_ply(path):
    """Positions, colours (0-255) and (u, v) of a binary little-endian PLY of scalar properties."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    props, n = [], 0
    for line in data[:end].decode().splitlines():
        t = line.split()
        if t[:2] == ["element", "vertex"]: n, cur = int(t[2]), "vertex"
        elif t[:1] == ["element"]: cur = t[1]
        elif t[:1] == ["property"] and cur == "vertex": props.append((t[1], t[2]))
    fmt = "<" + "".join({"float": "f", "double": "d", "uchar": "B"}[ty] for ty, _ in props)
    size, names = struct.calcsize(fmt), [nm for _, nm in props]
    rows = [dict(zip(names, struct.unpack_from(fmt, data, end + k * size))) for k in range(n)]
    # Colours as the SDK holds them: uchar k as k / 255 (the same double in Python and C++).
    scale = 255.0 if props[names.index("red")][0] == "uchar" else 1.0
    return ([(r["x"], r["y"], r["z"]) for r in rows],
            [tuple(r[c] / scale for c in ("red", "green", "blue")) for r in rows],
            [(r.get("u", r.get("texture_u")), r.get("v", r.get("texture_v"))) for r in rows])

def read_text(path):
    """OBJ ("v x y z r g b", vt) or COFF / STCOFF: positions, colours (0-1), (u, v)."""
    pos, col, uv = [], [], []
    lines = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    if path.endswith(".obj"):
        for t in lines:
            if t[0] == "v": pos.append(tuple(map(float, t[1:4]))); col.append(tuple(float(x) for x in t[4:7]))
            if t[0] == "vt": uv.append((float(t[1]), float(t[2])))
    else:
        st = lines[0][0].startswith("ST")
        n = int(lines[1][0])
        for t in lines[2:2 + n]:
            pos.append(tuple(map(float, t[:3]))); col.append(tuple(float(x) for x in t[3:6]))
            if st: uv.append((float(t[-2]), float(t[-1])))
    return pos, col, uv

def load(path):
    return read_ply(path) if path.endswith(".ply") else read_text(path)

if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "make":
        write_scan_ply(sys.argv[2], sys.argv[3])
    elif cmd == "same":  # exactly the scan's colours and (u, v); positions moved (or not, "--rest")
        scan, out = load(sys.argv[2]), load(sys.argv[3])
        moved = sum(1 for a, b in zip(scan[0], out[0]) if max(abs(x - y) for x, y in zip(a, b)) > 1e-9)
        errors = []
        if out[1] != scan[1]: errors.append("colours differ")
        if out[2] != scan[2]: errors.append("texture coordinates differ")
        if (moved == 0) != (len(sys.argv) > 4 and sys.argv[4] == "--rest"): errors.append("%d vertices moved" % moved)
        if errors:
            sys.exit("FAIL: %s vs %s: %s" % (sys.argv[2], sys.argv[3], ", ".join(errors)))
PY
SCAN="$TMP/scan.ply"
python3 "$TMP/mesh.py" make "$TMP/case/detail.obj" "$SCAN"

"$STRATA" stats "$SCAN" --json >"$TMP/stats.json"
python3 -c "
import json, sys
s = json.load(open('$TMP/stats.json'))
if s['vertex_colors'] != 'rgb' or s['texture_coordinates'] != 'per_vertex': sys.exit('FAIL: stats: %s' % s)"

# deform: the edited vertices with the scan's colours and (u, v), in every format that stores them.
for ext in ply obj off; do
  "$STRATA" deform "$SCAN" --edit "$TMP/bend.json" -o "$TMP/deformed.$ext" -q >/dev/null
  python3 "$TMP/mesh.py" same "$SCAN" "$TMP/deformed.$ext"
done
"$STRATA" deform "$SCAN" --edit "$TMP/bend.json" --method vectors -o "$TMP/vectors.ply" -q >/dev/null
python3 "$TMP/mesh.py" same "$SCAN" "$TMP/vectors.ply"
# STL stores none: written, with a warning.
"$STRATA" deform "$SCAN" --edit "$TMP/bend.json" -o "$TMP/deformed.stl" -q >/dev/null 2>"$TMP/stl.err"
grep -q "deformed.stl: this format does not store vertex colours and texture coordinates" "$TMP/stl.err" ||
  { echo "FAIL: no STL warning: $(cat "$TMP/stl.err")" >&2; exit 1; }

# reconstruct: the detail's values go with the reconstructed vertices.
"$STRATA" reconstruct --detail "$SCAN" --base "$TMP/case/base.obj" --edited-base "$TMP/case/edited_base.obj" \
  -o "$TMP/reconstructed.ply" -q >/dev/null
python3 "$TMP/mesh.py" same "$SCAN" "$TMP/reconstructed.ply"

# build, export (at rest), edit band 0, export again: the finest band keeps the scan's values.
"$STRATA" build "$SCAN" -o "$TMP/m.strata" -q >/dev/null
"$STRATA" info "$TMP/m.strata" --json | python3 -c "
import json, sys
b = json.load(sys.stdin)['bands']
a = b[-1].get('attributes')
if a != {'vertex_colors': 'rgb', 'texture_coordinates': 'per_vertex', 'materials': 0, 'material_library': '', 'texture_files': [], 'companion_files': []}:
    sys.exit('FAIL: info: the finest band carries %s' % a)
if any('attributes' in x for x in b[:-1]): sys.exit('FAIL: info: attributes on a coarser band')"
"$STRATA" export "$TMP/m.strata" -o "$TMP/rest.ply" >/dev/null
python3 "$TMP/mesh.py" same "$SCAN" "$TMP/rest.ply" --rest
"$STRATA" edit "$TMP/m.strata" --band 0 --edit "$TMP/bend.json" -o "$TMP/edited.strata" -q >/dev/null
"$STRATA" export "$TMP/edited.strata" -o "$TMP/edited.obj" >/dev/null
python3 "$TMP/mesh.py" same "$SCAN" "$TMP/edited.obj"
"$STRATA" export "$TMP/edited.strata" --band 1 -o "$TMP/band1.ply" >/dev/null
"$STRATA" stats "$TMP/band1.ply" --json | python3 -c "
import json, sys
s = json.load(sys.stdin)
if s['vertex_colors'] != 'none': sys.exit('FAIL: band 1 exported with colours')"

# A textured OBJ as photogrammetry writes it: texture coordinates per face corner with seams (the
# first face's corners use other vt than their vertices'), a material library and two
# materials. deform keeps all of it (the faces' vt and usemtl as in the input); PLY cannot, and
# says so.
python3 - "$TMP/case/detail.obj" "$TMP/seams.obj" <<'PY'
import sys
lines = open(sys.argv[1]).read().splitlines()
out, nv = ["mtllib scan.mtl"], 0
for l in lines:
    if l.startswith("v "): nv += 1
    if not l.startswith("f "): out.append(l)
out += ["vt %d 0.5" % k for k in range(nv + 1)]
faces = [[int(i) for i in l.split()[1:]] for l in lines if l.startswith("f ")]
# Faces 1 and 2 (which share an edge in the generated grid) become one quad; face 3 is flipped
# against its neighbours (deform flips it back, its corners' vt with it).
a, b = faces[1], faces[2]
shared = [v for v in a if v in b]
assert len(shared) == 2, (a, b)
apex_a, apex_b = [v for v in a if v not in b][0], [v for v in b if v not in a][0]
i = a.index(apex_a)
quad = [a[i], a[(i + 1) % 3], apex_b, a[(i + 2) % 3]]
faces = [faces[0], quad, [faces[3][0], faces[3][2], faces[3][1]]] + faces[4:]
for k, f in enumerate(faces):
    if k % 1000 == 0: out.append("usemtl %s" % ("skin", "eyes")[(k // 1000) % 2])
    shift = 1 if k == 0 else 0  # the first face's corners use other vt than their vertices'
    out.append("f " + " ".join("%d/%d" % (v, v + shift) for v in f))
open(sys.argv[2], "w").write("\n".join(out) + "\n")
PY
printf 'newmtl skin\nmap_Kd -s 1 1 1 textures/skin colour.png\nnewmtl eyes\nbump eyes.png\n' >"$TMP/scan.mtl"
mkdir "$TMP/textures"
printf '\211PNG\r\n\032\n\000skin' >"$TMP/textures/skin colour.png"
printf 'eyes' >"$TMP/eyes.png"
"$STRATA" deform "$TMP/seams.obj" --edit "$TMP/bend.json" -o "$TMP/seams_out.obj" -q >/dev/null 2>"$TMP/seams.err"
grep -q "seams.obj: 1 faces flipped" "$TMP/seams.err" && [ "$(wc -l <"$TMP/seams.err")" -eq 1 ] ||
  { echo "FAIL: notes on a textured OBJ: $(cat "$TMP/seams.err")" >&2; exit 1; }
cat >"$TMP/compare_textured.py" <<'PY'
import sys
def parts(path):
    """Per vertex the set of (u, v) its corners use; per triangle its material (a polygon of n
    corners counts n - 2 times); the libraries; the positions."""
    vt, uv_of, mtl, lib, v, cur = [], {}, [], [], [], None
    for l in open(path):
        t = l.split()
        if not t: continue
        if t[0] == "vt": vt.append(tuple(float(x) for x in t[1:3]))
        if t[0] == "usemtl": cur = t[1]
        if t[0] == "mtllib": lib.append(t[1])
        if t[0] == "v": v.append(tuple(float(x) for x in t[1:4]))
        if t[0] == "f":
            mtl += [cur] * (len(t) - 3)
            for c in t[1:]:
                i, j = c.split("/")[:2]
                uv_of.setdefault(int(i), set()).add(vt[int(j) - 1] if int(j) <= len(vt) else j)
    return uv_of, mtl, lib, v
a, b = parts(sys.argv[1]), parts(sys.argv[2])
names = ("texture coordinates of a vertex's corners", "face materials", "material library")
errors = [n for n, x, y in zip(names, a, b) if x != y]
if a[3] == b[3]: errors.append("no vertex moved")
if errors: sys.exit("FAIL: textured OBJ %s: %s differ" % (sys.argv[2], ", ".join(errors)))
PY
python3 "$TMP/compare_textured.py" "$TMP/seams.obj" "$TMP/seams_out.obj"
# The same through a layered model: build, edit band 0, export the finest band.
"$STRATA" build "$TMP/seams.obj" -o "$TMP/seams.strata" -q >/dev/null 2>"$TMP/build.err"
"$STRATA" edit "$TMP/seams.strata" --band 0 --edit "$TMP/bend.json" -o "$TMP/seams_edited.strata" -q >/dev/null 2>"$TMP/edit.err"
"$STRATA" info "$TMP/seams_edited.strata" | grep -q "band 2 carries vertex colours none, texture coordinates per_corner, 2 materials, 0 texture images, 3 files" ||
  { echo "FAIL: info does not show the textured band: $("$STRATA" info "$TMP/seams_edited.strata")" >&2; exit 1; }
"$STRATA" export "$TMP/seams_edited.strata" -o "$TMP/seams_out.obj" >/dev/null
python3 "$TMP/compare_textured.py" "$TMP/seams.obj" "$TMP/seams_out.obj"
"$STRATA" deform "$TMP/seams.obj" --edit "$TMP/bend.json" -o "$TMP/seams_out.ply" -q >/dev/null 2>"$TMP/seams_ply.err"
grep -q "seams_out.ply: this format does not store materials (their diffuse images are kept, as TextureFile); not written" \
  "$TMP/seams_ply.err" || { echo "FAIL: no warning for PLY: $(cat "$TMP/seams_ply.err")" >&2; exit 1; }
# The diffuse image goes with it, as MeshLab's TextureFile; and that PLY back to an OBJ elsewhere
# gets a library named after it, with the image beside it, on the same faces (per triangle: the
# scan's "skin" faces, the only material with a map_Kd, and no material for the others).
grep -a -q "^comment TextureFile textures/skin colour.png$" "$TMP/seams_out.ply" ||
  { echo "FAIL: the PLY does not name the image" >&2; exit 1; }
mkdir "$TMP/from_ply"
"$STRATA" deform "$TMP/seams_out.ply" --edit "$TMP/bend.json" -o "$TMP/from_ply/back.obj" -q >/dev/null 2>"$TMP/from_ply.err"
cmp -s "$TMP/textures/skin colour.png" "$TMP/from_ply/textures/skin colour.png" &&
  grep -q "^mtllib back.mtl$" "$TMP/from_ply/back.obj" && [ "$(grep -cv 'faces flipped' "$TMP/from_ply.err")" -eq 0 ] ||
  { echo "FAIL: PLY to OBJ: $(ls -R "$TMP/from_ply") $(cat "$TMP/from_ply.err")" >&2; exit 1; }
python3 - "$TMP/seams.obj" "$TMP/from_ply/back.obj" <<'PY'
import os, sys
def images(path):
    """Per triangle its material's map_Kd ('' for none); a polygon of n corners counts n - 2 times."""
    d = os.path.dirname(path)
    maps, cur, out = {}, None, []
    for l in open(path):
        t = l.split(maxsplit=1)
        if t and t[0] == "mtllib":
            m = None
            for x in open(os.path.join(d, t[1].strip())):
                y = x.split(maxsplit=1)
                if y and y[0] == "newmtl": m = y[1].strip()
                if y and y[0] == "map_Kd": maps[m] = y[1].strip().replace("-s 1 1 1 ", "")
        if t and t[0] == "usemtl": cur = t[1].strip() if len(t) > 1 else None
        if t and t[0] == "f": out += [maps.get(cur, "")] * (len(t[1].split()) - 2)
    return out
a, b = images(sys.argv[1]), images(sys.argv[2])
if a != b or a.count("textures/skin colour.png") == 0 or a.count("") == 0:
    sys.exit("FAIL: PLY to OBJ: the faces' images differ (%d and %d faces)" % (len(a), len(b)))
PY
# The material library and the images it names go beside an output elsewhere, byte for byte,
# from the scan's directory (deform) or from the model, which carries them (export).
same_files() {  # same_files DIR: DIR holds the library and its images as $TMP does
  for f in scan.mtl "textures/skin colour.png" eyes.png; do
    cmp -s "$TMP/$f" "$1/$f" || { echo "FAIL: $1/$f is not the scan's $f" >&2; exit 1; }
  done
}
mkdir "$TMP/elsewhere"
"$STRATA" deform "$TMP/seams.obj" --edit "$TMP/bend.json" -o "$TMP/elsewhere/out.obj" -q >/dev/null 2>"$TMP/lib.err"
same_files "$TMP/elsewhere"
[ "$(grep -cv 'faces flipped' "$TMP/lib.err")" -eq 0 ] ||
  { echo "FAIL: notes on a copied library: $(cat "$TMP/lib.err")" >&2; exit 1; }
"$STRATA" build "$TMP/elsewhere/out.obj" -o "$TMP/elsewhere/m.strata" -q >/dev/null 2>&1
"$STRATA" info "$TMP/elsewhere/m.strata" --json | python3 -c "
import json, sys
a = json.load(sys.stdin)['bands'][-1]['attributes']
if a['companion_files'] != ['scan.mtl', 'textures/skin colour.png', 'eyes.png']: sys.exit('FAIL: info: %s' % a)"
mkdir "$TMP/model_only"
cp "$TMP/seams_edited.strata" "$TMP/model_only/"
mv "$TMP/textures" "$TMP/textures.away"  # the model alone has them now
mkdir "$TMP/model_only/out"
"$STRATA" export "$TMP/model_only/seams_edited.strata" -o "$TMP/model_only/out/m.obj" >/dev/null
mv "$TMP/textures.away" "$TMP/textures"
same_files "$TMP/model_only/out"
# A file of that name already there is the user's: kept as it is, with a note. An image the
# library names that is not there is a note naming it; the rest is copied.
printf 'mine' >"$TMP/model_only/out/eyes.png"
rm "$TMP/model_only/out/scan.mtl"
"$STRATA" export "$TMP/model_only/seams_edited.strata" -o "$TMP/model_only/out/m.obj" >/dev/null 2>"$TMP/export2.err"
grep -q "eyes.png is already there (a file that differs from the scan's of that name); it was left as it is, and .*m.obj names it" "$TMP/export2.err" &&
  [ "$(cat "$TMP/model_only/out/eyes.png")" = mine ] && cmp -s "$TMP/scan.mtl" "$TMP/model_only/out/scan.mtl" ||
  { echo "FAIL: an existing image: $(cat "$TMP/export2.err")" >&2; exit 1; }
printf 'newmtl skin\nmap_Kd gone.png\nnewmtl eyes\n' >"$TMP/elsewhere/scan.mtl"
mkdir "$TMP/again"
"$STRATA" deform "$TMP/elsewhere/out.obj" --edit "$TMP/bend.json" -o "$TMP/again/out.obj" -q >/dev/null 2>"$TMP/gone.err"
grep -q "scan.mtl: texture image 'gone.png' is not carried along: it is not there (.*gone.png)" "$TMP/gone.err" &&
  cmp -s "$TMP/elsewhere/scan.mtl" "$TMP/again/scan.mtl" ||
  { echo "FAIL: a missing image: $(cat "$TMP/gone.err")" >&2; exit 1; }
# A library that is not there at all: a note at reading, and one on the output that names it.
rm "$TMP/elsewhere/scan.mtl"
mkdir "$TMP/third"
"$STRATA" deform "$TMP/elsewhere/out.obj" --edit "$TMP/bend.json" -o "$TMP/third/out.obj" -q >/dev/null 2>"$TMP/nolib.err"
grep -q "out.obj: material library 'scan.mtl' is not carried along: it is not there" "$TMP/nolib.err" &&
  grep -q "third/out.obj refers to the material library 'scan.mtl', which is not in its directory" "$TMP/nolib.err" ||
  { echo "FAIL: no notes on a missing library: $(cat "$TMP/nolib.err")" >&2; exit 1; }
# A library named with a space (Blender's "mtllib my scan.mtl"): one file, copied, and no note.
mkdir "$TMP/spaced" "$TMP/spaced_out"
sed 's/^mtllib scan.mtl$/mtllib my scan.mtl/' "$TMP/seams.obj" >"$TMP/spaced/my scan.obj"
cp "$TMP/scan.mtl" "$TMP/spaced/my scan.mtl"
cp -r "$TMP/textures" "$TMP/eyes.png" "$TMP/spaced/"
"$STRATA" deform "$TMP/spaced/my scan.obj" --edit "$TMP/bend.json" -o "$TMP/spaced_out/out.obj" -q >/dev/null 2>"$TMP/spaced.err"
cmp -s "$TMP/scan.mtl" "$TMP/spaced_out/my scan.mtl" && cmp -s "$TMP/eyes.png" "$TMP/spaced_out/eyes.png" &&
  [ "$(grep -cv 'faces flipped' "$TMP/spaced.err")" -eq 0 ] ||
  { echo "FAIL: a library named with a space: $(ls "$TMP/spaced_out") $(cat "$TMP/spaced.err")" >&2; exit 1; }
# A file of the scan's named as an output of the command (here the report): the output wins.
printf 'newmtl skin\nmap_Kd r.json\nnewmtl eyes\n' >"$TMP/elsewhere/scan.mtl"
printf 'not json' >"$TMP/elsewhere/r.json"
mkdir "$TMP/fourth"
"$STRATA" deform "$TMP/elsewhere/out.obj" --edit "$TMP/bend.json" -o "$TMP/fourth/out.obj" --report "$TMP/fourth/r.json" -q >/dev/null 2>"$TMP/clash.err"
grep -q "fourth/r.json is an output of this command; the scan's file of that name is not written" "$TMP/clash.err" &&
  python3 -c "import json; json.load(open('$TMP/fourth/r.json'))" ||
  { echo "FAIL: a companion named as the report: $(cat "$TMP/clash.err")" >&2; exit 1; }
# Texture coordinates on only some face corners cannot be kept: a note naming the file.
sed '0,/^f /s|^f \([0-9]*\)/[0-9]* |f \1 |' "$TMP/seams.obj" >"$TMP/partial.obj"
"$STRATA" deform "$TMP/partial.obj" --edit "$TMP/bend.json" -o "$TMP/partial_out.obj" -q >/dev/null 2>"$TMP/partial.err"
grep -q "partial.obj: not kept: texture coordinates: 1 of the [0-9]* face corners have none" "$TMP/partial.err" ||
  { echo "FAIL: no note on partial texture coordinates: $(cat "$TMP/partial.err")" >&2; exit 1; }

# A colour of NaN is an error naming the file; nothing is written.
sed '0,/^v /s/^v \(.*\)$/v \1 nan 0 0/' "$TMP/case/detail.obj" >"$TMP/nan.obj"
sed -i '0,/^v .* nan 0 0$/!{/^v /s/$/ 0 0 0/}' "$TMP/nan.obj"
expect_exit 1 "nan.obj: line .*: vertex 0 has a non-finite colour" "$TMP/nan.err" \
  "$STRATA" deform "$TMP/nan.obj" --edit "$TMP/bend.json" -o "$TMP/nan_out.obj"
[ ! -e "$TMP/nan_out.obj" ] || { echo "FAIL: output written for a NaN colour" >&2; exit 1; }
echo "attributes: ok"
