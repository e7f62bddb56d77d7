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

# Motion: the shutter, and every kind of shape that may move.
put("scene", "motion.toml", """name = "motion"
[camera]
position = [0, 0, -3]
look_at = [0, 0, 0]
fov_y = 40
width = 16
height = 12
shutter = [0.25, 0.75]

[materials]
white = { albedo = [0.7, 0.7, 0.7] }

[[lights]]
type = "sphere"
centre = [0, -1, 0]
radius = 0.1
power = 20

[[shapes]]
type = "quad"
material = "white"
vertices = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]
motion = { translate = [0.1, 0, 0] }

[[shapes]]
type = "box"
material = "white"
min = [-0.3, 0.2, -0.3]
max = [0.3, 0.8, 0.3]
motion = { translate = [0.5, 0, 0], rotate = [0, 45, 10], scale = [1, 2, 1], about = [0, 1, 0] }

[[shapes]]
type = "triangle"
material = "white"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
motion = { scale = 0.5 }

[[shapes]]
type = "mesh"
path = "a.obj"
motion = { rotate = [90, 0, 0] }

[[shapes]]
type = "sphere"
material = "white"
centre = [0.5, 0.5, 0]
radius = 0.2
motion = { translate = [0, -0.5, 0], scale = [1, 1.5, 1] }

[[shapes]]
type = "disk"
material = "white"
centre = [-0.5, 0.5, 0]
normal = [0, -1, 0]
radius = 0.3
motion = { rotate = [30, 0, 0], about = [-0.8, 0.5, 0] }
""")

