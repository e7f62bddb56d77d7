#!/usr/bin/env python3
"""The measuring part of bench/vs-mitsuba.sh (run that script: it installs
Mitsuba, builds the renderer and calls this with the virtual environment's
python). Settings come from environment variables, documented in the script.

For each case (scene, size):
1. a converged reference from each renderer, cached under target/vs-mitsuba/refs;
   their mean luminances must agree within 0.5% (reported, and the run goes on
   with a warning if they do not);
2. interleaved: after one warm-up render of Mitsuba's, its path tracer and
   ours at each sample count (the two in turn at one count, the order
   alternating from count to count), then our photon integrators;
3. relative MSE against the references, the reference noise taken out:
   with A our reference and B Mitsuba's, e(X) = (r(X, A) + r(X, B)) / 2 - r(A, B) / 2
   (E[r(X, A)] = e(X) + v(A), E[r(A, B)] = v(A) + v(B), provided A and B
   converge to the same image, which step 1 checks);
4. K = e x seconds, and each row's K over Mitsuba's K at MITSUBA_K_SPP samples.
"""
import csv
import os
import resource
import subprocess
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")

ROOT = os.getcwd()
RT = os.path.join("target", "release", "raytracer")
WORK = os.path.join("target", "vs-mitsuba")
REFS = os.path.join(WORK, "refs")
IMGS = os.path.join(WORK, "images")
BITTERLI = os.path.join("..", "shared", "bitterli", "cornell-box")


def env_list(name, default):
    return os.environ.get(name, default).split()


CASES = env_list("CASES", "cornell:256 cornell:512 cornell-box:256")
SPP = {"256": env_list("SPP_256", "16 64 256"), "512": env_list("SPP_512", "16 64 256")}
# cornell's references are rendered at 512 x 512 and box-averaged here
# for 256 x 256 (exact with the box filter: 512 spp there are 2048 at 256);
# cornell-box's (tent filter) at the case's own size.
REF_SPP_CORNELL = int(os.environ.get("REF_SPP_CORNELL", "512"))
REF_SPP_BOX = int(os.environ.get("REF_SPP_BOX", "1024"))
MITSUBA_K_SPP = int(os.environ.get("MITSUBA_K_SPP", "256"))
SKIP_PHOTON = os.environ.get("SKIP_PHOTON", "0") == "1"
CHECK_ONLY = os.environ.get("CHECK_ONLY", "0") == "1"
# A diagnostic: Mitsuba's path tracer with Russian roulette from this depth
# (its default is 5; ours starts at 2). Empty: the scene file's integrator.
MITSUBA_RR_DEPTH = os.environ.get("MITSUBA_RR_DEPTH", "")
# Variants of our path tracer, each a row at every sample count: extra
# options, variants separated by ";" (an empty variant: the scene's settings).
OURS_PATH_VARIANTS = [v.split() for v in os.environ.get("OURS_PATH_VARIANTS", "").split(";")]
CSV_OUT = os.environ.get("CSV_OUT", os.path.join("docs", "vs-mitsuba.csv"))
PNG_OUT = os.environ.get("PNG_OUT", os.path.join("docs", "vs-mitsuba.png"))

# Our photon integrators at a few settings (seconds grow down the list), per case.
P_FAST = ("photon", "200k ph, r 0.1, ssaa 2", ["--photons", "200000", "--gather-radius", "0.1", "--ssaa", "2"])
P_DEFAULT = ("photon", "default: 1M ph, r 0.06, ssaa 4", [])
P_1M = ("photon", "1M ph, r 0.06, precomputed, ssaa 4",
        ["--photons", "1000000", "--gather-radius", "0.06", "--precompute-irradiance", "--ssaa", "4"])
P_2M = ("photon", "2M ph, r 0.05, ssaa 4", ["--photons", "2000000", "--gather-radius", "0.05", "--ssaa", "4"])
S_16 = ("sppm", "16 passes x 100k ph", ["--passes", "16", "--photons", "100000"])
S_64 = ("sppm", "64 passes x 100k ph", ["--passes", "64", "--photons", "100000"])
PHOTON = {
    "cornell-256": [P_FAST, P_DEFAULT, P_2M, S_16, S_64],
    "cornell-512": [P_FAST, P_DEFAULT, P_2M, S_16],
    "cornell-box-256": [P_FAST, P_1M, S_16, S_64],
}
PHOTON["cornell-box-box-256"] = PHOTON["cornell-box-256"]


