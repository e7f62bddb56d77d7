"""Writes the grey equal-area intensity image of bench/scenes/goniometric.pbrt
(pbrt-v4's `goniometric` light): a dim base, a strong lobe and a weaker one
in other directions, so that a turned or mirrored reading shows. PFM.

    python3 bench/goniometric_map.py OUT.pfm [SIZE]
"""
import math
import struct
import sys

from portal_sky import square_to_sphere


def main():
    out = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 64
    lobes = [((0.2, 0.3, -0.93), 30.0, 0.35), ((0.8, -0.5, 0.3), 8.0, 0.25)]
    rows = []
    for y in range(n):
        row = []
        for x in range(n):
            w = square_to_sphere((x + 0.5) / n, (y + 0.5) / n)
            v = 0.3
            for d, k, width in lobes:
                norm = math.sqrt(sum(c * c for c in d))
                c = max(-1.0, min(1.0, sum(a * b / norm for a, b in zip(w, d))))
                v += k * math.exp(-((math.acos(c) / width) ** 2))
            row.append(v)
        rows.append(row)
    with open(out, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (n, n))
        for row in reversed(rows):
            f.write(b"".join(struct.pack("<3f", v, v, v) for v in row))


if __name__ == "__main__":
    main()
