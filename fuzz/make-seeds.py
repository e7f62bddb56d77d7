#!/usr/bin/env python3
"""Writes the small valid inputs that seed the fuzz corpora (seeds/<target>/)."""
import os
import struct

here = os.path.dirname(os.path.abspath(__file__))


def put(target, name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(here, "seeds", target, name), "wb") as f:
        f.write(data)


# OBJ: the material library follows a NUL byte (see fuzz_targets/common.rs).
put("obj", "triangle.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
put("obj", "quad-normals-uv.obj",
    "# a quad with normals and texture coordinates\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
    "f 1/1/1 2/2/1 3/3/1 4/4/1\nf -4//1 -2//1 -1//1\n")
put("obj", "groups-mtl.obj",
    "mtllib m.mtl\no first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1 1.0\n"
    "usemtl red\nf 1 2 3\ng second\nusemtl blue\ns 1\nf 1 3 4\nl 1 2\np 3\n"
    "\0newmtl red\nKd 0.8 0.1 0.1\nKs 0 0 0\nNs 10\nillum 2\n"
    "newmtl blue\nKa 0 0 0\nKd 0.1 0.1 0.8\nd 1\nNi 1.5\nmap_Kd tex.png\n")

# PLY: the three encodings, normals, extra properties and elements, a quad.
header = ("ply\nformat {fmt} 1.0\ncomment seed\nelement vertex 4\n"
          "property float x\nproperty float y\nproperty float z\n"
          "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\n"
          "element face 2\nproperty list uchar int vertex_indices\nproperty int flags\n"
          "element edge 1\nproperty list uchar uint pair\nend_header\n")
verts = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
put("ply", "ascii.ply", header.format(fmt="ascii")
    + "".join(f"{x} {y} {z} 0 0 1 200\n" for x, y, z in verts)
    + "4 0 1 2 3 7\n3 0 2 3 0\n2 0 1\n")
for fmt, e in [("binary_little_endian", "<"), ("binary_big_endian", ">")]:
    body = b"".join(struct.pack(e + "6fB", x, y, z, 0, 0, 1, 200) for x, y, z in verts)
    body += struct.pack(e + "B4ii", 4, 0, 1, 2, 3, 7) + struct.pack(e + "B3ii", 3, 0, 2, 3, 0)
    body += struct.pack(e + "B2I", 2, 0, 1)
    put("ply", fmt + ".ply", header.format(fmt=fmt).encode() + body)
put("ply", "minimal-double-ushort.ply",
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
    "element face 1\nproperty list uint8 uint16 vertex_index\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")

# Scenes: the target serves a.obj (with m.mtl) and a.ply beside the scene.
camera = ('[camera]\nposition = [0.5, -0.5, -3]\nlook_at = [0.5, 0.5, 0]\nup = [0, -1, 0]\n'
          'fov_y = 40\nwidth = 16\nheight = 12\n')
put("scene", "shapes.toml", 'name = "shapes"\n' + camera + """
[settings]
ssaa = 2
shadow_samples = 1
integrator = "photon"
photons = 1000
max_bounces = 4
gather_radius = 0.1
gather_k = 50
gather_filter = "normal"
final_gather = 0

[materials]
white = { albedo = [0.7, 0.7, 0.7] }
mirror = { type = "mirror", reflectance = [0.9, 0.9, 0.9] }
glass = { type = "glass", ior = 1.5 }

[[lights]]
type = "sphere"
centre = [0.5, -1, 0.5]
radius = 0.1
power = 20
colour = [1, 0.9, 0.8]

[[lights]]
type = "point"
position = [0, -1, 0]
power = 5

[[shapes]]
type = "quad"
material = "white"
vertices = [[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1]]

[[shapes]]
type = "triangle"
material = "white"
vertices = [[0, 0, 1], [1, 0, 1], [0, 1, 1]]
normals = [[0, 0, -1], [0, 0, -1], [0, 0, -1]]

[[shapes]]
type = "box"
material = "mirror"
min = [0.1, 0.6, 0.1]
max = [0.4, 1.0, 0.4]

[[shapes]]
type = "sphere"
material = "glass"
centre = [0.7, 0.8, 0.5]
radius = 0.2
""")
put("scene", "meshes.toml", camera + """
[materials]
grey = { albedo = [0.5, 0.5, 0.5] }

[[lights]]
type = "point"
position = [0, -2, 0]
power = 10

[[shapes]]
type = "mesh"
path = "a.obj"
scale = 2
rotate = [0, 90, 0]
translate = [0, 0, 1]
smooth = true

[[shapes]]
type = "mesh"
path = "a.ply"
material = "grey"
scale = [1, 2, 1]
fit = { height = 0.5, bottom_centre = [0.5, 1, 0.5] }
""")
