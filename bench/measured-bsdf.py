#!/usr/bin/env python3
"""Writes a synthetic RGL measured BSDF (`.bsdf` tensor file, Dupuy & Jakob
2018) that pbrt-v4's `Material "measured"` reads: an isotropic
Trowbridge-Reitz (GGX) microfacet reflector of roughness alpha with a
reflectance that rises from 0.2 (400 nm) to 0.9 (700 nm), for
bench/measured.sh.

    python3 bench/measured-bsdf.py OUT.bsdf [--alpha A] [--res N] [--thetas K]
        [--theta-max DEG] [--lum-res M] [--ndf-rows R] [--lambdas L]
        [--lum-slope S] [--white] [--rgl-like] [--check]

theta_i is laid out as in RGL's files (their isotropic *_rgb.bsdf hold 8
values: 0, then about 28 to 90 degrees evenly, the inner ones a little
different per material): 0, then K - 1 values evenly from 28 degrees to
--theta-max (90). --rgl-like takes the other sizes of those files too:
vndf 128 x 128, ndf and sigma 2 x 128 (two equal rows), luminance and
spectra 32 x 32, 8 theta_i.

The tables, as pbrt-v4 reads them (bxdfs.cpp, MeasuredBxDF):
  f(wo, wi) = spectra(s; theta_o, lambda) * ndf(wm) / (4 sigma(wo) cos theta_i)
where s is the point of the unit square that the VNDF warp of wo takes to
wm (pbrt-v4 inverts the `vndf` table to find it), and every 2-D grid spans
[0, 1]^2 with x = sqrt(theta * 2 / pi) (fastest index) and
y = phi / (2 pi) + 1/2; for an isotropic file the phi of wm is taken
relative to the phi of wo.
  ndf   [R, N]: D(wm), GGX, in 1/sr (D(wm) cos theta_m integrates to 1).
  sigma [R, N]: integral of D(wm) max(0, wo.wm) dwm = cos theta_o / G1(wo),
        the projected area of the microsurface, as a function of wo.
  vndf  [1, K, N, N]: per theta_i, the visible-normal density of wm,
        D(wm) max(0, wo.wm) / sigma(wo), times the Jacobian of the grid
        mapping, dw = 2 pi^2 x sin(theta_m) dx dy (pbrt-v4 divides its pdf by
        it); pbrt-v4 normalises each slice itself.
  luminance [1, K, M, M]: a density over the VNDF warp's input square that
        pbrt-v4 samples first (then the VNDF warp), here 1 + S * x.
  spectra [1, K, L, M, M]: R(lambda) * (1 + S * x) / (1 + S), over the same
        square as luminance (so luminance is the spectra's shape, as in RGL
        files, where it is their luminance); S = 0 makes both constant.
  jacobian [1] = 1: in RGL files and in Mitsuba, 1 says that spectra is to be
        multiplied by ndf / (4 sigma) (0: spectra is already f cos theta_i);
        pbrt-v4 only checks the field's shape and always multiplies.
With spectra <= R(lambda) the BRDF is R D G1(wo) / (4 cos theta_o cos theta_i)
at most, whose directional albedo is at most R (the visible normals whose
mirror direction stays above the horizon). --check prints it numerically.

--white writes R = 1 at every wavelength (for a white-furnace test).
"""
import argparse
import math
import struct
import sys

import numpy as np

# pbrt-v4's Tensor::Type codes.
UINT8, FLOAT32 = 1, 10


def theta2u(theta):
    return np.sqrt(theta * (2 / np.pi))


def u2theta(u):
    return u * u * (np.pi / 2)


def u2phi(u):
    return (2 * u - 1) * np.pi


def ggx_d(cos_m, alpha):
    """Trowbridge-Reitz D(wm), in 1/sr, for cos theta_m >= 0."""
    c2 = cos_m * cos_m
    return alpha * alpha / (np.pi * (c2 * (alpha * alpha - 1) + 1) ** 2)


def ggx_sigma(cos_o, alpha):
    """integral D(wm) max(0, wo.wm) dwm = cos theta_o (1 + Lambda(wo))."""
    c2 = cos_o * cos_o
    return 0.5 * (cos_o + np.sqrt(c2 + alpha * alpha * (1 - c2)))