def case_setup(scene, size):
    """Returns (our scene arguments, Mitsuba scene file, --max-luminance, reference size, reference spp)."""
    if scene == "cornell":
        sys.path.insert(0, os.path.join(ROOT, "bench"))
        import mitsuba_export

        xml = mitsuba_export.export(os.path.join("scenes", "cornell.toml"), os.path.join(WORK, "cornell"))
        # The light (radiance 111) is left out of the figures; the walls stay below 10.
        return ["--scene", "cornell"], xml, "10", 512 if 512 % int(size) == 0 else int(size), REF_SPP_CORNELL
    if scene == "cornell-box":
        # The pbrt file asks for a gaussian filter, its Mitsuba version for a
        # tent of radius 1: ours renders with --filter tent so that both
        # converge to the same pixels.
        # The pbrt file names no light sampler, so ours is pbrt-v4's
        # default, the light tree; a tree of this one quad light has nothing
        # to weigh and chooses by power, as Mitsuba chooses its emitter.
        return (["--scene", os.path.join(BITTERLI, "scene-v4.pbrt"), "--filter", "tent"],
                os.path.join(BITTERLI, "scene-mitsuba3.xml"), "4", int(size), REF_SPP_BOX)
    if scene == "cornell-box-box":
        # The same scene with a box filter in both renderers: Mitsuba splats
        # each sample over the pixels its tent covers, we importance-sample
        # the filter (one pixel a sample), which at equal samples has more
        # noise per pixel; the box filter takes that difference out.
        xml = os.path.join(WORK, "cornell-box-box", "scene.xml")
        os.makedirs(os.path.dirname(xml), exist_ok=True)
        text = open(os.path.join(BITTERLI, "scene-mitsuba3.xml")).read()
        assert '<rfilter type="tent" />' in text
        with open(xml, "w") as f:
            f.write(text.replace('<rfilter type="tent" />', '<rfilter type="box" />'))
        return (["--scene", os.path.join(BITTERLI, "scene-v4.pbrt"), "--filter", "box"],
                xml, "4", int(size),
                REF_SPP_BOX)
    raise SystemExit(f"unknown case scene {scene!r}")


def downsampled(src, size):
    """src box-averaged to size x size (cached beside it): `compare` wants equal sizes."""
    dst = src.replace(".exr", f"-to{size}.exr")
    if not os.path.exists(dst) or os.path.getmtime(dst) < os.path.getmtime(src):
        a = np.array(mi.Bitmap(src), dtype=np.float32)[:, :, :3]
        f = a.shape[0] // size
        assert a.shape[0] == f * size and a.shape[1] == f * size, (src, a.shape, size)
        b = a.reshape(size, f, size, f, 3).mean(axis=(1, 3))
        mi.Bitmap(np.ascontiguousarray(b)).write(dst)
    return dst


def downsampled_shipped(size):
    """The shipped reference (512 x 512, half floats) as float RGB at size x size."""
    src = os.path.join(REFS, "cornell-box-shipped-reference.exr")
    if not os.path.exists(src):
        a = np.array(mi.Bitmap(os.path.join(BITTERLI, "reference.exr")), dtype=np.float32)[:, :, :3]
        mi.Bitmap(np.ascontiguousarray(a)).write(src)
    return src if size == 512 else downsampled(src, size)


def compare(img, ref, max_lum):
    out = subprocess.run([RT, "compare", img, ref, "--max-luminance", max_lum],
                         check=True, capture_output=True, text=True).stdout.split()
    vals = dict(zip(out[::2], out[1::2]))
    return float(vals["rel_mse"]), float(vals["luminance_ratio"])


def compare_all(img, ref, max_lum):
    out = subprocess.run([RT, "compare", img, ref], check=True, capture_output=True, text=True).stdout.split()
    return float(dict(zip(out[::2], out[1::2]))["luminance_ratio"])


