#!/usr/bin/env bash
# Subsurface materials, ours against pbrt-v4 itself: Bitterli's cornell-box
# at 128 x 128, 512 spp, under a white light (rgb 12 12 12, so that the
# light's spectrum does not set the two renderers apart), its boxes made
# `subsurface` in several ways. Both render with the volumetric path tracer
# (pbrt-v4's "volpath"; its "path" ignores BSSRDFs). Prints the mean of each
# channel over the front of the tall box and of the short box, ours over
# pbrt-v4's.
#
#   grey        tall box sigma_a 0.5, sigma_s 20; short box reflectance 0.6,
#               mfp 0.05, eta 1.5, roughness 0.1
#   coloured    short box reflectance (0.8 0.6 0.3), mfp (0.05 0.03 0.02)
#   skin        tall box "Skin1" x 20 (sigma_a 0.64 3.4 9.6, sigma_s 14.8
#               17.6 20.2)
#   skin-red    tall box grey with Skin1's red coefficients (0.64, 14.8):
#               its red against skin's red, in each renderer, shows what
#               pbrt-v4's spectral upsampling of the coloured coefficients
#               does to the red channel
#
# Usage: PBRT=path/to/pbrt bench/subsurface.sh
#   (pbrt-v4 built as ../shared/tools/pbrt-v4/ says)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
cargo build --release --quiet
bin=$PWD/target/release/raytracer
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
scene=../shared/bitterli/cornell-box/scene-v4.pbrt
tall_grey='"string type" [ "subsurface" ] "rgb sigma_a" [ 0.5 0.5 0.5 ] "rgb sigma_s" [ 20 20 20 ] "float eta" [ 1.33 ]'
short_grey='"string type" [ "subsurface" ] "rgb reflectance" [ 0.6 0.6 0.6 ] "rgb mfp" [ 0.05 0.05 0.05 ] "float eta" [ 1.5 ] "float roughness" [ 0.1 ]'
short_col='"string type" [ "subsurface" ] "rgb reflectance" [ 0.8 0.6 0.3 ] "rgb mfp" [ 0.05 0.03 0.02 ] "float eta" [ 1.5 ] "float roughness" [ 0.1 ]'
tall_skin='"string type" [ "subsurface" ] "string name" [ "Skin1" ] "float scale" [ 20 ] "float eta" [ 1.33 ]'
tall_red='"string type" [ "subsurface" ] "rgb sigma_a" [ 0.64 0.64 0.64 ] "rgb sigma_s" [ 14.8 14.8 14.8 ] "float eta" [ 1.33 ]'
variants=(
    "grey|$tall_grey|$short_grey"
    "coloured|$tall_grey|$short_col"
    "skin|$tall_skin|$short_grey"
    "skin-red|$tall_red|$short_grey"
)
for v in "${variants[@]}"; do
    IFS='|' read -r name tall short <<<"$v"
    file=$out/$name.pbrt
    python3 - "$scene" "$file" "$tall" "$short" <<'PY'
import sys
src, dst, tall, short = sys.argv[1:]
s = open(src).read()
diffuse = '"string type" [ "diffuse" ]\n    "rgb reflectance" [ 0.725 0.71 0.68 ]'
for box, m in (("TallBox", tall), ("ShortBox", short)):
    old = f'MakeNamedMaterial "{box}"\n    {diffuse}'
    assert old in s, box
    s = s.replace(old, f'MakeNamedMaterial "{box}"\n    {m}')
for a, b in (('Integrator "path"', 'Integrator "volpath"'), ('"rgb L" [ 17 12 4 ]', '"rgb L" [ 12 12 12 ]'),
             ('"integer yresolution" [ 1024 ] "integer xresolution" [ 1024 ]',
              '"integer yresolution" [ 128 ] "integer xresolution" [ 128 ]')):
    assert a in s, a
    s = s.replace(a, b)
open(dst, "w").write(s)
PY
    "$PBRT" --quiet --nthreads 2 --spp 512 --outfile "$out/$name-pbrt.pfm" "$file"
    start=$(date +%s.%N)
    "$bin" -q --scene "$file" --spp 512 -o "$out/$name-ours.pfm"
    echo "$name: ours $(echo "$(date +%s.%N) - $start" | bc) s"
done
python3 - "$out" <<'PY'
import struct, sys
out = sys.argv[1]
def load(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        fmt = "<" if scale < 0 else ">"
        return w, h, struct.unpack(f"{fmt}{w * h * 3}f", f.read(w * h * 12))
# Fractions of the frame (x0, y0, x1, y1), top down: the boxes' fronts.
regions = {"tall box": (0.25, 0.35, 0.45, 0.75), "short box": (0.55, 0.6, 0.75, 0.85)}
def mean(img, r):
    w, h, d = img
    x0, y0, x1, y1 = int(r[0] * w), int(r[1] * h), int(r[2] * w), int(r[3] * h)
    s, n = [0.0] * 3, 0
    for y in range(y0, y1):
        row = h - 1 - y  # PFM rows run bottom up
        for x in range(x0, x1):
            for c in range(3):
                s[c] += d[3 * (row * w + x) + c]
            n += 1
    return [v / n for v in s]
means = {}
print("| variant | region | ours R G B | pbrt-v4 R G B | ours / pbrt-v4 |")
print("|---|---|---|---|---|")
for name in ("grey", "coloured", "skin", "skin-red"):
    ours, pbrt = load(f"{out}/{name}-ours.pfm"), load(f"{out}/{name}-pbrt.pfm")
    for rn, r in regions.items():
        a, b = mean(ours, r), mean(pbrt, r)
        means[(name, rn)] = (a, b)
        fmt = lambda v: " ".join(f"{x:.4f}" for x in v)
        print(f"| {name} | {rn} | {fmt(a)} | {fmt(b)} | {fmt([x / y for x, y in zip(a, b)])} |")
(sa, sb), (ra, rb) = means[("skin", "tall box")], means[("skin-red", "tall box")]
print(f"tall box red, Skin1 over its red coefficients in grey: ours {sa[0] / ra[0]:.3f}, pbrt-v4 {sb[0] / rb[0]:.3f}")
PY