# pbrt-v4 scenes: the input up to its first NUL is the scene; what follows is
# served as any .ply (or .ply.gz) it names; virtual/inc.pbrt is a fixed file
# (see fuzz_targets/pbrt.rs). Written for the fuzzer in the syntax of the
# Bitterli scenes, not copied from them.
pbrt_camera = """Integrator "path" "integer maxdepth" [ 5 ]
Transform [ 1 0 0 0 0 1 0 0 0 0 -1 0 0 -1 6.8 1 ]
Sampler "sobol" "integer pixelsamples" [ 4 ]
PixelFilter "gaussian" "float xradius" [ 1.5 ] "float yradius" [ 1.5 ]
Film "rgb" "string filename" [ "out.exr" ]
    "integer yresolution" [ 12 ] "integer xresolution" [ 16 ]
Camera "perspective" "float fov" [ 19.5 ]
"""
put("pbrt", "box.pbrt", pbrt_camera + """
WorldBegin
MakeNamedMaterial "Floor"
    "string type" [ "diffuse" ]
    "rgb reflectance" [ 0.725 0.71 0.68 ]
MakeNamedMaterial "Light"
    "string type" [ "diffuse" ]
    "rgb reflectance" [ 0 0 0 ]
NamedMaterial "Floor"
Shape "trianglemesh"
    "point2 uv" [ 0 0 1 0 1 1 0 1 ]
    "normal N" [ 0 1 0 0 1 0 0 1 0 0 1 0 ]
    "point3 P" [ -1 0 -1 -1 0 1 1 0 1 1 0 -1 ]
    "integer indices" [ 0 1 2 0 2 3 ]
AttributeBegin
    AreaLightSource "diffuse" "rgb L" [ 17 12 4 ]
    NamedMaterial "Light"
    Shape "trianglemesh"
        "point3 P" [ -0.24 1.98 -0.22 0.23 1.98 -0.22 0.23 1.98 0.16 -0.24 1.98 0.16 ]
        "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
""")
put("pbrt", "plates-spheres.pbrt", """Integrator "path" "integer maxdepth" [ 3 ]
LookAt 0 2 15  0 -1 0  0 1 0
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 18 ]
Camera "perspective" "float fov" [ 20.1 ] "float lensradius" [ 0.05 ] "float focaldistance" [ 15 ]
WorldBegin
MakeNamedMaterial "Rough"
    "string type" [ "conductor" ]
    "float vroughness" [ 0.1 ] "float uroughness" [ 0.1 ]
    "bool remaproughness" [ false ]
    "rgb k" [ 3.91 2.45 2.14 ] "rgb eta" [ 0.2 0.92 1.1 ]
MakeNamedMaterial "Cu"
    "string type" [ "conductor" ]
    "spectrum eta" [ "metal-Cu-eta" ] "spectrum k" [ "metal-Cu-k" ]
    "float roughness" [ 0.05 ]
NamedMaterial "Rough"
Shape "bilinearmesh" "point3 P" [ -2 0 0 2 0 0 -2 1 -1 2 1 -1 ] "integer indices" [ 0 1 2 3 ]
NamedMaterial "Cu"
Shape "trianglemesh" "point3 P" [ -2 -1 0 2 -1 0 0 0 -1 ] "integer indices" [ 0 1 2 ]
AttributeBegin
    Translate -1.25 0 0
    AreaLightSource "diffuse" "blackbody L" [ 5500 ] "float power" [ 10 ]
    Material "diffuse" "rgb reflectance" [ 0 0 0 ]
    Shape "sphere" "float radius" [ 0.1 ]
AttributeEnd
AttributeBegin
    Translate 1.25 0 0
    AreaLightSource "diffuse" "rgb L" [ 100 100 100 ] "bool twosided" [ true ]
    Shape "disk" "float radius" [ 0.3 ] "float innerradius" [ 0.1 ] "float height" [ 0.5 ]
AttributeEnd
LightSource "point" "rgb I" [ 5 5 5 ] "point3 from" [ 0 4 0 ]
""")
put("pbrt", "transforms-instances.pbrt", """LookAt 0 0 -5  0 0 0  0 1 0
CoordinateSystem "mycam"
Scale -1 1 1
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ] "float cropwindow" [ 0 1 0.25 0.75 ]
Camera "perspective" "float fov" [ 40 ] "float screenwindow" [ -1 1 -1 1 ]
Sampler "halton" "integer pixelsamples" [ 2 ]
Option "disablepixeljitter" true
ColorSpace "srgb"
WorldBegin
Attribute "shape" "float radius" [ 0.5 ]
Texture "checks" "spectrum" "checkerboard" "float uscale" [ 4 ] "float vscale" [ 4 ]
    "rgb tex1" [ 1 0 0 ] "rgb tex2" [ 0 0 1 ]
Texture "rough" "float" "constant" "float value" [ 0.2 ]
Material "diffuse" "texture reflectance" "checks"
ObjectBegin "quad"
    Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 1 1 0 0 1 0 ] "integer indices" [ 0 1 2 0 2 3 ]
ObjectEnd
AttributeBegin
    Rotate 30 0 1 0
    ConcatTransform [ 1 0 0 0 0 1 0 0 0 0 1 0 0.5 0 0 1 ]
    ReverseOrientation
    ObjectInstance "quad"
AttributeEnd
AttributeBegin
    CoordSysTransform "mycam"
    Translate 0 0 1
    Material "dielectric" "float eta" [ 1.33 ] "texture roughness" "rough"
    Shape "sphere"
AttributeEnd
Include "inc.pbrt"
LightSource "distant" "point3 from" [ 0 0 0 ] "point3 to" [ 0 0 1 ] "rgb L" [ 3 3 3 ]
LightSource "infinite" "rgb L" [ 0.1 0.1 0.1 ]
""")
put("pbrt", "sppm-plymesh.pbrt", """Integrator "sppm" "integer iterations" [ 4 ]
    "integer photonsperiteration" [ 1000 ] "float radius" [ 0.05 ]
LookAt 0 1 -4  0 0 0  0 1 0
Film "rgb" "integer xresolution" [ 16 ] "integer yresolution" [ 16 ]
Camera "perspective" "float fov" [ 45 ]
WorldBegin
MakeNamedMaterial "Water" "string type" [ "dielectric" ] "float eta" [ 1.33 ]
NamedMaterial "Water"
Shape "plymesh" "string filename" [ "models/mesh.ply" ]
AttributeBegin
    AreaLightSource "diffuse" "rgb L" [ 10 10 10 ] "float scale" [ 2 ]
    Shape "trianglemesh" "point3 P" [ -1 3 -1 1 3 -1 0 3 1 ] "integer indices" [ 0 2 1 ]
AttributeEnd
""" + "\0" + header.format(fmt="ascii")
    + "".join(f"{x} {y} {z} 0 0 1 200\n" for x, y, z in verts)
    + "4 0 1 2 3 7\n3 0 2 3 0\n2 0 1\n")
