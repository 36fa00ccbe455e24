#!/usr/bin/env python3
"""subdivide_off.py IN.off OUT.off [LEVELS]: 1-to-4 midpoint subdivision of a triangle OFF mesh
(each level multiplies the face count by 4; the surface is unchanged). Makes large test models,
e.g. the 27k-face bear scan into a 110k-face one for the viewer's frame-time benchmark."""
import sys


def main():
    src, dst = sys.argv[1], sys.argv[2]
    levels = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    tokens = [line.split('#')[0].split() for line in open(src)]
    tokens = [t for t in tokens if t]
    assert tokens[0][0] == "OFF"
    nv, nf = int(tokens[1][0]), int(tokens[1][1])
    verts = [tuple(float(x) for x in t[:3]) for t in tokens[2:2 + nv]]
    faces = [tuple(int(x) for x in t[1:4]) for t in tokens[2 + nv:2 + nv + nf]]
    for _ in range(levels):
        mid = {}
        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                pa, pb = verts[a], verts[b]
                mid[key] = len(verts)
                verts.append(tuple(0.5 * (x + y) for x, y in zip(pa, pb)))
            return mid[key]
        out = []
        for a, b, c in faces:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
        faces = out
    with open(dst, "w") as f:
        f.write(f"OFF\n{len(verts)} {len(faces)} 0\n")
        for v in verts:
            f.write(f"{v[0]!r} {v[1]!r} {v[2]!r}\n")
        for a, b, c in faces:
            f.write(f"3 {a} {b} {c}\n")


if __name__ == "__main__":
    main()
