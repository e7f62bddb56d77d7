#!/usr/bin/env bash
# What a large scene costs before its first pixel: wall time and peak
# resident memory of loading it, building the BVH and rendering a 16 x 16
# image at one sample, ours against pbrt-v4 (when PBRT is set) and against
# other builds of ours (BINS), in alternating rounds (the machine drifts).
#
# The scene, made in target/large-scene/ from ../shared/assets: the Stanford
# bunny as a binary PLY file, placed 49 times on a 7 x 7 grid by separate
# `Shape "plymesh"` directives (3.4 million triangles; both renderers make a
# mesh of each). SCENES adds pbrt-v4 files of your own (pbrt-v4-scenes'
# `crown`, say); their film is cut to 16 x 16 at one sample in a copy.
#
#   bench/large-scene.sh
#   ROUNDS=5 PBRT=path/to/pbrt BINS="old/raytracer" SCENES="path/to/crown.pbrt" bench/large-scene.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=${ROUNDS:-3}
out=$root/target/large-scene
mkdir -p "$out"
(cd "$root" && cargo build --release --quiet --bin raytracer)
bins="$root/target/release/raytracer ${BINS:-}"

python3 - "$root/../shared/assets/stanford-bunny.obj" "$out" <<'PY'
import os, struct, sys
obj, out = sys.argv[1:]
ply = os.path.join(out, "bunny.ply")
if not os.path.exists(ply):
    vs, fs = [], []
    for line in open(obj):
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            vs.append(tuple(float(x) for x in p[1:4]))
        elif p[0] == "f":
            idx = [int(x.split("/")[0]) for x in p[1:]]
            idx = [i - 1 if i > 0 else len(vs) + i for i in idx]
            fs.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vs)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(fs)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(ply + ".part", "wb") as f:
        f.write(head.encode())
        f.write(b"".join(struct.pack("<3f", *v) for v in vs))
        f.write(b"".join(struct.pack("<B3i", 3, *t) for t in fs))
    os.replace(ply + ".part", ply)
lines = ['LookAt 0 3 9  0 0.3 0  0 1 0', 'Camera "perspective" "float fov" 40',
         'Film "rgb" "integer xresolution" 16 "integer yresolution" 16 "string filename" "out.exr"',
         'Sampler "independent" "integer pixelsamples" 1', 'Integrator "path" "integer maxdepth" 5',
         'WorldBegin', 'LightSource "infinite" "rgb L" [1 1 1]',
         'Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]']
for i in range(7):
    for j in range(7):
        lines += ['AttributeBegin', f'Translate {(i - 3) * 0.25} 0 {(j - 3) * 0.25}',
                  'Scale 1.2 1.2 1.2', 'Shape "plymesh" "string filename" "bunny.ply"', 'AttributeEnd']
open(os.path.join(out, "bunnies.pbrt"), "w").write("\n".join(lines) + "\n")
PY

# A copy of each extra scene beside it, its film cut to 16 x 16 at one sample.
scenes="$out/bunnies.pbrt"
copies=()
trap 'rm -f "${copies[@]}"' EXIT
for s in ${SCENES:-}; do
    s=$(realpath "$s")
    c=$(mktemp "$(dirname "$s")/.large-scene-XXXXXX.pbrt")
    copies+=("$c")
    python3 - "$s" "$c" <<'PY'
import re, sys
src, dst = sys.argv[1:]
head, sep, tail = open(src).read().partition("WorldBegin")
for name in ("xresolution", "yresolution"):
    head = re.sub(rf'"integer {name}"\s*(\[\s*[^\]]*\]|\S+)', f'"integer {name}" [ 16 ]', head)
head = re.sub(r'"integer pixelsamples"\s*(\[\s*[^\]]*\]|\S+)', '"integer pixelsamples" [ 1 ]', head)
open(dst, "w").write(head + sep + tail)
PY
    scenes="$scenes $c"
done

printf '%-24s %-36s %8s %8s\n' scene renderer "wall s" "peak MB"
for s in $scenes; do
    name=$(basename "$s" .pbrt)
    [[ $name == .large-scene-* ]] && name=$(basename "$(dirname "$s")")
    for r in $(seq "$rounds"); do
        for b in $bins; do
            /usr/bin/time -f "%e %M" -o "$out/time" "$b" --quiet --scene "$s" --width 16 --height 16 \
                --spp 1 --integrator path -o "$out/ours.exr" 2>/dev/null
            read -r wall kb < "$out/time"
            printf '%-24s %-36s %8s %8d\n' "$name" "ours: ${b#"$root"/}" "$wall" $((kb / 1024))
        done
        if [ -n "${PBRT:-}" ]; then
            (cd "$(dirname "$s")" && /usr/bin/time -f "%e %M" -o "$out/time" "$PBRT" --quiet --spp 1 \
                --outfile "$out/pbrt.exr" "$s" >/dev/null 2>&1)
            read -r wall kb < "$out/time"
            printf '%-24s %-36s %8s %8d\n' "$name" "pbrt-v4" "$wall" $((kb / 1024))
        fi
    done
done
