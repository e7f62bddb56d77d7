"""Writes the slide of bench/scenes/projection.pbrt (pbrt-v4's `projection`
light): 48 x 32 texels, a dim frame, a red block at the top left and a
green one at the bottom right, so that a flipped or turned slide shows. PFM.

    python3 bench/projection_slide.py OUT.pfm
"""
import struct
import sys


def main():
    w, h = 48, 32
    rows = []
    for y in range(h):
        row = []
        for x in range(w):
            c = (0.6, 0.6, 0.6)
            if x < 4 or x >= w - 4 or y < 3 or y >= h - 3:
                c = (0.15, 0.15, 0.15)
            if 6 <= x < 18 and 5 <= y < 13:
                c = (3.0, 0.2, 0.2)
            if 30 <= x < 42 and 19 <= y < 27:
                c = (0.2, 3.0, 0.3)
            row.append(c)
        rows.append(row)
    with open(sys.argv[1], "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        # PFM rows run bottom up.
        for row in reversed(rows):
            f.write(b"".join(struct.pack("<3f", *c) for c in row))


if __name__ == "__main__":
    main()
