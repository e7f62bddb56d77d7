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


def write_png(path, w, h, images):
    """Writes images of w x h pixels (as `load` gives them) side by side to
    an sRGB PNG."""
    import zlib

    def srgb(x):
        x = min(max(x, 0.0), 1.0)
        return int((12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055) * 255 + 0.5)

    rows = b"".join(b"\0" + bytes(srgb(v) for img in images for x in range(w) for v in img[y * w + x])
                    for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", len(images) * w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


if __name__ == "__main__":
    # python3 bench/pfm.py OUT.png A.pfm B.pfm ...: the images side by side.
    import sys

    out, inputs = sys.argv[1], sys.argv[2:]
    loaded = [load(f) for f in inputs]
    write_png(out, loaded[0][0], loaded[0][1], [img for _, _, img in loaded])
    print(f"wrote {out}")
