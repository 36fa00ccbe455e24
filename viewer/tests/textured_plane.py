#!/usr/bin/env python3
"""Writes textured planes for the viewer's pixel tests (standard library only):

textured_plane.py DIR  writes into DIR:
  maps/rb.png  a 64 x 64 PNG, the left half red, the right half blue;
  maps/br.png  the top half blue, the bottom half red (which way up the texture is drawn);
  plane.obj    a 2 x 1 plane of 400 triangles in z = 0, vt per vertex, material rb (plane.mtl);
  upright.obj  the same plane with material br (upright.mtl);
  seams.obj    the plane with vt per face corner: the left half's faces map to the red half, the
               right half's to the blue half, so the middle column's vertices have two each.
"""
import os
import struct
import sys
import zlib

out = sys.argv[1]
os.makedirs(out + "/maps", exist_ok=True)
W = H = 64


def write_png(path, colour_of):
    """colour_of(x, y): RGB of pixel (x, y), y = 0 the top row."""
    raw = b"".join(b"\x00" + b"".join(bytes(colour_of(x, y)) for x in range(W)) for y in range(H))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
    open(path, "wb").write(png)


RED, BLUE = (220, 30, 30), (30, 30, 220)
write_png(out + "/maps/rb.png", lambda x, y: RED if x < W // 2 else BLUE)
write_png(out + "/maps/br.png", lambda x, y: BLUE if y < H // 2 else RED)
open(out + "/plane.mtl", "w").write("newmtl rb\nKd 1 1 1\nmap_Kd -clamp on maps/rb.png\n")
open(out + "/upright.mtl", "w").write("newmtl rb\nmap_Kd maps/br.png\n")
# A 2 x 1 plane of 20 x 10 quads; per vertex: u from 0.05 to 0.95 across, v across y.
nx, ny = 20, 10
v, vt, f, ft = [], [], [], []
for j in range(ny + 1):
    for i in range(nx + 1):
        v.append((2.0 * i / nx, 1.0 * j / ny, 0.0))
        vt.append((0.05 + 0.9 * i / nx, 0.05 + 0.9 * j / ny))
for j in range(ny):
    for i in range(nx):
        a, b, c, d = j * (nx + 1) + i, j * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i
        f += [(a, b, c), (a, c, d)]
def obj(path, faces_vt, vts, library="plane.mtl"):
    with open(path, "w") as o:
        o.write("mtllib %s\n" % library)
        for p in v: o.write("v %g %g %g\n" % p)
        for t in vts: o.write("vt %.6f %.6f\n" % t)
        o.write("usemtl rb\n")
        for tri, tt in zip(f, faces_vt): o.write("f " + " ".join("%d/%d" % (a + 1, b + 1) for a, b in zip(tri, tt)) + "\n")
obj(out + "/plane.obj", f, vt)
obj(out + "/upright.obj", f, vt, "upright.mtl")
# Seams: the left half's faces map to u in [0.05, 0.45] (red), the right half's to [0.55, 0.95]
# (blue); the middle column's vertices have a vt on each side.
seam_vt, seam_ft = [], []
for tri in f:
    right = sum(v[a][0] for a in tri) / 3 > 1.0
    tt = []
    for a in tri:
        x, y = v[a][0], v[a][1]
        u = 0.55 + 0.4 * (x - 1.0) if right else 0.05 + 0.4 * x
        seam_vt.append((u, 0.05 + 0.9 * y)); tt.append(len(seam_vt) - 1)
    seam_ft.append(tt)
obj(out + "/seams.obj", seam_ft, seam_vt)
