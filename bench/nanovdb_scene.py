#!/usr/bin/env python3
"""Writes a pbrt-v4 scene with a `nanovdb` medium for rendering with pbrt-v4
itself and with ours (`bench/against-pbrt.sh`): the NanoVDB file of the
tests (`tests/data/small-zip.nvdb`, written by NanoVDB's own writer: an
ellipsoid of lumpy density and a temperature grid), copied beside the
scene, in a box of no surface above a grey floor, under a disk light and a
dim sky, glowing by the blackbody of its temperatures. See BENCHMARKS.md,
"NanoVDB media against pbrt-v4".

    python3 bench/nanovdb_scene.py OUT.pbrt [--dark] [--grid FILE.nvdb --scale S]

--dark leaves the glow out (Lescale 0). --grid copies another NanoVDB file
in the test file's place (its "density" grid; with no temperature grid it
does not glow), e.g. the one bench/nanovdb-large.cpp writes, and --scale sets
the medium's density scale (4).
"""
import os
import shutil
import sys

argv = sys.argv[1:]
opts = {}
for name in ("--grid", "--scale"):
    if name in argv:
        i = argv.index(name)
        if i + 1 >= len(argv):
            sys.exit(__doc__)
        opts[name] = argv[i + 1]
        del argv[i:i + 2]
args = [a for a in argv if not a.startswith("--")]
flags = {a for a in argv if a.startswith("--")}
if len(args) != 1 or flags - {"--dark"}:
    sys.exit(__doc__)
out = args[0]
here = os.path.dirname(os.path.abspath(__file__))
grid = opts.get("--grid", os.path.join(here, "..", "tests", "data", "small-zip.nvdb"))
scale = float(opts.get("--scale", "4"))
shutil.copy(grid, os.path.join(os.path.dirname(os.path.abspath(out)), "smoke.nvdb"))
lescale = 0 if "--dark" in flags else 0.05
with open(out, "w") as f:
    f.write(f'''LookAt 1.3 2.5 -4.5  1.3 0.3 1.1  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 200 "integer yresolution" 150 "string filename" "nanovdb.exr"
Sampler "halton" "integer pixelsamples" 64
Integrator "volpath" "integer maxdepth" 20
WorldBegin
LightSource "infinite" "rgb L" [0.2 0.25 0.3]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [12 11 9]
  Translate 1.3 4 1
  Rotate 90 1 0 0
  Shape "disk" "float radius" 0.8
AttributeEnd
Material "diffuse" "rgb reflectance" [0.6 0.6 0.6]
Shape "trianglemesh" "point3 P" [-5 -1 -5 8 -1 -5 8 -1 8 -5 -1 8] "integer indices" [0 2 1 0 3 2]
AttributeBegin
  Translate 0.2 0 0
  Rotate 15 0 1 0
  MakeNamedMedium "smoke" "string type" "nanovdb" "string filename" "smoke.nvdb"
    "rgb sigma_a" [0.5 0.6 0.8] "rgb sigma_s" [2.5 2.0 1.5] "float scale" {scale:g} "float g" 0.3
    "float Lescale" {lescale} "float temperaturescale" 2
  Material "interface"
  MediumInterface "" "smoke"
  Shape "trianglemesh" "point3 P" [-0.8 -0.8 0 3.7 -0.8 0 3.7 2.2 0 -0.8 2.2 0 -0.8 -0.8 3.4 3.7 -0.8 3.4 3.7 2.2 3.4 -0.8 2.2 3.4]
    "integer indices" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  3 2 6 3 6 7  0 3 7 0 7 4  1 5 6 1 6 2]
AttributeEnd
''')
