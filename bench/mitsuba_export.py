#!/usr/bin/env python3
"""Exports one of our TOML scenes (docs/scene-format.md) to a Mitsuba 3 scene.

    python3 bench/mitsuba_export.py scenes/cornell.toml OUT_DIR

Writes OUT_DIR/scene.xml and one PLY mesh per material (OUT_DIR/meshes/).
The XML takes Mitsuba's usual parameters: $spp, $resx, $resy (load it with
mi.load_file(path, resx=..., resy=..., spp=...)).

The conventions carried over (checked by bench/vs-mitsuba.sh, which compares
the two renderers' converged images):
- camera: pinhole at `position` looking at `look_at`, vertical field of view
  `fov_y` (fov_axis "y"); Mitsuba's look_at gives image right = forward x up,
  which is also ours (docs/scene-format.md), so `up` is passed as it is;
- pixel filter: box (Mitsuba's box has radius 0.5, the pixel's area), as
  our default; other filters map to tent (radius 1) and gaussian (stddev 0.5);
- materials: two-sided Lambertian with the linear RGB albedo;
- a sphere light of total power Phi: a sphere shape with an area emitter of
  radiance Phi / (pi * area) (src/light.rs), and a black BSDF (ours reflects
  nothing);
- triangles: flat-shaded (face normals), grouped per material.
Anything else (meshes, mirrors, glass, point or triangle lights) is refused.
"""
import math
import os
import sys
import tomllib


def fmt(v):
    return ", ".join(repr(float(x)) for x in v)


def write_ply(path, tris):
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"element vertex {3 * len(tris)}\n")
        f.write("property float x\nproperty float y\nproperty float z\n")
        f.write(f"element face {len(tris)}\n")
        f.write("property list uchar int vertex_indices\nend_header\n")
        for t in tris:
            for v in t:
                f.write(" ".join(repr(float(c)) for c in v) + "\n")
        for i in range(len(tris)):
            f.write(f"3 {3 * i} {3 * i + 1} {3 * i + 2}\n")


def export(toml_path, out_dir):
    with open(toml_path, "rb") as f:
        scene = tomllib.load(f)
    cam = scene["camera"]
    settings = scene.get("settings", {})
    rfilter = {"box": "box", "tent": "tent", "gaussian": "gaussian"}[settings.get("filter", "box")]

    tris = {}
    for shape in scene.get("shapes", []):
        if shape.get("type") != "triangle":
            sys.exit(f"{toml_path}: shape type {shape.get('type')!r} is not exported")
        tris.setdefault(shape["material"], []).append(shape["vertices"])

    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    out = ['<scene version="3.0.0">']
    out.append('\t<default name="spp" value="64"/>')
    out.append(f'\t<default name="resx" value="{cam.get("width", 512)}"/>')
    out.append(f'\t<default name="resy" value="{cam.get("height", 512)}"/>')
    out.append('\t<integrator type="path"><integer name="max_depth" value="-1"/></integrator>')
    up = cam.get("up", [0, -1, 0])
    out.append('\t<sensor type="perspective">')
    out.append(f'\t\t<float name="fov" value="{float(cam["fov_y"])!r}"/>')
    out.append('\t\t<string name="fov_axis" value="y"/>')
    out.append('\t\t<transform name="to_world">')
    out.append(
        f'\t\t\t<lookat origin="{fmt(cam["position"])}" target="{fmt(cam["look_at"])}" up="{fmt(up)}"/>'
    )
    out.append("\t\t</transform>")
    out.append('\t\t<sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>')
    out.append('\t\t<film type="hdrfilm">')
    out.append('\t\t\t<integer name="width" value="$resx"/>')
    out.append('\t\t\t<integer name="height" value="$resy"/>')
    out.append('\t\t\t<string name="pixel_format" value="rgb"/>')
    out.append(f'\t\t\t<rfilter type="{rfilter}"/>')
    out.append("\t\t</film>")
    out.append("\t</sensor>")

    for name, mat in scene.get("materials", {}).items():
        if mat.get("type") != "diffuse":
            sys.exit(f"{toml_path}: material {name!r} of type {mat.get('type')!r} is not exported")
        out.append(f'\t<bsdf type="twosided" id="{name}">')
        out.append(f'\t\t<bsdf type="diffuse"><rgb name="reflectance" value="{fmt(mat["albedo"])}"/></bsdf>')
        out.append("\t</bsdf>")
    out.append('\t<bsdf type="diffuse" id="__black"><rgb name="reflectance" value="0, 0, 0"/></bsdf>')

    for name, ts in tris.items():
        rel = f"meshes/{name}.ply"
        write_ply(os.path.join(out_dir, rel), ts)
        out.append('\t<shape type="ply">')
        out.append(f'\t\t<string name="filename" value="{rel}"/>')
        out.append('\t\t<boolean name="face_normals" value="true"/>')
        out.append(f'\t\t<ref id="{name}"/>')
        out.append("\t</shape>")

    for light in scene.get("lights", []):
        if light.get("type") != "sphere":
            sys.exit(f"{toml_path}: light type {light.get('type')!r} is not exported")
        r = float(light["radius"])
        area = 4 * math.pi * r * r
        colour = light.get("colour", [1, 1, 1])
        power = light["power"]
        power = [power * c for c in colour] if not isinstance(power, list) else power
        radiance = [p / (math.pi * area) for p in power]
        out.append('\t<shape type="sphere">')
        out.append(f'\t\t<point name="center" value="{fmt(light["centre"])}"/>')
        out.append(f'\t\t<float name="radius" value="{r!r}"/>')
        out.append('\t\t<ref id="__black"/>')
        out.append(f'\t\t<emitter type="area"><rgb name="radiance" value="{fmt(radiance)}"/></emitter>')
        out.append("\t</shape>")
    out.append("</scene>")
    path = os.path.join(out_dir, "scene.xml")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return path


if __name__ == "__main__":
    print(export(sys.argv[1], sys.argv[2]))
