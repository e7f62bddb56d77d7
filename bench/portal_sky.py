"""Writes the equal-area environment map of bench/scenes/portal.pbrt: a sky
brightening towards the zenith and a soft sun, as a PFM (pbrt-v4's
octahedral equal-area layout, +z up in the light's frame).

    python3 bench/portal_sky.py OUT.pfm [SIZE]
"""
import math
import struct
import sys


def square_to_sphere(u, v):
    """pbrt-v4's equal-area square-to-sphere map (Clarberg's octahedral)."""
    u, v = 2 * u - 1, 2 * v - 1
    up, vp = abs(u), abs(v)
    signed = 1 - (up + vp)
    r = 1 - abs(signed)
    phi = (math.pi / 4) * ((vp - up) / r + 1) if r != 0 else math.pi / 4
    z = math.copysign(1 - r * r, signed)
    cos_phi = math.copysign(math.cos(phi), u)
    sin_phi = math.copysign(math.sin(phi), v)
    s = r * math.sqrt(max(0.0, 2 - r * r))
    return cos_phi * s, sin_phi * s, z


def main():
    out = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 128
    # Towards the sun, in the light's frame: up (+z) 35 degrees, and round.
    sun = (0.3, -1.0, 0.6)
    norm = math.sqrt(sum(c * c for c in sun))
    sun = tuple(c / norm for c in sun)
    rows = []
    for y in range(n):
        row = []
        for x in range(n):
            w = square_to_sphere((x + 0.5) / n, (y + 0.5) / n)
            up = max(w[2], 0.0)
            sky = (0.25 + 0.5 * up, 0.35 + 0.6 * up, 0.6 + 0.9 * up) if w[2] > 0 else (0.15, 0.12, 0.1)
            c = max(-1.0, min(1.0, sum(a * b for a, b in zip(w, sun))))
            glow = 400.0 * math.exp(-((math.acos(c) / 0.07) ** 2))
            row.append((sky[0] + glow, sky[1] + 0.9 * glow, sky[2] + 0.75 * glow))
        rows.append(row)
    with open(out, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (n, n))
        # PFM rows run bottom up.
        for row in reversed(rows):
            f.write(b"".join(struct.pack("<3f", *px) for px in row))


if __name__ == "__main__":
    main()
