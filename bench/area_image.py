"""Writes the emission image of bench/scenes/area-image.pbrt (pbrt-v4's
`diffuse` area light with a `filename`): 64 x 40 texels of 8-bit sRGB, a
dim blue-to-orange gradient with a red block at the top left and a green one
at the bottom right, so that a flipped or turned image shows. PNG.

    python3 bench/area_image.py OUT.png
"""
import struct
import sys
import zlib


def png(path, w, h, rows):
    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    raw = b"".join(b"\0" + bytes(v for px in row for v in px) for row in rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def main():
    w, h = 64, 40
    rows = []
    for y in range(h):
        row = []
        for x in range(w):
            t = x / (w - 1)
            c = (int(60 + 160 * t), int(90 + 40 * t), int(200 - 150 * t))
            if 6 <= x < 22 and 5 <= y < 15:
                c = (250, 30, 20)
            if 42 <= x < 58 and 25 <= y < 35:
                c = (30, 240, 40)
            row.append(c)
        rows.append(row)
    png(sys.argv[1], w, h, rows)


if __name__ == "__main__":
    main()
