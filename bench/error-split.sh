#!/usr/bin/env bash
# How much of the path tracer's error on Bitterli's `cornell-box` is direct
# light (what a better light sampler could lower) and how much is the rest.
# With DEPTH=D, how much is in the first D bounces, which Russian roulette
# (from bounce 5) never touches when D <= 5.
#
#   bench/error-split.sh            # ~3 min on 2 cores
#   SPP="16 64" SEEDS="1 2 3" DEPTH=1 bench/error-split.sh
#
# Renders at 256 x 256 with the tent filter, as bench/vs-mitsuba.sh does: a
# converged image (1024 spp) with all bounces and one with direct light only
# (--max-depth DEPTH, the same estimator cut after DEPTH vertices), then each
# at SPP samples a pixel and seeds SEEDS. The error of each is compare's
# relative MSE (per channel (x - r)^2 / (r^2 + 0.01), over the pixels that
# `--max-luminance 4` keeps), always divided by the full converged image's
# r, so that the two errors add up as the image's do. Prints the direct-light
# error, the full error and their ratio per sample count (means over seeds).
set -euo pipefail
cd "$(dirname "$0")/.."
SPP=${SPP:-16 64}
SEEDS=${SEEDS:-1 2 3}
DEPTH=${DEPTH:-1}
SCENE=${SCENE:-../shared/bitterli/cornell-box/scene-v4.pbrt}
cargo build --release --quiet --bin raytracer
rt=target/release/raytracer
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
common=(--quiet --scene "$SCENE" --width 256 --height 256 --filter tent --integrator path)
"$rt" "${common[@]}" --spp 1024 --seed 1000 -o "$out/ref-full.pfm"
"$rt" "${common[@]}" --spp 1024 --seed 1000 --max-depth "$DEPTH" -o "$out/ref-direct.pfm"
for spp in $SPP; do
    for seed in $SEEDS; do
        "$rt" "${common[@]}" --spp "$spp" --seed "$seed" -o "$out/full-$spp-$seed.pfm"
        "$rt" "${common[@]}" --spp "$spp" --seed "$seed" --max-depth "$DEPTH" -o "$out/direct-$spp-$seed.pfm"
    done
done
python3 - "$out" "$SPP" "$SEEDS" "$DEPTH" <<'EOF'
import array, sys

def pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        a = array.array("f")
        a.frombytes(f.read())
        if (scale < 0) != (sys.byteorder == "little"):
            a.byteswap()
        return w, h, a

out, spps, seeds, depth = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4]
w, h, ref = pfm(f"{out}/ref-full.pfm")
_, _, ref_direct = pfm(f"{out}/ref-direct.pfm")
# compare --max-luminance 4: pixels brighter than 4 and their neighbours out.
lum = [0.2126 * ref[3 * i] + 0.7152 * ref[3 * i + 1] + 0.0722 * ref[3 * i + 2] for i in range(w * h)]
bright = [l > 4.0 for l in lum]
keep = []
for y in range(h):
    for x in range(w):
        near = any(bright[yy * w + xx] for yy in range(max(y - 1, 0), min(y + 2, h))
                   for xx in range(max(x - 1, 0), min(x + 2, w)))
        if not near:
            keep.append(y * w + x)

def rel_mse(img, target):
    s = 0.0
    for i in keep:
        for k in range(3):
            j = 3 * i + k
            d = img[j] - target[j]
            s += d * d / (ref[j] * ref[j] + 0.01)
    return s / (3 * len(keep))

print(f"{'spp':>5} {'depth ' + depth:>13} {'full':>10} {'ratio':>14}")
for spp in spps:
    d = [rel_mse(pfm(f"{out}/direct-{spp}-{s}.pfm")[2], ref_direct) for s in seeds]
    f = [rel_mse(pfm(f"{out}/full-{spp}-{s}.pfm")[2], ref) for s in seeds]
    md, mf = sum(d) / len(d), sum(f) / len(f)
    print(f"{spp:>5} {md:>13.3e} {mf:>10.3e} {md / mf:>14.3f}")
EOF
