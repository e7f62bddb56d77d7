#!/usr/bin/env bash
# Which renderer's `coateddiffuse` is right: the material against the same
# coat made as geometry. A diffuse floor (reflectance R) under a rough
# dielectric plane 0.001 above it (index 1.5, `roughness` ROUGH, remapped as
# pbrt-v4 remaps it) is the layered model a `coateddiffuse` of that
# reflectance and roughness describes, without its absorbing layer
# (`thickness` 1e-5 here). BASE=conductor puts a copper-like metal of
# roughness CR (0) under the coat instead, against `coatedconductor`. Both are path traced, by us and by pbrt-v4 when
# PBRT is set, under a quad light to the side, seen from 45 degrees; the
# script prints each image's mean and its three bands of rows (far, middle,
# near), and each coat against the geometry rendered by the same renderer.
#
#   bench/coat-as-geometry.sh                       # ours only
#   PBRT=path/to/pbrt SPP=1024 ROUGH=0.3 R=0.64 bench/coat-as-geometry.sh
#   PBRT=path/to/pbrt BASE=conductor ROUGH=0.3 CR=0.1 bench/coat-as-geometry.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
(cd "$root" && cargo build --release --quiet --bin raytracer)
out=$root/target/coat-as-geometry
mkdir -p "$out"
spp=${SPP:-512} rough=${ROUGH:-0.3} r=${R:-0.64} base=${BASE:-diffuse} cr=${CR:-0}
python3 - "$out" "$spp" "$rough" "$r" "$base" "$cr" <<'PY'
import sys
out, spp, rough, r, base, cr = sys.argv[1:]
head = f'''LookAt 3 0 3  0 0 0  0 0 1
Camera "perspective" "float fov" 50
Film "rgb" "integer yresolution" [ 24 ] "integer xresolution" [ 24 ]
Sampler "independent" "integer pixelsamples" {spp}
Integrator "path" "integer maxdepth" 60
WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]
Shape "trianglemesh" "integer indices" [0 2 1 0 3 2] "point3 P" [ -8 -5 6  -2 -5 6  -2 5 6  -8 5 6 ]
AttributeEnd
'''
def plane(z):
    return (f'Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] '
            f'"point3 P" [ -100 -100 {z}  100 -100 {z}  100 100 {z}  -100 100 {z} ]\n')
glass = f'Material "dielectric" "float eta" 1.5 "float roughness" {rough}\n'
if base == "conductor":
    # A copper-like metal. Under the coat its indices are relative to the
    # coat's (pbrt-v4 divides them by the interface's); the bare metal of
    # the geometry takes them divided so, its Fresnel being against air.
    eta, k = (0.27, 0.68, 1.22), (3.61, 2.62, 2.29)
    rel = lambda v: " ".join(f"{x / 1.5:.6f}" for x in v)
    diffuse = f'Material "conductor" "rgb eta" [ {rel(eta)} ] "rgb k" [ {rel(k)} ] "float roughness" {cr}\n'
    coat = (f'Material "coatedconductor" "float interface.roughness" {rough} '
            f'"rgb conductor.eta" [ {" ".join(map(str, eta))} ] "rgb conductor.k" [ {" ".join(map(str, k))} ] '
            f'"float conductor.roughness" {cr} "float thickness" 0.00001 "integer maxdepth" 100\n')
else:
    diffuse = f'Material "diffuse" "rgb reflectance" [ {r} {r} {r} ]\n'
    coat = (f'Material "coateddiffuse" "rgb reflectance" [ {r} {r} {r} ] "float roughness" {rough} '
            '"float thickness" 0.00001 "integer maxdepth" 100\n')
open(f"{out}/geometry.pbrt", "w").write(
    head + "AttributeBegin\n" + diffuse + plane(0) + "AttributeEnd\nAttributeBegin\n" + glass
    + plane(0.001) + "AttributeEnd\n")
open(f"{out}/material.pbrt", "w").write(head + coat + plane(0))
PY
for scene in geometry material; do
    "$root/target/release/raytracer" -q --scene "$out/$scene.pbrt" -o "$out/$scene-ours.pfm"
    if [ -n "${PBRT:-}" ]; then
        "$PBRT" --quiet --outfile "$out/$scene-pbrt.pfm" "$out/$scene.pbrt"
    fi
done
python3 - "$out" <<'PY'
import os, struct, sys
out = sys.argv[1]
def read(path):
    with open(path, "rb") as f:
        f.readline()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * 3
        v = struct.unpack(("<" if scale < 0 else ">") + f"{n}f", f.read(4 * n))
    # Rows bottom to top in the file: band 0 printed first is the top (far).
    rows = [sum(v[(y * w) * 3:(y * w + w) * 3]) / (3 * w) for y in range(h)][::-1]
    bands = [sum(rows[i:i + h // 3]) / (h // 3) for i in range(0, h, h // 3)]
    return sum(rows) / h, bands
for who in ("ours", "pbrt"):
    g, m = f"{out}/geometry-{who}.pfm", f"{out}/material-{who}.pfm"
    if not os.path.exists(m):
        continue
    (gm, gb), (mm, mb) = read(g), read(m)
    print(f"{who}: geometry {gm:.5f} {[round(b, 4) for b in gb]}  material {mm:.5f} "
          f"{[round(b, 4) for b in mb]}  coat / geometry {mm / gm:.4f}")
PY