class Mitsuba:
    def __init__(self, xml, size, max_depth=-1):
        self.scene = mi.load_file(xml, resx=size, resy=size, spp=16)
        self.integrator = self.scene.integrator()
        if MITSUBA_RR_DEPTH:
            self.integrator = mi.load_dict({"type": "path", "max_depth": max_depth, "rr_depth": int(MITSUBA_RR_DEPTH)})
        dr.set_flag(dr.JitFlag.KernelHistory, True)

    def render(self, spp, seed, path):
        global LAST_CPU
        c0 = cpu(resource.RUSAGE_SELF)
        t0 = time.perf_counter()
        img = mi.render(self.scene, integrator=self.integrator, spp=spp, seed=seed)
        arr = np.array(img)  # waits for the render
        secs = time.perf_counter() - t0
        LAST_CPU = cpu(resource.RUSAGE_SELF) - c0
        hist = dr.kernel_history()
        jit = sum((k.get("codegen_time") or 0) + (k.get("backend_time") or 0)
                  for k in hist if k.get("cache_hit") == 0) / 1000.0
        mi.Bitmap(np.ascontiguousarray(arr[:, :, :3])).write(path)
        return secs, jit

    def warm_up(self, spp, path):
        """A first render of the case (another seed), which compiles the kernels.
        Dr.Jit's kernel cache does not depend on the sample count: the timed
        renders after it compile nothing (their kernel history says so; a
        render that did compile is timed again)."""
        return self.render(spp, 999999, path)[0]

    def timed(self, spp, seed, path):
        secs, jit = self.render(spp, seed, path)
        if jit > 0.01:
            print(f"    (mitsuba compiled {jit:.2f} s of kernels during a timed render: timing it again)", flush=True)
            secs, jit = self.render(spp, seed, path)
        return secs, jit


LAST_CPU = 0.0  # CPU seconds (user + system, all threads) of the last timed render


