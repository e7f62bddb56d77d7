#!/usr/bin/env python3
"""Our path tracer's efficiency (relative MSE x seconds) under different
samplers and Russian roulette depths, measured side by side (issue 15).

    bench/sobol-roulette.py [CONFIG ...]

Each CONFIG is LABEL=BINARY[:ARG,ARG...], e.g.
    independent=target/release/raytracer:--sampler,independent
    sobol=target/release/raytracer:--sampler,sobol
and defaults to those two. Several binaries (builds of the renderer that
differ in one constant, such as ROULETTE_DEPTH in src/integrator/path.rs)
compare the same way; an argument of the form ENV:NAME=VALUE sets an
environment variable for that binary's runs instead.

Environment:
CASES    scenes [cornell cornell-box]: the built-in room, and ../shared/bitterli/
         cornell-box/scene-v4.pbrt with a tent filter (as bench/vs-mitsuba.sh)
SIZE     image width and height [256]
SPP      samples per pixel [16 64 256]
REPEATS  rounds [2]; each round runs every configuration at every sample
         count, the order of the configurations alternating from run to run
REF_SPP  samples per pixel of each of the two references [2048 for cornell,
         1024 for cornell-box], rendered once (independent sampler, seeds 1000
         and 1001) and cached in target/sobol-bench/refs/
CSV_OUT  the rows [target/sobol-bench/results.csv]

Error: with A and B the two references, e(X) = (r(X, A) + r(X, B)) / 2 -
r(A, B) / 2, r being `raytracer compare`'s relative MSE (pixels brighter than
--max-luminance in the reference left out: 10 for cornell, 4 for cornell-box),
so the references' own noise is taken out. Time: the whole process, wall
clock and CPU (user + system of all threads). K = e x seconds.
"""
import csv
import os
import resource
import subprocess
import sys
import time

os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
RT = os.path.join("target", "release", "raytracer")
WORK = os.path.join("target", "sobol-bench")
REFS = os.path.join(WORK, "refs")
IMGS = os.path.join(WORK, "images")
BITTERLI = os.path.join("..", "shared", "bitterli", "cornell-box", "scene-v4.pbrt")

CASES = os.environ.get("CASES", "cornell cornell-box").split()
SIZE = os.environ.get("SIZE", "256")
SPP = os.environ.get("SPP", "16 64 256").split()
REPEATS = int(os.environ.get("REPEATS", "2"))
CSV_OUT = os.environ.get("CSV_OUT", os.path.join(WORK, "results.csv"))

SCENES = {
    "cornell": (["--scene", "cornell"], "10", 2048),
    "cornell-box": (["--scene", BITTERLI, "--filter", "tent"], "4", 1024),
}


def parse_config(text):
    label, _, rest = text.partition("=")
    binary, _, args = rest.partition(":")
    env, argv = {}, []
    for a in filter(None, args.split(",")):
        if a.startswith("ENV:"):
            k, _, v = a[4:].partition("=")
            env[k] = v
        else:
            argv.append(a)
    return label, binary, argv, env


def cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(binary, args, env, out):
    c0, t0 = cpu(), time.perf_counter()
    subprocess.run([binary, *args, "-q", "-o", out], check=True, env={**os.environ, **env})
    return time.perf_counter() - t0, cpu() - c0


def rel_mse(img, ref, max_lum):
    out = subprocess.run([RT, "compare", img, ref, "--max-luminance", max_lum],
                         check=True, capture_output=True, text=True).stdout.split()
    return float(dict(zip(out[::2], out[1::2]))["rel_mse"])


def main():
    configs = [parse_config(c) for c in (sys.argv[1:] or [
        f"independent={RT}:--sampler,independent", f"sobol={RT}:--sampler,sobol"])]
    os.makedirs(REFS, exist_ok=True)
    os.makedirs(IMGS, exist_ok=True)
    rows = []
    for case in CASES:
        scene_args, max_lum, default_ref_spp = SCENES[case]
        ref_spp = os.environ.get("REF_SPP", str(default_ref_spp))
        common = scene_args + ["--width", SIZE, "--height", SIZE, "--integrator", "path"]
        refs = []
        for seed in ("1000", "1001"):
            ref = os.path.join(REFS, f"{case}-{SIZE}-ref-{seed}.exr")
            if not os.path.exists(ref):
                print(f"{case}: rendering reference {ref} ({ref_spp} spp)", flush=True)
                run(RT, common + ["--spp", ref_spp, "--seed", seed, "--sampler", "independent"], {}, ref + ".tmp.exr")
                os.replace(ref + ".tmp.exr", ref)
            refs.append(ref)
        ref_noise = rel_mse(refs[1], refs[0], max_lum)
        print(f"{case}: relMSE between the references {ref_noise:.6f}", flush=True)
        n = 0
        for rep in range(REPEATS):
            for spp in SPP:
                order = configs if n % 2 == 0 else configs[::-1]
                n += 1
                for label, binary, argv, env in order:
                    img = os.path.join(IMGS, f"{case}-{label}-{spp}.exr")
                    wall, cpu_s = run(binary, common + ["--spp", spp, "--seed", str(rep)] + argv, env, img)
                    e = (rel_mse(img, refs[0], max_lum) + rel_mse(img, refs[1], max_lum)) / 2 - ref_noise / 2
                    rows.append(dict(case=case, config=label, spp=spp, round=rep, seconds=f"{wall:.3f}",
                                     cpu_seconds=f"{cpu_s:.3f}", rel_mse=f"{e:.6g}", K=f"{e * wall:.6g}",
                                     K_cpu=f"{e * cpu_s:.6g}"))
                    print(f"  {case:12s} {label:14s} {spp:>4s} spp round {rep}: {wall:7.2f} s (cpu {cpu_s:7.2f})"
                          f"  relMSE {e:.6f}  K {e * wall:.6f}  K_cpu {e * cpu_s:.6f}", flush=True)
    with open(CSV_OUT, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    # Means over the rounds, and each configuration's K over the first one's.
    print()
    print("| case | config | spp | seconds | CPU s | rel. MSE | K | K_cpu | K / K_first | K_cpu / K_cpu,first |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for case in CASES:
        for spp in SPP:
            first = None
            for label, *_ in configs:
                sel = [r for r in rows if r["case"] == case and r["spp"] == spp and r["config"] == label]
                mean = {k: sum(float(r[k]) for r in sel) / len(sel)
                        for k in ("seconds", "cpu_seconds", "rel_mse", "K", "K_cpu")}
                first = first or mean
                print(f"| {case} | {label} | {spp} | {mean['seconds']:.2f} | {mean['cpu_seconds']:.2f} "
                      f"| {mean['rel_mse']:.5f} | {mean['K']:.5f} | {mean['K_cpu']:.5f} "
                      f"| {mean['K'] / first['K']:.2f} | {mean['K_cpu'] / first['K_cpu']:.2f} |")


if __name__ == "__main__":
    main()