def reflectance(lam, white):
    if white:
        return np.ones_like(lam)
    return np.clip(0.2 + 0.7 * (lam - 400.0) / 300.0, 0.2, 0.9)


def write_tensor(path, fields):
    """fields: list of (name, numpy array); pbrt-v4's / RGL's tensor_file
    v1.0, little endian, each field's data 8-byte aligned (as RGL's
    write_tensor does)."""
    header = bytearray(b"tensor_file\0" + struct.pack("<BBI", 1, 0, len(fields)))
    offsets = []
    for name, a in fields:
        code = {np.dtype(np.uint8): UINT8, np.dtype(np.float32): FLOAT32}[a.dtype]
        header += struct.pack("<H", len(name)) + name.encode("ascii")
        header += struct.pack("<HB", a.ndim, code)
        offsets.append(len(header))
        header += struct.pack("<Q", 0)
        header += struct.pack("<" + "Q" * a.ndim, *a.shape)
    data = bytearray()
    pos = len(header)
    for (name, a), at in zip(fields, offsets):
        pad = (-(pos + len(data))) % 8
        data += b"\0" * pad
        struct.pack_into("<Q", header, at, pos + len(data))
        data += np.ascontiguousarray(a).astype(a.dtype.newbyteorder("<")).tobytes()
    with open(path, "wb") as f:
        f.write(header + data)
    return len(header) + len(data)


def bilinear(table, x, y):
    """pbrt-v4's PiecewiseLinear2D<0>::Evaluate (unnormalised) of table
    [ny, nx] at (x, y) in [0, 1]^2."""
    ny, nx = table.shape
    fx, fy = x * (nx - 1), y * (ny - 1)
    ix = np.minimum(fx.astype(int), nx - 2)
    iy = np.minimum(fy.astype(int), ny - 2)
    wx, wy = fx - ix, fy - iy
    return ((1 - wy) * ((1 - wx) * table[iy, ix] + wx * table[iy, ix + 1])
            + wy * ((1 - wx) * table[iy + 1, ix] + wx * table[iy + 1, ix + 1]))