put("pbrt", "ply-uv-faceindices.pbrt", """LookAt 0 0 -3  0 0 0  0 1 0
Camera "perspective" "float fov" [ 30 ]
WorldBegin
Shape "plymesh" "string filename" "mesh.ply"
""" + "\0" + "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nproperty float u\nproperty float v\nelement face 1\n"
    "property list uchar int vertex_indices\nproperty int face_indices\nend_header\n"
    "0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2 0\n")
put("pbrt", "cutouts.pbrt", """LookAt 0 1 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 16 ] "integer yresolution" [ 12 ]
WorldBegin
LightSource "distant" "point3 from" [ 1 4 -3 ] "point3 to" [ 0 0 0 ] "rgb L" [ 3 3 3 ]
Texture "stripes" "float" "checkerboard" "float uscale" [ 8 ] "float vscale" [ 1 ]
    "float tex1" [ 1 ] "float tex2" [ 0 ]
Material "diffuse" "rgb reflectance" [ 0.6 0.6 0.6 ] "texture displacement" "stripes"
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ] "point2 uv" [ 0 0 1 0 1 1 0 1 ]
    "integer indices" [ 0 1 2 0 2 3 ] "texture alpha" "stripes"
AttributeBegin
Translate 0.5 0.5 0
Rotate 30 0 1 0
Shape "sphere" "float radius" [ 0.5 ] "texture alpha" "stripes"
AttributeEnd
Shape "disk" "float radius" [ 0.3 ] "float alpha" [ 0.5 ]
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 2 2 2 ]
Shape "sphere" "float radius" [ 0.1 ] "float alpha" [ 0.25 ]
AttributeEnd
""")
put("pbrt", "mix-spectrum-file.pbrt", """Option "seed" 3
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ] "float shutterclose" [ 0.5 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ] "float iso" [ 200 ]
WorldBegin
LightSource "point" "rgb I" [ 5 5 5 ] "point3 from" [ 0 0 -4 ]
MakeNamedMaterial "a" "string type" "diffuse"
MakeNamedMaterial "b" "string type" "conductor" "spectrum k" "gold.spd" "spectrum eta" "metal-Au-eta"
Texture "bump" "float" "constant" "float value" [ 0.1 ]
MakeNamedMaterial "m" "string type" "mix" "string materials" [ "a" "b" ] "float amount" [ 0.3 ]
    "texture displacement" "bump"
NamedMaterial "m"
Shape "sphere"
Material "interface"
Shape "sphere" "float radius" [ 2 ]
""" + "\0" + "# wavelength value\n400 1.9\n500 1.8\n600 2.9\n700 4.0\n")

# A nanovdb medium: the tail is served as any .nvdb file too, here the
# tests' NanoVDB file (uncompressed it would be 4 MB; ZIP as it is).
with open(os.path.join(here, "..", "tests", "data", "small-zip.nvdb"), "rb") as f:
    nvdb = f.read()
put("pbrt", "nanovdb-media.pbrt", (pbrt_camera + """WorldBegin
AttributeBegin
  MakeNamedMedium "smoke" "string type" "nanovdb" "string filename" "smoke.nvdb"
    "rgb sigma_a" [0.5 0.6 0.8] "rgb sigma_s" [2.5 2.0 1.5] "float scale" 4
    "float Lescale" 0.05 "float temperaturescale" 2
  Material "interface"
  MediumInterface "" "smoke"
  Shape "sphere" "float radius" 3
AttributeEnd
LightSource "infinite" "rgb L" [0.5 0.5 0.5]
""").encode() + b"\0" + nvdb)

# Subsurface materials, every way of giving their medium, and a measured
# medium preset.
put("pbrt", "subsurface.pbrt", pbrt_camera + """WorldBegin
LightSource "infinite" "rgb L" [0.5 0.5 0.5]
Material "subsurface" "string name" [ "Skin1" ] "float scale" [ 20 ] "float eta" [ 1.5 ]
Shape "sphere" "float radius" 0.5
AttributeBegin
  Translate 1 0 0
  Material "subsurface" "rgb reflectance" [ 0.8 0.6 0.3 ] "rgb mfp" [ 0.05 0.03 0.02 ] "float roughness" 0.1
  Shape "sphere" "float radius" 0.3
AttributeEnd
AttributeBegin
  Translate -1 0 0
  MakeNamedMedium "milk" "string type" "homogeneous" "string preset" "Wholemilk" "float scale" 10
  Material "subsurface" "rgb sigma_a" [ 0.5 1 2 ] "rgb sigma_s" [ 20 20 20 ] "float g" 0.3
  MediumInterface "milk" ""
  Shape "sphere" "float radius" 0.3
AttributeEnd
""")