def cpu(who):
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def ours(args, path):
    global LAST_CPU
    c0 = cpu(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([RT, *args, "-q", "-o", path], check=True)
    secs = time.perf_counter() - t0
    LAST_CPU = cpu(resource.RUSAGE_CHILDREN) - c0
    return secs


def main():
    os.makedirs(REFS, exist_ok=True)
    os.makedirs(IMGS, exist_ok=True)
    rows = []
    summary = []
    for case in CASES:
        scene, size = case.split(":")
        n = int(size)
        our_args, xml, max_lum, ref_size, ref_spp = case_setup(scene, size)
        common = our_args + ["--width", size, "--height", size]
        name = f"{scene}-{size}"

        # 1. References (cached).
        rs = str(ref_size)
        ref_a = os.path.join(REFS, f"{scene}-{rs}-ours-path-{ref_spp}spp.exr")
        ref_b = os.path.join(REFS, f"{scene}-{rs}-mitsuba-path-{ref_spp}spp.exr")
        if not os.path.exists(ref_a):
            print(f"{scene}-{rs}: rendering our reference once ({ref_spp} spp)", flush=True)
            s = ours(our_args + ["--width", rs, "--height", rs, "--integrator", "path", "--spp", str(ref_spp),
                                 "--seed", "1000"], ref_a + ".tmp.exr")
            os.replace(ref_a + ".tmp.exr", ref_a)
            print(f"  {s:.1f} s", flush=True)
        if not os.path.exists(ref_b):
            print(f"{scene}-{rs}: rendering Mitsuba's reference once ({ref_spp} spp)", flush=True)
            s, _ = Mitsuba(xml, ref_size).render(ref_spp, 1000, ref_b + ".tmp.exr")
            os.replace(ref_b + ".tmp.exr", ref_b)
            print(f"  {s:.1f} s", flush=True)
        if ref_size != n:
            ref_a, ref_b = downsampled(ref_a, n), downsampled(ref_b, n)
        mts = Mitsuba(xml, n, -1 if scene == "cornell" else 65)
        ref_noise, lum = compare(ref_b, ref_a, max_lum)
        lum_all = compare_all(ref_b, ref_a, max_lum)
        ok = abs(lum - 1) <= 0.005 and abs(lum_all - 1) <= 0.005
        print(f"{name}: Mitsuba's reference / ours: mean luminance {lum:.4f} (light left out, "
              f"--max-luminance {max_lum}), {lum_all:.4f} (all pixels); relMSE between them {ref_noise:.6f}"
              + ("" if ok else "  ** NOT within 0.5% **"), flush=True)
        extra = ""
        if scene.startswith("cornell-box"):
            tungsten = downsampled_shipped(n)
            ra, la = compare(ref_a, tungsten, max_lum)
            rb, lb = compare(ref_b, tungsten, max_lum)
            extra = f"; against the shipped reference: ours {la:.4f} (relMSE {ra:.5f}), Mitsuba {lb:.4f} (relMSE {rb:.5f})"
            print(f"  {extra[2:]}", flush=True)
        # The framing: Mitsuba's reference mirrored left-right and flipped
        # upside down must be far from ours, the reference itself close.
        arr = np.array(mi.Bitmap(ref_b), dtype=np.float32)[:, :, :3]
        framing = []
        for what, a in (("mirrored", arr[:, ::-1]), ("upside down", arr[::-1])):
            tmp = os.path.join(REFS, f"{name}-mitsuba-{what.replace(' ', '-')}.exr")
            mi.Bitmap(np.ascontiguousarray(a)).write(tmp)
            framing.append(f"Mitsuba's reference {what} against ours: relMSE {compare(tmp, ref_a, max_lum)[0]:.4f}")
        print(f"  framing: relMSE between the references {ref_noise:.6f}; " + "; ".join(framing), flush=True)
        extra += "; " + "; ".join(framing)
        summary.append((name, lum, lum_all, ref_noise, ok, extra))
        if CHECK_ONLY:
            continue

        def record(renderer, integrator, settings, spp, secs, img, cold="", jit=""):
            cpu_secs = LAST_CPU
            ra, _ = compare(img, ref_a, max_lum)
            rb, lb = compare(img, ref_b, max_lum)
            e = (ra + rb) / 2 - ref_noise / 2
            row = dict(case=name, renderer=renderer, integrator=integrator, settings=settings, spp=spp,
                       seconds=f"{secs:.3f}", cpu_seconds=f"{cpu_secs:.3f}", warmup_seconds=cold, jit_seconds=jit, rel_mse=f"{e:.6g}",
                       rel_mse_vs_ours_ref=f"{ra:.6g}", rel_mse_vs_mitsuba_ref=f"{rb:.6g}",
                       luminance_ratio=f"{lb:.4f}", K=f"{e * secs:.6g}", K_cpu=f"{e * cpu_secs:.6g}")
            rows.append(row)
            print(f"  {renderer:8s} {integrator:7s} {settings:34s} {secs:8.2f} s (cpu {cpu_secs:7.2f} s)"
                  f"  relMSE {e:.6f}  K {e * secs:.6f}"
                  + (f"  (jit in the timed render {jit} s)" if jit else ""), flush=True)

        # 2. Interleaved runs, after Mitsuba's warm-up render.
        spps = SPP.get(size, SPP["256"])
        first = int(spps[0])
        cold = mts.warm_up(first, os.path.join(IMGS, f"{name}-mitsuba-warmup.exr"))
        print(f"  mitsuba warm-up render ({first} spp, kernels compiled): {cold:.2f} s", flush=True)
        for i, spp_s in enumerate(spps):
            spp = int(spp_s)
            pair = ["mitsuba", "ours"] if i % 2 == 0 else ["ours", "mitsuba"]
            for who in pair:
                if who == "mitsuba":
                    img = os.path.join(IMGS, f"{name}-mitsuba-path-{spp}.exr")
                    warm, jit = mts.timed(spp, spp, img)
                    record("mitsuba", "path", f"{spp} spp", spp, warm, img, f"{cold:.3f}", f"{jit:.3f}")
                else:
                    for k, variant in enumerate(OURS_PATH_VARIANTS):
                        img = os.path.join(IMGS, f"{name}-ours-path-{spp}-{k}.exr")
                        secs = ours(common + ["--integrator", "path", "--spp", str(spp)] + variant, img)
                        label = " ".join([f"{spp} spp"] + variant)
                        record("ours", "path", label, spp, secs, img)
        if not SKIP_PHOTON:
            for j, (integ, label, extra_args) in enumerate(PHOTON.get(name, PHOTON.get(f"{scene}-256", []))):
                img = os.path.join(IMGS, f"{name}-ours-{integ}-{j}.exr")
                secs = ours(common + ["--integrator", integ] + extra_args, img)
                record("ours", integ, label, "", secs, img)
        del mts

    if CHECK_ONLY:
        for name, lum, lum_all, noise, ok, extra in summary:
            print(f"reference check {name}: Mitsuba / ours mean luminance {lum:.4f} (light out), {lum_all:.4f} (all);"
                  f" relMSE between references {noise:.6f}; {'OK' if ok else 'NOT within 0.5%'}{extra}")
        return
    # 3. K ratios.
    fields = list(rows[0].keys()) + ["K_over_mitsuba", "K_cpu_over_mitsuba"]
    for name in dict.fromkeys(r["case"] for r in rows):
        m = [r for r in rows if r["case"] == name and r["renderer"] == "mitsuba" and r["spp"] == MITSUBA_K_SPP]
        for r in rows:
            if r["case"] == name:
                for k in ("K", "K_cpu"):
                    ok = m and float(m[0][k]) > 0
                    r[f"{k}_over_mitsuba"] = f"{float(r[k]) / float(m[0][k]):.3f}" if ok else ""
    os.makedirs(os.path.dirname(CSV_OUT) or ".", exist_ok=True)
    with open(CSV_OUT, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)

    print()
    print(f"K = relMSE x seconds; ratio against Mitsuba's K at {MITSUBA_K_SPP} spp in the same case")
    print("(K_cpu: the same with CPU seconds, user + system of all threads)")
    print("| case | renderer | integrator | settings | seconds | CPU s | rel. MSE | K | K / K_mitsuba "
          "| K_cpu / K_cpu,mitsuba |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['case']} | {r['renderer']} | {r['integrator']} | {r['settings']} | {float(r['seconds']):.2f} "
              f"| {float(r['cpu_seconds']):.2f} | {float(r['rel_mse']):.5f} | {float(r['K']):.5f} "
              f"| {r['K_over_mitsuba']} | {r['K_cpu_over_mitsuba']} |")
    print()
    print("Same sample count, path tracers: K_ours / K_mitsuba")
    for name in dict.fromkeys(r["case"] for r in rows):
        parts = []
        for r in rows:
            if r["case"] == name and r["renderer"] == "mitsuba":
                o = [x for x in rows if x["case"] == name and x["renderer"] == "ours"
                     and x["integrator"] == "path" and x["spp"] == r["spp"]]
                if o and float(r["K"]) > 0:
                    parts.append(f"{r['spp']} spp: {float(o[0]['K']) / float(r['K']):.2f}"
                                 f" (time {float(o[0]['seconds']) / float(r['seconds']):.2f}x,"
                                 f" CPU {float(o[0]['cpu_seconds']) / float(r['cpu_seconds']):.2f}x,"
                                 f" error {float(o[0]['rel_mse']) / float(r['rel_mse']):.2f}x)")
        print(f"  {name}: " + "; ".join(parts))
    print()
    for name, lum, lum_all, noise, ok, extra in summary:
        print(f"reference check {name}: Mitsuba / ours mean luminance {lum:.4f} (light out), {lum_all:.4f} (all);"
              f" relMSE between references {noise:.6f}; {'OK' if ok else 'NOT within 0.5%'}{extra}")
    print(f"CSV: {CSV_OUT}")
    plot(rows)


def plot(rows):
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    style = {("mitsuba", "path"): ("tab:red", "D", "Mitsuba 3 path (llvm, warm)"),
             ("ours", "path"): ("tab:blue", "o", "ours: path"),
             ("ours", "photon"): ("tab:orange", "s", "ours: photon"),
             ("ours", "sppm"): ("tab:green", "^", "ours: sppm")}
    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(1, len(cases), figsize=(5 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        for (who, integ), (colour, marker, label) in style.items():
            pts = sorted((r for r in rows if r["case"] == case and r["renderer"] == who
                          and r["integrator"] == integ and float(r["rel_mse"]) > 0),
                         key=lambda r: float(r["seconds"]))
            if pts:
                ax.plot([float(r["seconds"]) for r in pts], [float(r["rel_mse"]) for r in pts],
                        color=colour, marker=marker, label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        mk = [float(r["K"]) for r in rows if r["case"] == case and r["renderer"] == "mitsuba"
              and int(r["spp"] or 0) == MITSUBA_K_SPP]
        if mk:
            xlim, ylim = ax.get_xlim(), ax.get_ylim()
            xs = np.geomspace(*xlim, 20)
            ax.plot(xs, mk[0] / xs, color="tab:red", linestyle=":", alpha=0.6,
                    label=f"Mitsuba's K at {MITSUBA_K_SPP} spp")
            ax.plot(xs, 0.25 * mk[0] / xs, color="grey", linestyle=":", alpha=0.6, label="a quarter of it")
            ax.set_xlim(xlim)
            ax.set_ylim(ylim)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_title(case)
        ax.set_xlabel("wall time (s)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("relative MSE (reference noise taken out)")
    fig.tight_layout()
    fig.savefig(PNG_OUT, dpi=110)
    print(f"plot: {PNG_OUT}")


if __name__ == "__main__":
    if os.environ.get("PLOT_ONLY") == "1":  # redraw PNG_OUT from CSV_OUT
        plot(list(csv.DictReader(open(CSV_OUT))))
    else:
        main()
