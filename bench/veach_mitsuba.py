#!/usr/bin/env python3
"""Bitterli's `veach-mis` (../shared/bitterli/veach-mis/scene-v4.pbrt) in
Mitsuba 3, built from the pbrt file's own values, for comparing our path
tracer's noise with Mitsuba's (issue 13's veach-mis target).

    python bench/veach_mitsuba.py render OUT.exr [--spp N] [--seed S] [--passes P] [--width W --height H]
    python bench/veach_mitsuba.py seeds [--seeds 0-7] [--ours] [--spp 256]

`render` writes one Mitsuba image (with --passes, the mean of P renders of
--spp each: a converged image); `seeds` renders Mitsuba (and with --ours our
path tracer, target/release/raytracer) at each seed and prints each render's
relative MSE and mean luminance ratio (`raytracer compare --max-luminance 4`)
against the shipped reference box-averaged to the render's size, then their
mean, spread and median: the error is fireflies, so one seed says little.
Images go to target/veach-mis/. Run from the mitsuba virtual environment
(target/mitsuba-venv/bin/python).

Needs Mitsuba 3 with the llvm_ad_rgb variant (bench/vs-mitsuba.sh installs it
into target/mitsuba-venv) and DRJIT_LIBLLVM_PATH pointing at libLLVM.

What is carried over from the pbrt file, and how:
- camera: the `Transform` before WorldBegin is pbrt's camera-from-world; its
  inverse, times a flip of x (pbrt's camera space is left-handed, x to the
  right; Mitsuba's sensor has x to the left), is Mitsuba's to_world. pbrt's
  `fov` is the shorter image axis's: fov_axis "smaller";
- pixel filter: pbrt's `triangle` of radius 1 is Mitsuba's `tent` (radius 1);
- integrator: pbrt's `maxdepth` D counts bounces (1: direct light only),
  Mitsuba's `max_depth` counts path segments (2: direct light only), so D + 1;
  Russian roulette then never starts in either (Mitsuba's rr_depth is 5);
- sampler: `independent` (Mitsuba's plain sampler);
- meshes: the trianglemesh P/indices as they are, with the file's per-vertex
  normals; every BSDF wrapped in `twosided` (pbrt's materials reflect on
  both sides, Mitsuba's on the front only);
- conductors: pbrt-v4's `conductor` with `remaproughness false` takes
  u/vroughness as the Trowbridge-Reitz alpha, which is Mitsuba's `ggx` alpha;
  eta and k as the file's RGB values;
- diffuse: the RGB reflectance; the lights' `Null` material: black diffuse;
- sphere area lights: a sphere shape with an `area` emitter of the file's
  `L` (pbrt-v4 normalises an RGB illuminant so that `L` is the RGB radiance
  the film records).
Not carried over: pbrt-v4's (and our) masking-shadowing is Smith's
height-correlated form; Mitsuba's GGX takes the separable G1(wo) G1(wi),
which leaves the roughest plate, seen at grazing angles, about 2% darker
than ours (BENCHMARKS.md, "veach-mis: the 0.016 target against Mitsuba 3").
"""
import argparse
import os
import re
import subprocess
import sys

import numpy as np

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
PBRT = os.path.join(ROOT, "..", "shared", "bitterli", "veach-mis", "scene-v4.pbrt")
RT = os.path.join(ROOT, "target", "release", "raytracer")


def tokens(text):
    text = re.sub(r"#[^\n]*", "", text)
    return re.findall(r'"[^"]*"|\[|\]|[^\s\[\]"]+', text)


def parse(path):
    """The pbrt file as a list of (directive, [args], {param: values}); only
    what this scene uses."""
    toks = tokens(open(path).read())
    out = []
    i = 0
    while i < len(toks):
        d = toks[i]
        i += 1
        args, params = [], {}
        if d in ("Transform",):
            assert toks[i] == "["
            j = toks.index("]", i)
            args = [float(x) for x in toks[i + 1:j]]
            i = j + 1
        while i < len(toks) and (toks[i].startswith('"') or toks[i] == "["):
            if toks[i] == "[":  # a bare list (none expected but Transform's)
                raise SystemExit(f"unexpected list after {d}")
            s = toks[i].strip('"')
            i += 1
            if " " in s:  # a typed parameter: values follow
                ty, name = s.split()
                if toks[i] == "[":
                    j = toks.index("]", i)
                    vals = toks[i + 1:j]
                    i = j + 1
                else:
                    vals = [toks[i]]
                    i += 1
                vals = [v.strip('"') for v in vals]
                if ty in ("float", "rgb", "point3", "normal", "point2", "integer"):
                    vals = [float(v) for v in vals]
                elif ty == "bool":
                    vals = [v == "true" for v in vals]
                params[name] = (ty, vals)
            else:
                args.append(s)
        out.append((d, args, params))
    return out


def mat4(m):
    """pbrt's Transform lists the matrix column by column."""
    return np.array(m, dtype=np.float64).reshape(4, 4).T