# Quadrics made meshes (partial and stretched spheres and disks, a mirrored
# cap that emits) and coats whose medium scatters.
put("pbrt", "quadrics-coats.pbrt", pbrt_camera + """WorldBegin
LightSource "distant" "point3 from" [ -1 3 -2 ] "point3 to" [ 0 0 0 ] "rgb L" [ 2 2 2 ]
AttributeBegin
  Scale 1 0.5 2
  Material "coateddiffuse" "rgb albedo" [ 0.9 0.5 0.1 ] "float g" 0.3 "float thickness" 0.2 "integer maxdepth" 12
  Shape "sphere" "float radius" 0.7 "float zmin" -0.2 "float zmax" 0.5 "float phimax" 270
AttributeEnd
AttributeBegin
  Translate 0 1 0
  Scale -1 1 1
  AreaLightSource "diffuse" "rgb L" [ 3 3 3 ]
  Shape "sphere" "float radius" 0.4 "float zmin" 0.1
AttributeEnd
AttributeBegin
  Rotate 90 1 0 0
  Scale 2 1 1
  Material "coatedconductor" "rgb albedo" [ 0.5 0.5 0.5 ] "float g" -0.4 "float conductor.roughness" 0.2
  Shape "disk" "float radius" 1 "float innerradius" 0.3 "float phimax" 200
AttributeEnd
""")

# Ribbon curves (normals at the segments' ends) and invisible area lights
# (alpha 0 on an emitting sphere and quad).
put("pbrt", "ribbons-invisible.pbrt", pbrt_camera + """WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 4 4 4 ]
  Translate 0 2 0
  Shape "sphere" "float radius" 0.3 "float alpha" 0
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 2 2 2 ] "bool twosided" true
  Shape "bilinearmesh" "point3 P" [ -1 1 1  1 1 1  -1 1.2 1  1 1.2 1 ] "float alpha" [ 0 ]
AttributeEnd
Shape "curve" "string type" "ribbon" "float width0" 0.3 "float width1" 0.1
  "point3 P" [ -1 0 0  -0.5 0.5 0  0.5 0.5 0  1 0 0  1.5 -0.5 0  2 0 0  2 1 0 ]
  "normal N" [ 0 0 1  0 1 1  1 0 0 ]
Shape "curve" "string type" "ribbon" "string basis" "bspline" "integer degree" 2
  "point3 P" [ 0 0 0  0 1 0  1 1 0  1 2 0 ] "normal N" [ 0 0 1  1 0 0  0 0 1 ]
""")

# Motion: a moving mesh, a moving instance, a moving camera and transform
# times, and the refused kinds (a moving sphere, a moving area light).
put("pbrt", "motion.pbrt", """TransformTimes 0.25 1.5
ActiveTransform EndTime
Rotate 3 0 1 0
ActiveTransform All
LookAt 0 1 -5  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ] "float shutteropen" 0.1 "float shutterclose" 1.2
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
WorldBegin
LightSource "infinite" "rgb L" [0.5 0.5 0.5]
AttributeBegin
  ActiveTransform StartTime
  Translate -1 0 0
  ActiveTransform EndTime
  Translate 1 0.5 0
  Rotate 90 0 0 1
  Scale 1 2 1
  ActiveTransform All
  Shape "trianglemesh" "integer indices" [ 0 1 2 2 3 0 ] "point3 P" [ -0.5 -0.5 0  0.5 -0.5 0  0.5 0.5 0  -0.5 0.5 0 ]
AttributeEnd
ObjectBegin "o"
  Scale 0.5 1 1
  Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ]
ObjectEnd
AttributeBegin
  ActiveTransform EndTime
  Translate 0 -1 0
  ActiveTransform All
  ObjectInstance "o"
  Shape "sphere" "float radius" 0.2
AttributeEnd
""")

