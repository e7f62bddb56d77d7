#!/usr/bin/env python3
"""Writes a pbrt-v4 scene of one glowing cube of `rgbgrid` medium that only
absorbs, seen alone against black, for telling apart, against pbrt-v4
itself (`bench/against-pbrt.sh OUT.pbrt 32 32 64`), what an RGB renderer
makes of emission from what a spectral one does. See BENCHMARKS.md,
"Emissive media against pbrt-v4".

    python3 bench/glow_cube.py OUT.pbrt [--grey]

By default sigma_a (0.5, 0.6, 0.8) and Le (1, 0.45, 0.1), the colours of the
glowing smoke; --grey makes sigma_a (0.5, 0.5, 0.5) and Le (1, 0.5, 0.2).
"""
import sys

args = [a for a in sys.argv[1:] if not a.startswith("--")]
flags = {a for a in sys.argv[1:] if a.startswith("--")}
if len(args) != 1 or flags - {"--grey"}:
    sys.exit(__doc__)
grey = "--grey" in flags
n = 4
sigma_a = "0.5 0.5 0.5" if grey else "0.5 0.6 0.8"
le = "1 0.5 0.2" if grey else "1 0.45 0.1"
with open(args[0], "w") as f:
    f.write(f'''LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 32 "integer yresolution" 32 "string filename" "cube.exr"
Sampler "halton" "integer pixelsamples" 64
Integrator "volpath" "integer maxdepth" 5
WorldBegin
AttributeBegin
MakeNamedMedium "glow" "string type" "rgbgrid"
  "integer nx" {n} "integer ny" {n} "integer nz" {n} "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1]
  "rgb sigma_a" [{" ".join([sigma_a] * n**3)}]
  "rgb sigma_s" [{" ".join(["0 0 0"] * n**3)}]
  "rgb Le" [{" ".join([le] * n**3)}]
Material "interface"
# The cube's triangles face into it: its inside is pbrt-v4's "outside".
MediumInterface "" "glow"
Shape "trianglemesh" "point3 P" [-1 -1 -1 1 -1 -1 1 1 -1 -1 1 -1 -1 -1 1 1 -1 1 1 1 1 -1 1 1]
    "integer indices" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  3 2 6 3 6 7  0 3 7 0 7 4  1 5 6 1 6 2]
AttributeEnd
''')
