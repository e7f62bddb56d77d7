#!/usr/bin/env python3
"""The measuring part of bench/bitterli.sh (run that script; it builds the
renderer and calls this with a virtual environment's python that has numpy,
matplotlib and OpenEXR). Settings come from environment variables,
documented in the script.

For each scene of ../shared/bitterli/:
1. whether it loads (`raytracer info`); a refused scene is reported with the
   renderer's message and the bench goes on with the next;
2. the path tracer at PATH_SPP samples a pixel: its wall time T is the budget;
   then the same with its diffuse bounces guided by GUIDE_PHOTONS caustic
   photons (`--guide-photons`), at the same samples a pixel (its own time);
3. our photon integrators and the bidirectional path tracer at the same wall
   time: `photon` with PHOTONS photons (precomputed irradiance) and the N x N
   camera samples that fill T, `sppm` with SPPM_PHOTONS photons a pass and the
   passes that fill T, `bdpt` with the samples a pixel that fill T, each sized
   from short calibration renders (time = fixed part + per-sample or per-pass
   part);
4. `raytracer compare --max-luminance 4` against the reference (box-averaged
   to the render's size here: `compare` takes equal sizes), and the same figure
   with the light's one-pixel border left out too (computed here with
   compare's formula);
5. a picture per scene, docs/bitterli-SCENE.png: ours (the integrator with the
   lowest error) | reference | relative error (`compare --diff`);
6. the table, between marker comments in BENCHMARKS.md.
"""
import os
import subprocess
import sys
import time

import numpy as np
import OpenEXR

RT = os.path.join("target", "release", "raytracer")
BASE = os.path.join("..", "shared", "bitterli")
WORK = os.path.join("target", "bitterli")
SIZES = {"cornell-box": (256, 256), "water-caustic": (256, 256), "veach-mis": (320, 180)}
SCENES = os.environ.get("SCENES", "cornell-box water-caustic veach-mis").split()
PATH_SPP = int(os.environ.get("PATH_SPP", "256"))
PHOTONS = os.environ.get("PHOTONS", "1000000")
SPPM_PHOTONS = os.environ.get("SPPM_PHOTONS", "200000")
GUIDE_PHOTONS = os.environ.get("GUIDE_PHOTONS", "100000")
MAX_LUM = os.environ.get("MAX_LUMINANCE", "4")
# A pixel filter for every render instead of the scene file's (box, tent, gaussian).
FILTER = os.environ.get("FILTER", "")
WRITE_DOCS = os.environ.get("WRITE_DOCS", "1") == "1"
START = "<!-- bitterli-bench:start (bench/bitterli.sh replaces this part) -->"
END = "<!-- bitterli-bench:end -->"
# The targets for the path tracer at 256 samples a pixel.
TARGETS = {"cornell-box": 0.001, "veach-mis": 0.016}


def read_exr(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.asarray(ch["RGB"].pixels, dtype=np.float32)[:, :, :3]
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in "RGB"], axis=-1)


def write_exr(path, a):
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(a, dtype=np.float32)}) as f:
        f.write(path)


def reference(scene, w, h):
    """The shipped reference box-averaged to w x h (cached in target/bitterli)."""
    src = os.path.join(BASE, scene, "reference.exr")
    dst = os.path.join(WORK, f"{scene}-reference-{w}x{h}.exr")
    if not os.path.exists(dst):
        a = read_exr(src)
        f = a.shape[1] // w
        assert a.shape[0] == f * h and a.shape[1] == f * w, (scene, a.shape, w, h)
        write_exr(dst, a.reshape(h, f, w, f, 3).mean(axis=(1, 3)))
    return dst


def luminance(a):
    return 0.2126 * a[..., 0] + 0.7152 * a[..., 1] + 0.0722 * a[..., 2]


def rel_mse_border_out(img, ref, max_lum):
    """compare's relative MSE (mean over channels of (x - r)^2 / (r^2 + 0.01))
    over the pixels neither brighter than max_lum in the reference nor next to one."""
    x, r = read_exr(img), read_exr(ref)
    bright = luminance(r) > max_lum
    grown = bright.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            grown |= np.roll(np.roll(bright, dy, axis=0), dx, axis=1)
    keep = ~grown
    e = (x - r) ** 2 / (r * r + 0.01)
    return float(e[keep].mean()), float(luminance(x)[keep].mean() / luminance(r)[keep].mean())