put("scene", "procedural.toml", """name = "procedural"
[camera]
position = [0, 0, -3]
look_at = [0, 0, 0]
fov_y = 40
width = 16
height = 12

[textures.clouds]
type = "fbm"
frequency = 4
octaves = 5
[textures.sky]
type = "mix"
tex1 = [0.2, 0.3, 0.8]
amount = "clouds"
[textures.bumps]
type = "wrinkled"
roughness = 0.6
[textures.stone]
type = "marble"
variation = 0.5
[textures.spots]
type = "dots"
inside = "stone"
uscale = 8
[textures.ramp]
type = "bilerp"
v11 = [1, 0, 0]
[textures.waves]
type = "windy"
[textures.planks]
type = "checkerboard"
mapping = "planar"
v1 = [4, 0, 0]
v2 = [0, 0, 4]
udelta = 0.5
[textures.globe]
type = "dots"
mapping = "spherical"
centre = [0.5, 0.5, 0]
axis = [0, -1, 0]
[textures.barrel]
type = "bilerp"
mapping = "cylindrical"
v11 = [1, 0, 0]
[textures.cubes]
type = "checkerboard"
dimension = 3
frequency = 4
tex1 = "globe"

[materials]
a = { reflectance = "sky", displacement = "bumps" }
b = { reflectance = "spots" }
c = { reflectance = "ramp", displacement = "waves" }
d = { reflectance = "cubes", displacement = "barrel" }

[[lights]]
type = "sphere"
centre = [0, -1, 0]
radius = 0.1
power = 20

[[shapes]]
type = "quad"
material = "a"
vertices = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]

[[shapes]]
type = "sphere"
material = "b"
centre = [0.5, 0.5, 0]
radius = 0.2

[[shapes]]
type = "box"
material = "c"
min = [-0.3, 0.2, -0.3]
max = [0.3, 0.8, 0.3]

[[shapes]]
type = "triangle"
material = "d"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
""")

put("pbrt", "procedural.pbrt", """LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
WorldBegin
LightSource "infinite" "rgb L" [0.5 0.5 0.5]
AttributeBegin
  Translate 1 0 0
  Rotate 30 0 1 1
  Scale 3 3 3
  Texture "n" "float" "fbm" "integer octaves" [ 4 ] "float roughness" [ 0.6 ]
  Texture "w" "float" "wrinkled"
  Texture "v" "float" "windy"
  Texture "m" "spectrum" "marble" "float scale" [ 2 ] "float variation" [ 0.4 ]
  Texture "c3" "spectrum" "checkerboard" "integer dimension" [ 3 ] "texture tex1" "m"
  Texture "sph" "spectrum" "checkerboard" "string mapping" "spherical"
  Texture "cyl" "float" "dots" "string mapping" "cylindrical" "float inside" [ 0.2 ]
  Texture "pla" "spectrum" "bilerp" "string mapping" "planar" "vector3 v1" [ 0 0 1 ] "float udelta" [ 0.5 ]
  Texture "dm" "spectrum" "directionmix" "vector3 dir" [ 1 1 0 ] "texture tex1" "pla" "texture tex2" "sph"
  Texture "mx" "spectrum" "mix" "texture amount" "n" "texture tex1" "c3" "texture tex2" "dm"
AttributeEnd
Material "coateddiffuse" "texture reflectance" "mx" "texture displacement" "w" "texture roughness" "v"
Shape "sphere" "float radius" 1
Material "diffusetransmission" "texture reflectance" "m" "texture transmittance" "dm"
Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ]
Material "conductor" "texture roughness" "cyl"
Shape "trianglemesh" "integer indices" [ 0 1 2 ] "point3 P" [ -1 -1 1  1 -1 1  0 1 1 ]
""")

put("pbrt", "portal.pbrt", """LookAt 0 1 -1.5  0 1 2  0 1 0
Camera "perspective" "float fov" [ 60 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
Integrator "bdpt" "integer maxdepth" [ 4 ]
WorldBegin
AttributeBegin
  Rotate -90 1 0 0
  LightSource "infinite" "rgb L" [ 2 2 2 ] "float scale" [ 1.5 ]
    "point3 portal" [ -0.5 0.5 2  -0.5 1.5 2  0.5 1.5 2  0.5 0.5 2 ]
AttributeEnd
Material "diffuse"
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ -2 0 2  2 0 2  2 0.5 2  -2 0.5 2 ]
""")