def albedo(theta_o, alpha, ndf=None, sigma=None, n=768):
    """integral over wi of D(wm) / (4 sigma(wo)) dwi (f cos theta_i with
    spectra = 1), by the midpoint rule over (cos theta_i, phi_i); with ndf
    and sigma tables, read as pbrt-v4 reads them, else in closed form."""
    ci = (np.arange(n) + 0.5) / n
    pi_ = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    c, p = np.meshgrid(ci, pi_, indexing="ij")
    s = np.sqrt(1 - c * c)
    wi = np.stack([s * np.cos(p), s * np.sin(p), c])
    wo = np.array([math.sin(theta_o), 0.0, math.cos(theta_o)])[:, None, None]
    wm = wi + wo
    wm /= np.linalg.norm(wm, axis=0)
    if ndf is None:
        d = ggx_d(wm[2], alpha)
        sig = ggx_sigma(math.cos(theta_o), alpha)
    else:
        theta_m = np.arccos(np.clip(wm[2], -1, 1))
        phi_m = np.arctan2(wm[1], wm[0])  # phi_o = 0
        y = phi_m / (2 * np.pi) + 0.5
        y -= np.floor(y)
        d = bilinear(ndf, theta2u(theta_m), y)
        sig = bilinear(sigma, np.array([theta2u(theta_o)]), np.array([0.5]))[0]
    dw = (1.0 / n) * (2 * np.pi / (2 * n))
    return float(np.sum(d / (4 * sig)) * dw)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--alpha", type=float, default=0.3)
    ap.add_argument("--res", type=int, default=32,
                    help="N: nx = ny of the vndf grid, and of the others unless set")
    ap.add_argument("--lum-res", type=int, help="M: nx = ny of luminance and spectra (N)")
    ap.add_argument("--ndf-rows", type=int, help="R: ny of ndf and sigma (N; nx is N)")
    ap.add_argument("--thetas", type=int, default=9, help="theta_i count K")
    ap.add_argument("--theta-max", type=float, default=90.0, help="last theta_i, degrees")
    ap.add_argument("--lambdas", type=int, default=11, help="wavelength count, 360-830 nm")
    ap.add_argument("--lum-slope", type=float, default=0.5)
    ap.add_argument("--white", action="store_true", help="R = 1 at every wavelength")
    ap.add_argument("--rgl-like", action="store_true",
                    help="RGL's sizes: --res 128 --lum-res 32 --ndf-rows 2 --thetas 8")
    ap.add_argument("--check", action="store_true", help="print directional albedos")
    a = ap.parse_args()
    if a.rgl_like:
        a.res, a.lum_res, a.ndf_rows, a.thetas = 128, 32, 2, 8
    alpha, n, k = a.alpha, a.res, a.thetas
    m = a.lum_res or n
    rows = a.ndf_rows or n
    if min(n, m, rows) < 2 or k < 2:
        ap.error("every grid needs at least 2 x 2 points and 2 theta_i")

    # theta_i as in RGL's files: 0, then evenly from 28 degrees to theta_max.
    first = min(28.0, a.theta_max / 3)
    theta_i = np.radians(np.concatenate([[0.0], np.linspace(first, a.theta_max, k - 1)]))
    phi_i = np.array([0.0])  # one value: isotropic (pbrt-v4: n_phi <= 2)
    lam = np.linspace(360, 830, a.lambdas)

    def grid(nx, ny):
        """(x, y) of a [ny, nx] grid over [0, 1]^2, x fastest."""
        return np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))

    # ndf and sigma: x = u_theta (of wm, of wo); isotropic, so equal rows.
    x, _ = grid(n, rows)
    ndf = ggx_d(np.cos(u2theta(x)), alpha)
    sigma = ggx_sigma(np.cos(u2theta(x)), alpha)

    # vndf: per theta_i (wo at phi 0), over (u_theta, u_phi) of wm.
    X, Y = grid(n, n)
    theta_m, dphi = u2theta(X), u2phi(Y)
    cos_m, sin_m = np.cos(theta_m), np.sin(theta_m)
    d = ggx_d(cos_m, alpha)
    vndf = np.empty((1, k, n, n))
    for j, t in enumerate(theta_i):
        dot = math.sin(t) * sin_m * np.cos(dphi) + math.cos(t) * cos_m
        dvis = np.maximum(dot, 0) * d / ggx_sigma(math.cos(t), alpha)
        vndf[0, j] = dvis * 2 * np.pi ** 2 * X * sin_m

    # luminance and spectra: over the VNDF warp's input square.
    Xs, _ = grid(m, m)
    shape = 1 + a.lum_slope * Xs
    luminance = np.broadcast_to(shape, (1, k, m, m))
    r = reflectance(lam, a.white)
    spectra = (r[None, None, :, None, None] * (shape / shape.max())[None, None, None]
               * np.ones((1, k, 1, 1, 1)))

    desc = (f"synthetic GGX alpha={alpha} (bench/measured-bsdf.py), "
            f"R {'1' if a.white else '0.2@400nm..0.9@700nm'}").encode("ascii")
    f32 = lambda v: np.ascontiguousarray(v, dtype=np.float32)
    fields = [
        ("description", np.frombuffer(desc, dtype=np.uint8)),
        ("jacobian", np.array([1], dtype=np.uint8)),
        ("theta_i", f32(theta_i)),
        ("phi_i", f32(phi_i)),
        ("wavelengths", f32(lam)),
        ("ndf", f32(ndf)),
        ("sigma", f32(sigma)),
        ("vndf", f32(vndf)),
        ("luminance", f32(luminance)),
        ("spectra", f32(spectra)),
    ]
    size = write_tensor(a.out, fields)
    print(f"wrote {a.out}: {size} bytes, GGX alpha {alpha}, vndf {n}x{n}, "
          f"ndf/sigma {rows}x{n}, luminance/spectra {m}x{m}, "
          f"{k} theta_i (0-{a.theta_max:g} deg), {len(lam)} wavelengths "
          f"{lam[0]:g}-{lam[-1]:g} nm, R {'1' if a.white else '0.2-0.9'}, "
          f"luminance 1 + {a.lum_slope:g} x")

    if a.check:
        print("directional albedo with spectra = 1 (an upper bound; x R(lambda) for the file):")
        print("  theta_o  closed-form  pbrt-tables")
        for deg in (0, 30, 45, 60, 75, 85, 89):
            t = math.radians(deg)
            print(f"  {deg:7d}  {albedo(t, alpha):11.4f}  "
                  f"{albedo(t, alpha, f32(ndf), f32(sigma)):11.4f}")


if __name__ == "__main__":
    sys.exit(main())
