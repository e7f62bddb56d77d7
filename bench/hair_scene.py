#!/usr/bin/env python3
"""Writes a pbrt-v4 scene of hair for comparing our curves and hair material
with pbrt-v4's own (bench/against-pbrt.sh renders it with both).

    python3 bench/hair_scene.py target/hair/hair.pbrt [STRANDS]

Three locks of wavy strands hang in front of a grey wall, lit by a distant
light and a uniform sky: blonde (`reflectance`), brown (`eumelanin`) and red
(`pheomelanin`); cubic B-spline cylinders, cubic Bezier flat ribbons and
quadratic B-splines, tapering, under a rotation and a uniform scale. The
strands are drawn from a fixed seed, so the file is the same every time.
"""
import math
import os
import random
import sys

out = sys.argv[1]
strands = int(sys.argv[2]) if len(sys.argv) > 2 else 1500
rng = random.Random(7)
locks = [
    ('"rgb reflectance" [0.8 0.6 0.35]', 'cylinder', 'bspline', 3, -1.1),
    ('"float eumelanin" 1.2', 'flat', 'bezier', 3, 0.0),
    ('"float eumelanin" 0.3 "float pheomelanin" 2.5 "float beta_m" 0.2 "float alpha" 3', 'cylinder', 'bspline', 2, 1.1),
]
lines = [
    'Integrator "path" "integer maxdepth" [ 24 ]',
    'Sampler "independent" "integer pixelsamples" [ 64 ]',
    'PixelFilter "box"',
    'Film "rgb" "integer xresolution" [ 320 ] "integer yresolution" [ 240 ] "string filename" [ "hair.exr" ]',
    'LookAt 0 0.2 -5  0 0.2 0  0 1 0',
    'Camera "perspective" "float fov" [ 36 ]',
    'WorldBegin',
    'LightSource "infinite" "rgb L" [ 0.35 0.4 0.5 ]',
    'LightSource "distant" "point3 from" [ -1 2 -2 ] "point3 to" [ 0 0 0 ] "rgb L" [ 2.5 2.5 2.4 ]',
    'AttributeBegin',
    '  Material "diffuse" "rgb reflectance" [ 0.45 0.45 0.45 ]',
    '  Shape "trianglemesh" "point3 P" [ -4 -3 1.5  4 -3 1.5  4 3 1.5  -4 3 1.5 ] "integer indices" [ 0 1 2  0 2 3 ]',
    'AttributeEnd',
]
for material, kind, basis, degree, x0 in locks:
    lines += ['AttributeBegin', f'  Material "hair" {material}', '  Rotate 8 0 0 1', '  Scale 0.5 0.5 0.5']
    for _ in range(strands // len(locks)):
        x = 2 * x0 + rng.gauss(0, 0.45)
        z = rng.uniform(-0.6, 0.6)
        phase, amp, freq = rng.uniform(0, 6.3), rng.uniform(0.05, 0.25), rng.uniform(1.5, 3.0)
        if basis == 'bezier':
            n = 3 * 3 + 1  # three cubic segments
        else:
            n = 9
        pts = []
        for i in range(n):
            t = i / (n - 1)
            y = 2.4 - 4.4 * t
            pts.append((x + amp * math.sin(phase + freq * 6 * t), y, z + amp * math.cos(phase + freq * 5 * t)))
        flat = ' '.join(f'{a:.4f} {b:.4f} {c:.4f}' for a, b, c in pts)
        lines.append(
            f'  Shape "curve" "string type" "{kind}" "string basis" "{basis}" "integer degree" {degree} '
            f'"float width0" 0.014 "float width1" 0.006 "point3 P" [ {flat} ]'
        )
    lines.append('AttributeEnd')
os.makedirs(os.path.dirname(out) or '.', exist_ok=True)
with open(out, 'w') as f:
    f.write('\n'.join(lines) + '\n')
