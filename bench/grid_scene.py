#!/usr/bin/env python3
"""Writes a pbrt-v4 scene with a `uniformgrid` medium: a lumpy blob of smoke
in a box of no surface above a grey floor, lit by a disk light and a dim
sky, for rendering with pbrt-v4 itself and with ours
(`bench/against-pbrt.sh`). See BENCHMARKS.md, "Participating media".

    python3 bench/grid_scene.py OUT.pbrt [--homogeneous | --rgb] [--absorbing] [--emissive] [N]
    python3 bench/grid_scene.py OUT.pbrt --furnace

N is the grid's samples along each axis (24 by default). --homogeneous
writes the same scene with a homogeneous medium of half the coefficients
instead (its twin, to tell the grid's share of a difference from the
rest); --absorbing makes the smoke absorb without scattering; --emissive
makes it glow: the grid by the blackbody of a temperature grid (hottest in
the middle, with pbrt-v4's `temperatureoffset` and `temperaturescale`) times
a grid of `Lescale`, the homogeneous twin by an RGB `Le` (with `Lescale`).
--rgb writes the smoke as an `rgbgrid` instead: the same densities times
the same coefficients, sigma_s tinted from red to blue across x (its Le,
with --emissive, an RGB grid hottest in the middle).
--furnace
writes a white furnace instead: the camera inside a dense 4 x 4 x 4 grid
that scatters without absorbing, under a sky of radiance 1 and nothing
else, where every pixel's true value is 1 (Russian roulette in media).
"""
import math
import sys

args = [a for a in sys.argv[1:] if not a.startswith("--")]
flags = {a for a in sys.argv[1:] if a.startswith("--")}
if not args or flags - {"--homogeneous", "--absorbing", "--furnace", "--emissive", "--rgb"}:
    sys.exit(__doc__)
out = args[0]
if "--furnace" in flags:
    density = " ".join(str([0.0, 3.0, 0.5, 8.0][i % 4] * (1 + i % 3)) for i in range(64))
    with open(out, "w") as f:
        f.write(f'''LookAt 0 0 0.3  0 0 1  0 1 0
MakeNamedMedium "cloud" "string type" "uniformgrid" "rgb sigma_a" [0 0 0] "rgb sigma_s" [0.3 0.8 2.0] "float g" 0.5
  "integer nx" 4 "integer ny" 4 "integer nz" 4 "point3 p0" [-1.5 -1.5 -1.5] "point3 p1" [1.5 1.5 1.5]
  "float density" [{density}]
MediumInterface "" "cloud"
Camera "perspective" "float fov" 60
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Sampler "halton" "integer pixelsamples" 256
Integrator "volpath" "integer maxdepth" 60000
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
''')
    sys.exit(0)
n = int(args[1]) if len(args) > 1 else 24

values, temperatures, lescale, rgb_a, rgb_s, rgb_le = [], [], [], [], [], []
for k in range(n):
    for j in range(n):
        for i in range(n):
            x, y, z = ((c + 0.5) / n * 2 - 1 for c in (i, j, k))
            r = math.sqrt(x * x + 1.5 * y * y + z * z)
            d = max(0.0, 1 - r) * (1 + 0.5 * math.sin(7 * x) * math.cos(5 * z))
            values.append(f"{max(d, 0.0) * 4:.4f}")
            # Kelvin after the offset (300) and scale (1.5): up to about 2100 K.
            temperatures.append(f"{300 + 1400 * max(0.0, 1 - r):.2f}")
            lescale.append(f"{1 + 0.5 * math.cos(3 * y):.4f}")
            dv = max(d, 0.0) * 4
            sa = (1.5, 2.0, 3.0) if "--absorbing" in flags else (0.5, 0.6, 0.8)
            ss = (0.0, 0.0, 0.0) if "--absorbing" in flags else (2.5 * (1 + 0.5 * x), 2.0, 1.5 * (1 - 0.5 * x))
            rgb_a.append(" ".join(f"{dv * c:.4f}" for c in sa))
            rgb_s.append(" ".join(f"{dv * c:.4f}" for c in ss))
            glow = 2 * max(0.0, 1 - r)
            rgb_le.append(" ".join(f"{glow * c:.4f}" for c in (1.0, 0.45, 0.1)))
emissive = "--emissive" in flags

sigma_s = "[0 0 0]" if "--absorbing" in flags else "[2.5 2.0 1.5]"
sigma_a = "[1.5 2.0 3.0]" if "--absorbing" in flags else "[0.5 0.6 0.8]"
if "--rgb" in flags:
    medium = (f'MakeNamedMedium "smoke" "string type" "rgbgrid" "float g" 0.3\n'
              f'    "integer nx" {n} "integer ny" {n} "integer nz" {n} '
              f'"point3 p0" [-1 -1 -1] "point3 p1" [1 1 1]\n'
              f'    "rgb sigma_a" [{" ".join(rgb_a)}]\n'
              f'    "rgb sigma_s" [{" ".join(rgb_s)}]')
    if emissive:
        medium += f'\n    "rgb Le" [{" ".join(rgb_le)}] "float Lescale" 0.8'
elif "--homogeneous" in flags:
    medium = (f'MakeNamedMedium "smoke" "string type" "homogeneous" "rgb sigma_a" {sigma_a} '
              f'"rgb sigma_s" {sigma_s} "float scale" 0.5 "float g" 0.3')
    if emissive:
        medium += ' "rgb Le" [1.0 0.45 0.1] "float Lescale" 0.6'
else:
    medium = (f'MakeNamedMedium "smoke" "string type" "uniformgrid" "rgb sigma_a" {sigma_a} '
              f'"rgb sigma_s" {sigma_s} "float g" 0.3\n'
              f'    "integer nx" {n} "integer ny" {n} "integer nz" {n} '
              f'"point3 p0" [-1 -1 -1] "point3 p1" [1 1 1]\n'
              f'    "float density" [{" ".join(values)}]')
    if emissive:
        medium += (f'\n    "float temperatureoffset" 300 "float temperaturescale" 1.5'
                   f'\n    "float temperature" [{" ".join(temperatures)}]'
                   f'\n    "float Lescale" [{" ".join(lescale)}]')

# The box's triangles face into it, so its inside is pbrt-v4's "outside".
scene = f'''LookAt 0 1.5 -5  0 0.2 0  0 1 0
Camera "perspective" "float fov" 35
Film "rgb" "integer xresolution" 200 "integer yresolution" 150 "string filename" "grid.exr"
Sampler "halton" "integer pixelsamples" 64
Integrator "volpath" "integer maxdepth" 20
WorldBegin
LightSource "infinite" "rgb L" [0.2 0.25 0.3]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [12 11 9]
  Translate 0 3 0
  Rotate 90 1 0 0
  Shape "disk" "float radius" 0.8
AttributeEnd
Material "diffuse" "rgb reflectance" [0.6 0.6 0.6]
Shape "trianglemesh" "point3 P" [-5 -1.3 -5 5 -1.3 -5 5 -1.3 5 -5 -1.3 5] "integer indices" [0 2 1 0 3 2]
AttributeBegin
  Rotate 20 0 1 0
  {medium}
  Material "interface"
  MediumInterface "" "smoke"
  Shape "trianglemesh" "point3 P" [-1 -1 -1 1 -1 -1 1 1 -1 -1 1 -1 -1 -1 1 1 -1 1 1 1 1 -1 1 1]
    "integer indices" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  3 2 6 3 6 7  0 3 7 0 7 4  1 5 6 1 6 2]
AttributeEnd
'''
with open(out, "w") as f:
    f.write(scene)
