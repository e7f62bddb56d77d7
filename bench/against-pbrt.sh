#!/usr/bin/env bash
# One pbrt-v4 scene rendered by pbrt-v4 itself and by us at the same size
# and sample count, with the integrator the file asks for, and the two
# compared (`raytracer compare --max-luminance 4`: mean luminance ratio
# ours / pbrt-v4, relative MSE; both renders' noise is in the latter).
#
# Usage: PBRT=path/to/pbrt bench/against-pbrt.sh SCENE.pbrt WIDTH HEIGHT SPP
#   (pbrt-v4 built as ../shared/tools/pbrt-v4/ says; PBRT_THREADS sets its
#   thread count, 2 by default). The renders are left in target/against-pbrt/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
[ $# -eq 4 ] || { echo "usage: PBRT=... $0 SCENE.pbrt WIDTH HEIGHT SPP" >&2; exit 2; }
scene=$(realpath "$1")
w=$2 h=$3 spp=$4
root=$(cd "$(dirname "$0")/.." && pwd)
(cd "$root" && cargo build --release --quiet --bin raytracer)
bin=$root/target/release/raytracer
out=$root/target/against-pbrt
mkdir -p "$out"
name=$(basename "$scene" .pbrt)
# A copy beside the scene, so that its relative paths resolve, with the
# film's size, samples and output name replaced (before WorldBegin only).
copy=$(mktemp "$(dirname "$scene")/.against-pbrt-XXXXXX.pbrt")
trap 'rm -f "$copy"' EXIT
python3 - "$scene" "$copy" "$w" "$h" "$spp" "$out/$name-pbrt.exr" <<'PY'
import re, sys
src, dst, w, h, spp, exr = sys.argv[1:]
text = open(src).read()
head, sep, tail = text.partition("WorldBegin")
def put(name, ty, value, head):
    pattern = rf'"{ty} {name}"\s*(\[\s*[^\]]*\]|\S+)'
    if re.search(pattern, head):
        return re.sub(pattern, f'"{ty} {name}" [ {value} ]', head)
    return head
head = put("xresolution", "integer", w, head)
head = put("yresolution", "integer", h, head)
if '"integer pixelsamples"' in head:
    head = put("pixelsamples", "integer", spp, head)
elif re.search(r'\bSampler\s+"[^"]*"', head):
    head = re.sub(r'(\bSampler\s+"[^"]*")', rf'\1 "integer pixelsamples" [ {spp} ]', head, count=1)
else:
    # pbrt-v4's default sampler, at the count asked for (not its default 16).
    head += f'\nSampler "zsobol" "integer pixelsamples" [ {spp} ]\n'
head = put("filename", "string", f'"{exr}"', head)
if '"integer xresolution"' not in head:
    head += f'\nFilm "rgb" "integer xresolution" [ {w} ] "integer yresolution" [ {h} ] "string filename" [ "{exr}" ]\n'
open(dst, "w").write(head + sep + tail)
PY
start=$(date +%s.%N)
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" "$copy"
mid=$(date +%s.%N)
"$bin" -q --scene "$copy" --spp "$spp" -o "$out/$name-ours.exr"
end=$(date +%s.%N)
awk -v a="$start" -v b="$mid" -v c="$end" 'BEGIN { printf "pbrt-v4 %.1f s, ours %.1f s\n", b - a, c - b }'
echo "ours against pbrt-v4: $("$bin" compare "$out/$name-ours.exr" "$out/$name-pbrt.exr" --max-luminance 4)"