def compare(img, ref, diff=None):
    cmd = [RT, "compare", img, ref, "--max-luminance", MAX_LUM]
    if diff:
        cmd += ["--diff", diff]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.split()
    v = dict(zip(out[::2], out[1::2]))
    return float(v["rel_mse"]), float(v["luminance_ratio"])


def render(args, out):
    t0 = time.perf_counter()
    p = subprocess.run([RT, *args, "-q", "-o", out], capture_output=True, text=True)
    secs = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(p.stderr.strip() or f"exit status {p.returncode}")
    return secs


def tonemap(a):
    a = np.clip(a, 0, None)
    srgb = np.where(a <= 0.0031308, 12.92 * a, 1.055 * np.power(a, 1 / 2.4) - 0.055)
    return np.clip(srgb, 0, 1)


def picture(scene, best, ref, diff_png, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    integ, settings, img = best
    panels = [(tonemap(read_exr(img)), f"ours: {integ}, {settings}"),
              (tonemap(read_exr(ref)), "reference (box-averaged)"),
              (plt.imread(diff_png), "relative error (red: 0.5)")]
    h, w = panels[0][0].shape[:2]
    fig, axes = plt.subplots(1, 3, figsize=(3 * w / 80, h / 80 + 0.5))
    for ax, (im, title) in zip(axes, panels):
        ax.imshow(im, interpolation="nearest")
        ax.set_title(title, fontsize=7)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main():
    os.makedirs(WORK, exist_ok=True)
    rows = []
    notes = []
    for scene in SCENES:
        w, h = SIZES[scene]
        pbrt = os.path.join(BASE, scene, "scene-v4.pbrt")
        common = ["--scene", pbrt, "--width", str(w), "--height", str(h)] + (["--filter", FILTER] if FILTER else [])
        info = subprocess.run([RT, "info", "--scene", pbrt], capture_output=True, text=True)
        if info.returncode != 0:
            msg = (info.stderr.strip() or info.stdout.strip()).splitlines()[0]
            msg = msg.replace(os.path.join(BASE, scene) + os.sep, "")
            if msg.count("; ") > 0:  # one line per place: the first, and how many more
                first, rest = msg.split("; ", 1)
                msg = f"{first} and {rest.count('; ') + 1} more places"
            print(f"{scene}: refused (exit {info.returncode}): {msg}", flush=True)
            rows.append(dict(scene=scene, integrator="-", settings="refused", seconds=None, note=msg))
            continue
        ref = reference(scene, w, h)
        print(f"{scene} ({w} x {h})", flush=True)

        def measure(integ, settings, args, tag):
            img = os.path.join(WORK, f"{scene}-{tag}.exr")
            diff = os.path.join(WORK, f"{scene}-{tag}-diff.png")
            secs = render(common + ["--integrator", integ] + args, img)
            rel, lum = compare(img, ref, diff)
            rel_b, lum_b = rel_mse_border_out(img, ref, float(MAX_LUM))
            row = dict(scene=scene, integrator=integ, settings=settings, seconds=secs, rel_mse=rel,
                       luminance_ratio=lum, rel_mse_border=rel_b, lum_border=lum_b, img=img, diff=diff)
            rows.append(row)
            print(f"  {integ:6s} {settings:42s} {secs:7.1f} s  relMSE {rel:.5f}  lum {lum:.4f}"
                  f"  (border out: {rel_b:.5f}, {lum_b:.4f})", flush=True)
            return row

        # The fixed part of a render: start, scene, BVH, writing (a 1-sample path render).
        fixed = render(common + ["--integrator", "path", "--spp", "1"], os.path.join(WORK, "calib.exr"))
        path_row = measure("path", f"{PATH_SPP} spp", ["--spp", str(PATH_SPP)], "path")
        budget = path_row["seconds"]
        guided_row = measure("path", f"{PATH_SPP} spp, guided by {int(GUIDE_PHOTONS) // 1000}k caustic photons",
                             ["--spp", str(PATH_SPP), "--guide-photons", GUIDE_PHOTONS], "path-guided")

        # photon: fixed photon map, N x N camera samples.
        pargs = ["--photons", PHOTONS, "--precompute-irradiance"]
        t1 = render(common + ["--integrator", "photon", "--ssaa", "1"] + pargs, os.path.join(WORK, "calib.exr"))
        t2 = render(common + ["--integrator", "photon", "--ssaa", "2"] + pargs, os.path.join(WORK, "calib.exr"))
        per_spp = max((t2 - t1) / 3, 1e-3)
        n = int(max(1, min(32, np.sqrt(max(budget - (t1 - per_spp), per_spp) / per_spp))))
        measure("photon", f"{int(PHOTONS) // 1000}k photons, precomputed, ssaa {n}", pargs + ["--ssaa", str(n)],
                "photon")

        # sppm: SPPM_PHOTONS a pass, as many passes as fill the budget.
        sargs = ["--photons", SPPM_PHOTONS]
        t4 = render(common + ["--integrator", "sppm", "--passes", "4"] + sargs, os.path.join(WORK, "calib.exr"))
        per_pass = max((t4 - fixed) / 4, 1e-3)
        passes = int(max(1, round((budget - fixed) / per_pass)))
        measure("sppm", f"{passes} passes x {int(SPPM_PHOTONS) // 1000}k photons", sargs + ["--passes", str(passes)],
                "sppm")

        # bdpt: the samples a pixel that fill the budget.
        t8 = render(common + ["--integrator", "bdpt", "--spp", "8"], os.path.join(WORK, "calib.exr"))
        per_sample = max((t8 - fixed) / 8, 1e-3)
        spp = int(max(1, round((budget - fixed) / per_sample)))
        measure("bdpt", f"{spp} spp", ["--spp", str(spp)], "bdpt")

        scene_rows = [r for r in rows if r["scene"] == scene and r.get("rel_mse") is not None]
        best = min(scene_rows, key=lambda r: r["rel_mse"])
        if WRITE_DOCS:
            out = os.path.join("docs", f"bitterli-{scene}.png")
            picture(scene, (best["integrator"], best["settings"], best["img"]), ref, best["diff"], out)
            print(f"  picture: {out}", flush=True)
        if scene in TARGETS:
            t = TARGETS[scene]
            for row, how in [(path_row, ""), (guided_row, f", guided by {int(GUIDE_PHOTONS) // 1000}k photons")]:
                verdict = "met" if row["rel_mse"] <= t else "not met"
                notes.append(f"{scene}: path tracer at {PATH_SPP} spp{how}, {w} x {h}"
                             + (f", filter {FILTER}" if FILTER else "") + f": relative MSE {row['rel_mse']:.5f}"
                             f" (target <= {t}: {verdict}; {row['rel_mse_border']:.5f} with the light's border"
                             f" left out), mean luminance ratio {row['luminance_ratio']:.4f}")

    table = ["| scene | integrator | settings | seconds | rel. MSE | luminance ratio "
             "| rel. MSE, light border out | luminance ratio, border out |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["seconds"] is None:
            table.append(f"| {r['scene']} | | refused: {r['note']} | | | | | |")
        else:
            table.append(f"| {r['scene']} | {r['integrator']} | {r['settings']} | {r['seconds']:.1f} "
                         f"| {r['rel_mse']:.5f} | {r['luminance_ratio']:.4f} | {r['rel_mse_border']:.5f} "
                         f"| {r['lum_border']:.4f} |")
    print()
    print("\n".join(table))
    for n in notes:
        print(n)
    if WRITE_DOCS:
        write_benchmarks(table, notes)


def write_benchmarks(table, notes):
    path = "BENCHMARKS.md"
    text = open(path).read()
    load = os.getloadavg()
    body = [START, "",
            f"Measured by `bench/bitterli.sh` on {time.strftime('%Y-%m-%d', time.gmtime())} "
            f"(load average {load[0]:.1f} at the end; wall times of the whole process, all cores; "
            f"path tracer at {PATH_SPP} spp, the photon integrators and bdpt sized to its time"
            + (f"; filter {FILTER}" if FILTER else "; each file's pixel filter") + "):", ""]
    body += table + [""]
    body += [f"- {n}" for n in notes]
    body += ["", END]
    block = "\n".join(body)
    if START in text and END in text:
        a = text.index(START)
        b = text.index(END) + len(END)
        text = text[:a] + block + text[b:]
    else:
        text = text.rstrip("\n") + "\n\n## Bitterli's scenes: path tracer and photon integrators at equal time\n\n" \
            + "```\nbench/bitterli.sh\n```\n\n" + block + "\n"
    with open(path, "w") as f:
        f.write(text)
    print(f"table written into {path}")


if __name__ == "__main__":
    sys.exit(main())
