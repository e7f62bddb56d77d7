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
#   forward     tall box sigma_a 0.5, sigma_s 5, g 0.7 (forward scattering:
#               the phase function's direction convention in the single-
#               scattering term, and the reduced coefficients of the rest)
#   skin-red    tall box grey with Skin1's red coefficients (0.64, 14.8):
#               its red against skin's red, in each renderer, shows what
#               pbrt-v4's spectral upsampling of the coloured coefficients
#               does to the red channel
#
# Then a translucent bunny in the manner of pbrt-v4-scenes' sssdragon
# (`dragon_50.pbrt`: Skin1 x 50, eta 1.5, the mesh scaled by 0.02 over a
# checkerboard floor; its dragon mesh and sky image stand in as the
# Stanford bunny scaled to the dragon's size and a constant sky with a
# distant light), 342 x 256, 256 spp: `compare` over the image, and the
# bunny's mean in each channel (its pixels: those pbrt-v4 renders orange),
# ours over pbrt-v4's. PNG_OUT=file.png writes the two side by side.
#
# Last, lossless balls of 30 and 6 mean free paths in radius under a
# uniform sky, ours and pbrt-v4's centre pixels.
#
# Usage: PBRT=path/to/pbrt [PNG_OUT=docs/subsurface-bunny.png] bench/subsurface.sh
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
tall_fwd='"string type" [ "subsurface" ] "rgb sigma_a" [ 0.5 0.5 0.5 ] "rgb sigma_s" [ 5 5 5 ] "float g" [ 0.7 ] "float eta" [ 1.33 ]'
tall_red='"string type" [ "subsurface" ] "rgb sigma_a" [ 0.64 0.64 0.64 ] "rgb sigma_s" [ 14.8 14.8 14.8 ] "float eta" [ 1.33 ]'
variants=(
    "grey|$tall_grey|$short_grey"
    "coloured|$tall_grey|$short_col"
    "skin|$tall_skin|$short_grey"
    "forward|$tall_fwd|$short_grey"
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
import sys
sys.path.insert(0, "bench")
from pfm import load
out = sys.argv[1]
# Fractions of the frame (x0, y0, x1, y1), top down: the boxes' fronts.
regions = {"tall box": (0.25, 0.35, 0.45, 0.75), "short box": (0.55, 0.6, 0.75, 0.85)}
def mean(img, r):
    w, h, d = img
    x0, y0, x1, y1 = int(r[0] * w), int(r[1] * h), int(r[2] * w), int(r[3] * h)
    s, n = [0.0] * 3, 0
    for y in range(y0, y1):
        for x in range(x0, x1):
            for c in range(3):
                s[c] += d[y * w + x][c]
            n += 1
    return [v / n for v in s]
means = {}
print("| variant | region | ours R G B | pbrt-v4 R G B | ours / pbrt-v4 |")
print("|---|---|---|---|---|")
for name in ("grey", "coloured", "skin", "forward", "skin-red"):
    ours, pbrt = load(f"{out}/{name}-ours.pfm"), load(f"{out}/{name}-pbrt.pfm")
    for rn, r in regions.items():
        a, b = mean(ours, r), mean(pbrt, r)
        means[(name, rn)] = (a, b)
        fmt = lambda v: " ".join(f"{x:.4f}" for x in v)
        print(f"| {name} | {rn} | {fmt(a)} | {fmt(b)} | {fmt([x / y for x, y in zip(a, b)])} |")
(sa, sb), (ra, rb) = means[("skin", "tall box")], means[("skin-red", "tall box")]
print(f"tall box red, Skin1 over its red coefficients in grey: ours {sa[0] / ra[0]:.3f}, pbrt-v4 {sb[0] / rb[0]:.3f}")
PY

# The translucent bunny.
mkdir -p "$out/geometry"
python3 - ../shared/assets/stanford-bunny.obj "$out/geometry/bunny.ply" <<'PY'
import sys
vs, fs = [], []
for line in open(sys.argv[1]):
    t = line.split()
    if t and t[0] == "v":
        vs.append([float(x) for x in t[1:4]])
    elif t and t[0] == "f":
        fs.append([int(x.split("/")[0]) - 1 for x in t[1:]])
# Centred on the floor, 46 units tall (the dragon's size before its 0.02).
cx = (min(v[0] for v in vs) + max(v[0] for v in vs)) / 2
cz = (min(v[2] for v in vs) + max(v[2] for v in vs)) / 2
y0 = min(v[1] for v in vs)
with open(sys.argv[2], "w") as f:
    f.write(f"ply\nformat ascii 1.0\nelement vertex {len(vs)}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face {len(fs)}\nproperty list uchar int vertex_indices\nend_header\n")
    for v in vs:
        f.write(f"{(v[0] - cx) * 300:.5f} {(v[1] - y0) * 300:.5f} {(v[2] - cz) * 300:.5f}\n")
    for face in fs:
        f.write(f"{len(face)} " + " ".join(map(str, face)) + "\n")
PY
cat >"$out/bunny.pbrt" <<'PBRT'
Sampler "halton" "integer pixelsamples" [ 256 ]
PixelFilter "gaussian"
Film "rgb" "float iso" 200 "integer yresolution" [ 256 ] "integer xresolution" [ 342 ]
Scale -1 1 1
LookAt 3.69558 -3.46243 3.25463  3.04072 -2.85176 2.80939  -0.317366 0.312466 0.895346
Camera "perspective" "float fov" [ 28.841503 ]
WorldBegin
AttributeBegin
    ConcatTransform [ -0.224951 0 -0.97437 0 -0.97437 0 0.224951 0 0 1 0 8.87 0 0 0 1 ]
    LightSource "infinite" "float scale" .3 "rgb L" [ 1 1 1 ]
AttributeEnd
LightSource "distant" "point3 from" [ 2 -3 6 ] "point3 to" [ 0 0 0 ] "rgb L" [ 2 2 2 ]
AttributeBegin
    Translate 0.2 0.3 0.78
    Rotate 90 1 0 0
    Rotate -90 0 1 0
    Scale 0.02 0.02 0.02
    Material "subsurface" "float scale" [ 50 ] "string name" [ "Skin1" ] "float eta" [ 1.5 ]
    Shape "plymesh" "string filename" [ "geometry/bunny.ply" ]
AttributeEnd
Texture "checkers" "spectrum" "checkerboard" "float uscale" [ 16 ] "float vscale" [ 16 ]
    "rgb tex2" [ 0.2 0.2 0.2 ] "rgb tex1" [ 0.4 0.4 0.4 ]
AttributeBegin
    Material "diffuse" "texture reflectance" [ "checkers" ]
    Shape "bilinearmesh" "point3 P" [ -4 -4 0.78  4 -4 0.78  -4 4 0.78  4 4 0.78 ] "point2 uv" [ 0 0 1 0 0 1 1 1 ]
AttributeEnd
PBRT
"$PBRT" --quiet --nthreads 2 --outfile "$out/bunny-pbrt.pfm" "$out/bunny.pbrt"
start=$(date +%s.%N)
"$bin" -q --scene "$out/bunny.pbrt" -o "$out/bunny-ours.pfm"
echo "bunny: ours $(echo "$(date +%s.%N) - $start" | bc) s"
"$bin" compare "$out/bunny-ours.pfm" "$out/bunny-pbrt.pfm" --max-luminance 4
python3 - "$out" "${PNG_OUT:-}" <<'PY'
import sys
sys.path.insert(0, "bench")
from pfm import load, write_png
out, png = sys.argv[1], sys.argv[2]
w, h, ours = load(f"{out}/bunny-ours.pfm")
_, _, pbrt = load(f"{out}/bunny-pbrt.pfm")
sel = [i for i, p in enumerate(pbrt) if p[0] > 1.6 * p[2]]
a = [sum(ours[i][c] for i in sel) / len(sel) for c in range(3)]
b = [sum(pbrt[i][c] for i in sel) / len(sel) for c in range(3)]
print(f"bunny ({len(sel)} pixels): ours / pbrt-v4 R G B " + " ".join(f"{x / y:.3f}" for x, y in zip(a, b)))
if png:
    write_png(png, w, h, (ours, pbrt))
    print(f"wrote {png}")
PY


# Lossless balls (sigma_s 30) under a uniform sky of 1, 32 x 32, 256 spp:
# the centre pixels' mean, radius 1 (30 mean free paths) and 0.2 (6). The
# profile is a slab's: on a small object probes that miss it lose light.
for radius in 1 0.2; do
    file=$out/ball-$radius.pbrt
    printf 'Integrator "volpath"\nFilm "rgb" "integer xresolution" 32 "integer yresolution" 32\nCamera "perspective" "float fov" 20\nWorldBegin\nLightSource "infinite" "rgb L" [ 1 1 1 ]\nTranslate 0 0 %s\nMaterial "subsurface" "rgb sigma_a" [ 0 0 0 ] "rgb sigma_s" [ 30 30 30 ]\nShape "sphere" "float radius" %s\n' \
        "$(echo "$radius * 4" | bc)" "$radius" >"$file"
    "$PBRT" --quiet --nthreads 2 --spp 256 --outfile "$out/ball-$radius-pbrt.pfm" "$file"
    "$bin" -q --scene "$file" --spp 256 -o "$out/ball-$radius-ours.pfm"
    python3 - "$out" "$radius" <<'PY'
import sys
sys.path.insert(0, "bench")
from pfm import load
out, radius = sys.argv[1:]
def centre(path):
    w, h, p = load(path)
    c = [p[y * w + x] for y in range(12, 20) for x in range(12, 20)]
    return sum(sum(q) / 3 for q in c) / len(c)
print(f"lossless ball, radius {radius}: ours {centre(f'{out}/ball-{radius}-ours.pfm'):.3f}, "
      f"pbrt-v4 {centre(f'{out}/ball-{radius}-pbrt.pfm'):.3f}")
PY
done