put("pbrt", "reflecting-emitters.pbrt", """LookAt 0 1 -3  0 1 0  0 1 0
Camera "perspective" "float fov" [ 50 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
Integrator "bdpt" "integer maxdepth" [ 5 ]
WorldBegin
Texture "t" "spectrum" "checkerboard" "float uscale" [ 4 ]
AttributeBegin
  Material "dielectric" "float eta" [ 1.5 ]
  AreaLightSource "diffuse" "rgb L" [ 0.2 0.6 0.3 ]
  Translate -0.6 0.5 0
  Shape "sphere" "float radius" [ 0.5 ]
AttributeEnd
AttributeBegin
  Material "conductor" "float roughness" [ 0.1 ]
  AreaLightSource "diffuse" "rgb L" [ 0.5 0.5 0.5 ] "bool twosided" true
  Translate 0.6 0.5 0.5
  Shape "disk" "float radius" [ 0.4 ]
AttributeEnd
AttributeBegin
  Material "diffuse" "texture reflectance" "t"
  AreaLightSource "diffuse" "rgb L" [ 3 3 3 ]
  ReverseOrientation
  Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ -1 2 -1  1 2 -1  1 2 1  -1 2 1 ]
    "point2 uv" [ 0 0  1 0  1 1  0 1 ]
AttributeEnd
Material "diffuse"
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ]
""")

put("scene", "reflecting-light.toml", camera + """
[materials.d]
albedo = [0.5, 0.5, 0.5]

[[lights]]
type = "quad"
radiance = [2, 2, 2]
material = "d"
vertices = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]

[[lights]]
type = "sphere"
centre = [0, 0, 0.5]
radius = 0.3
power = 5
material = "d"

[[shapes]]
type = "quad"
material = "d"
vertices = [[-2, -1, -2], [2, -1, -2], [2, -1, 2], [-2, -1, 2]]
""")

put("scene", "portal.toml", camera + """
[[lights]]
type = "infinite"
radiance = [1, 1, 1]
rotate = [90, 0, 0]
portal = [[-0.5, -0.5, 2], [-0.5, 0.5, 2], [0.5, 0.5, 2], [0.5, -0.5, 2]]

[materials.d]
albedo = [0.5, 0.5, 0.5]

[[shapes]]
type = "quad"
material = "d"
vertices = [[-2, -1, -2], [2, -1, -2], [2, -1, 2], [-2, -1, 2]]
""")


# Measured BRDFs (RGL tensor files): a small isotropic one with spectra,
# and one of RGB values over a quarter of the incident azimuths.
def tensor(fields):
    head_len = 18 + sum(13 + len(n) + 8 * len(s) for n, s, _, _ in fields)
    head, body = bytearray(b"tensor_file\0\x01\x00"), bytearray()
    head += struct.pack("<I", len(fields))
    for name, shape, dtype, values in fields:
        data = bytes(values) if dtype == 1 else struct.pack(f"<{len(values)}f", *values)
        head += struct.pack("<H", len(name)) + name.encode() + struct.pack("<HBQ", len(shape), dtype, head_len + len(body))
        head += b"".join(struct.pack("<Q", n) for n in shape)
        body += data
    return bytes(head + body)


def measured(phis, colours, rgb):
    n, nt, npi = 3, 2, len(phis)
    grid = [1.0 + 0.1 * i for i in range(n * n)]
    fields = [("description", [4], 1, b"seed"), ("jacobian", [1], 1, [1]),
              ("theta_i", [nt], 10, [0.0, 1.2]), ("phi_i", [npi], 10, phis),
              ("ndf", [n, n], 10, grid), ("sigma", [n, n], 10, grid),
              ("vndf", [npi, nt, n, n], 10, grid * npi * nt),
              ("luminance", [npi, nt, n, n], 10, grid * npi * nt)]
    if not rgb:
        fields.append(("wavelengths", [colours], 10, [400.0 + 100 * i for i in range(colours)]))
    fields.append(("rgb" if rgb else "spectra", [npi, nt, colours, n, n], 10,
                   [0.5] * (npi * nt * colours * n * n)))
    return tensor(fields)


os.makedirs(os.path.join(here, "seeds", "measured"), exist_ok=True)
put("measured", "isotropic.bsdf", measured([0.0], 2, False))
put("measured", "quarter-rgb.bsdf", measured([-3.14159265, -2.35619449, -1.57079633], 3, True))
