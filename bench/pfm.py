"""Reads the PFM images the bench scripts write (ours and pbrt-v4's)."""
import struct


def load(path):
    """(width, height, pixels): the pixels as (r, g, b) tuples, top row first
    (PFM stores rows bottom up)."""
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF", f"{path}: not an RGB PFM"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        fmt = "<" if scale < 0 else ">"
        d = struct.unpack(f"{fmt}{w * h * 3}f", f.read(w * h * 12))
    pixels = []
    for y in range(h):
        row = h - 1 - y
        pixels.extend(d[3 * (row * w + x):3 * (row * w + x) + 3] for x in range(w))
    return w, h, pixels
