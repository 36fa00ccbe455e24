#!/usr/bin/env python3
"""Pixel statistics of PNG files for the viewer's pixel tests (standard library only).

png_stats.py IMAGE.png [OTHER.png]  prints one JSON object:
  width, height; foreground: fraction of pixels differing from the background (the top-left
  pixel's colour) by more than 24 in some channel; centre_foreground: the same over the central
  10% x 10% box; reddish: fraction of pixels with R > 150, G < 110, B < 110 (bluish: B > 150,
  R < 110, G < 110); red_x, blue_x (red_y, blue_y): the mean x of those pixels over the width (y
  over the height, 0 at the top; -1: none); and with OTHER.png,
  changed: fraction of pixels differing from OTHER by more than 24 in some channel.
Decodes 8-bit non-interlaced greyscale/RGB/RGBA PNGs (what stb_image_write produces).
"""
import json
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise SystemExit(f"{path}: not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, ctype, _, _, interlace = header
    channels = {0: 1, 2: 3, 6: 4}.get(ctype)
    if depth != 8 or channels is None or interlace:
        raise SystemExit(f"{path}: unsupported PNG layout")
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    pixels = []
    for line in rows:
        for x in range(width):
            px = line[x * channels:(x + 1) * channels]
            pixels.append((px[0], px[0], px[0]) if channels == 1 else tuple(px[:3]))
    return width, height, pixels


def mean_x(px, w, test):
    xs = [i % w for i, p in enumerate(px) if test(p)]
    return sum(xs) / len(xs) / w if xs else -1.0


def differs(p, q):
    return max(abs(p[0] - q[0]), abs(p[1] - q[1]), abs(p[2] - q[2])) > 24


def main():
    w, h, px = read_png(sys.argv[1])
    bg = px[0]
    fg = sum(1 for p in px if differs(p, bg))
    x0, x1, y0, y1 = int(0.45 * w), int(0.55 * w) + 1, int(0.45 * h), int(0.55 * h) + 1
    centre = [px[y * w + x] for y in range(y0, y1) for x in range(x0, x1)]
    out = {
        "width": w,
        "height": h,
        "foreground": fg / len(px),
        "centre_foreground": sum(1 for p in centre if differs(p, bg)) / len(centre),
        "reddish": sum(1 for p in px if p[0] > 150 and p[1] < 110 and p[2] < 110) / len(px),
        "bluish": sum(1 for p in px if p[2] > 150 and p[0] < 110 and p[1] < 110) / len(px),
        # Where the red and the blue pixels lie across the image: the mean x of each, 0 to 1.
        "red_x": mean_x(px, w, lambda p: p[0] > 150 and p[1] < 110 and p[2] < 110),
        "blue_x": mean_x(px, w, lambda p: p[2] > 150 and p[0] < 110 and p[1] < 110),
        "red_y": mean_x([px[(i % h) * w + i // h] for i in range(w * h)], h,
                        lambda p: p[0] > 150 and p[1] < 110 and p[2] < 110),
        "blue_y": mean_x([px[(i % h) * w + i // h] for i in range(w * h)], h,
                         lambda p: p[2] > 150 and p[0] < 110 and p[1] < 110),
    }
    if len(sys.argv) > 2:
        w2, h2, px2 = read_png(sys.argv[2])
        out["changed"] = 1.0 if (w2, h2) != (w, h) else sum(1 for p, q in zip(px, px2) if differs(p, q)) / len(px)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