def write_ply(path, p, n, idx):
    with open(path, "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {len(p)}\n")
        f.write("property float x\nproperty float y\nproperty float z\n")
        if n is not None:
            f.write("property float nx\nproperty float ny\nproperty float nz\n")
        f.write(f"element face {len(idx)}\nproperty list uchar int vertex_indices\nend_header\n")
        for i in range(len(p)):
            f.write(" ".join(repr(float(c)) for c in (list(p[i]) + ([] if n is None else list(n[i])))) + "\n")
        for t in idx:
            f.write(f"3 {t[0]} {t[1]} {t[2]}\n")


def scene_dict(path, width, height, spp, mesh_dir):
    import mitsuba as mi

    os.makedirs(mesh_dir, exist_ok=True)

    directives = parse(path)
    d = {"type": "scene"}
    named = {}
    ctm = np.eye(4)
    stack = []
    world = False
    material = None
    area = None
    max_depth = 5
    fov = None
    rfilter = {"type": "box"}
    cam_from_world = None
    n_shape = 0
    for kind, args, params in directives:
        if kind == "Integrator":
            assert args == ["path"], args
            max_depth = int(params.get("maxdepth", ("integer", [5]))[1][0])
        elif kind == "Transform":
            ctm = mat4(args)
        elif kind == "PixelFilter":
            assert args == ["triangle"], args
            assert params["xradius"][1] == [1.0] and params["yradius"][1] == [1.0]
            rfilter = {"type": "tent"}
        elif kind == "Camera":
            assert args == ["perspective"], args
            fov = params["fov"][1][0]
            cam_from_world = ctm.copy()
        elif kind == "WorldBegin":
            world = True
            ctm = np.eye(4)
        elif kind == "MakeNamedMaterial":
            ty = params["type"][1][0]
            if ty == "diffuse":
                bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": params["reflectance"][1]}}
            elif ty == "conductor":
                assert params["remaproughness"][1] == [False]
                au, av = params["uroughness"][1][0], params["vroughness"][1][0]
                assert au == av
                bsdf = {"type": "roughconductor", "distribution": "ggx", "alpha": au,
                        "eta": {"type": "rgb", "value": params["eta"][1]},
                        "k": {"type": "rgb", "value": params["k"][1]}}
            else:
                raise SystemExit(f"material type {ty}")
            named[args[0]] = {"type": "twosided", "bsdf": bsdf}
        elif kind == "NamedMaterial":
            material = args[0]
        elif kind == "AttributeBegin":
            stack.append((ctm.copy(), material, area))
        elif kind == "AttributeEnd":
            ctm, material, area = stack.pop()
        elif kind == "AreaLightSource":
            assert args == ["diffuse"], args
            area = params["L"][1]
        elif kind == "Shape":
            n_shape += 1
            if args[0] == "trianglemesh":
                assert area is None
                p = np.array(params["P"][1]).reshape(-1, 3)
                p = (np.c_[p, np.ones(len(p))] @ ctm.T)[:, :3]
                idx = np.array(params["indices"][1], dtype=np.uint32).reshape(-1, 3)
                n = None
                if "N" in params:
                    n = np.array(params["N"][1]).reshape(-1, 3) @ np.linalg.inv(ctm[:3, :3])
                    n /= np.linalg.norm(n, axis=1, keepdims=True)
                ply = os.path.join(mesh_dir, f"mesh{n_shape}.ply")
                write_ply(ply, p, n, idx)
                d[f"mesh{n_shape}"] = {"type": "ply", "filename": ply, "bsdf": named[material]}
            elif args[0] == "sphere":
                r = params["radius"][1][0]
                c = (ctm @ np.array([0, 0, 0, 1.0]))[:3]
                assert np.allclose(ctm[:3, :3], np.eye(3)), ctm
                s = {"type": "sphere", "center": c.tolist(), "radius": r,
                     "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}}
                if area is not None:
                    s["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(area)}}
                d[f"sphere{n_shape}"] = s
            else:
                raise SystemExit(f"shape {args[0]}")
        elif kind in ("Sampler", "Film"):
            pass
        else:
            raise SystemExit(f"directive {kind}")
    assert world and fov is not None
    to_world = np.linalg.inv(cam_from_world) @ np.diag([-1.0, 1.0, 1.0, 1.0])
    d["integrator"] = {"type": "path", "max_depth": max_depth + 1}
    d["sensor"] = {
        "type": "perspective",
        "fov": fov,
        "fov_axis": "smaller",
        "to_world": mi.ScalarTransform4f(to_world.tolist()),
        "sampler": {"type": "independent", "sample_count": spp},
        "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
                 "rfilter": rfilter},
    }
    return d


def reference(width, height, out_dir):
    """The shipped reference box-averaged to width x height (`compare` takes equal sizes)."""
    import mitsuba as mi

    dst = os.path.join(out_dir, f"reference-{width}x{height}.exr")
    if not os.path.exists(dst):
        src = os.path.join(os.path.dirname(PBRT), "reference.exr")
        a = np.array(mi.Bitmap(src), dtype=np.float32)[:, :, :3]
        f = a.shape[1] // width
        assert a.shape[0] == f * height and a.shape[1] == f * width, (a.shape, width, height)
        b = a.reshape(height, f, width, f, 3).mean(axis=(1, 3))
        mi.Bitmap(np.ascontiguousarray(b)).write(dst)
    return dst


def compare(img, ref, max_lum):
    out = subprocess.run([RT, "compare", img, ref, "--max-luminance", max_lum],
                         check=True, capture_output=True, text=True).stdout.split()
    v = dict(zip(out[::2], out[1::2]))
    return float(v["rel_mse"]), float(v["luminance_ratio"])


def seeds(a, mi):
    """Both renderers at --spp over the seeds; per seed and in summary, relative
    MSE and mean luminance ratio against the shipped reference."""
    import time

    out_dir = os.path.join(ROOT, "target", "veach-mis")
    os.makedirs(out_dir, exist_ok=True)
    ref = reference(a.width, a.height, out_dir)
    scene = mi.load_dict(scene_dict(PBRT, a.width, a.height, a.spp, os.path.join(out_dir, "meshes")))
    mi.render(scene, spp=a.spp, seed=999999)  # compiles the kernels: the timed renders compile nothing
    lo, hi = (int(x) for x in a.seeds.split("-"))
    rows = {"ours": [], "mitsuba": []}
    for seed in range(lo, hi + 1):
        for who in ("mitsuba", "ours") if a.ours else ("mitsuba",):
            img = os.path.join(out_dir, f"{who}-{a.spp}spp-{seed}.exr")
            t0 = time.perf_counter()
            if who == "mitsuba":
                arr = np.array(mi.render(scene, spp=a.spp, seed=seed), dtype=np.float32)[:, :, :3]
                secs = time.perf_counter() - t0
                mi.Bitmap(np.ascontiguousarray(arr)).write(img)
            else:
                subprocess.run([RT, "--scene", PBRT, "--width", str(a.width), "--height", str(a.height),
                                "--integrator", "path", "--spp", str(a.spp), "--seed", str(seed), "-q", "-o", img],
                               check=True)
                secs = time.perf_counter() - t0
            rel, lum = compare(img, ref, a.max_luminance)
            rows[who].append((rel, lum, secs))
            print(f"{who:8s} seed {seed:3d}  {secs:6.1f} s  relMSE {rel:.5f}  lum {lum:.4f}", flush=True)
    for who, r in rows.items():
        if r:
            r = np.array(r)
            sd = f"{r[:, 0].std(ddof=1):.5f}" if len(r) > 1 else "-"
            print(f"{who:8s} {len(r)} seeds: relMSE mean {r[:, 0].mean():.5f} (sd {sd}, "
                  f"median {np.median(r[:, 0]):.5f}, {r[:, 0].min():.5f} to {r[:, 0].max():.5f}), "
                  f"lum {r[:, 1].mean():.4f}, {r[:, 2].mean():.1f} s a render")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    r = sub.add_parser("render", help="one Mitsuba render to OUT")
    r.add_argument("out")
    r.add_argument("--passes", type=int, default=1,
                   help="average this many renders of --spp each (seeds seed * passes + i): a converged "
                        "image without one huge wavefront")
    r.add_argument("--seed", type=int, default=0)
    s = sub.add_parser("seeds", help="Mitsuba (and with --ours our path tracer) over seeds, against the reference")
    s.add_argument("--seeds", default="0-7", help="first-last [0-7]")
    s.add_argument("--ours", action="store_true", help="our path tracer too (target/release/raytracer)")
    s.add_argument("--max-luminance", default="4")
    for p in (r, s):
        p.add_argument("--spp", type=int, default=256)
        p.add_argument("--width", type=int, default=320)
        p.add_argument("--height", type=int, default=180)
    a = ap.parse_args()
    import time

    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    if a.what == "seeds":
        return seeds(a, mi)
    mesh_dir = os.path.join(ROOT, "target", "veach-mis", "meshes")
    scene = mi.load_dict(scene_dict(PBRT, a.width, a.height, a.spp, mesh_dir))
    acc = None
    t0 = time.perf_counter()
    for i in range(a.passes):
        img = np.array(mi.render(scene, spp=a.spp, seed=a.seed * a.passes + i), dtype=np.float64)[:, :, :3]
        acc = img if acc is None else acc + img
    secs = time.perf_counter() - t0
    mi.Bitmap(np.ascontiguousarray((acc / a.passes).astype(np.float32))).write(a.out)
    print(f"{a.out}: {a.passes} x {a.spp} spp, {secs:.1f} s (kernel compilation included)", file=sys.stderr)


if __name__ == "__main__":
    main()
