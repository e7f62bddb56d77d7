#!/usr/bin/env bash
# pbrt-v4's lights that read an image (bench/scenes/goniometric.pbrt: a
# turned light with a two-lobed intensity image in a closed room;
# bench/scenes/projection.pbrt: a slide cast on a wall;
# bench/scenes/area-image.pbrt: area lights with an emission image, a
# mirrored screen and a ceiling triangle set by `power`;
# bench/scenes/area-image-shapes.pbrt: the same image on a sphere and a
# disk) rendered by pbrt-v4
# itself and by us at the same size and sample count, compared with
# `raytracer compare --max-luminance 4`; pbrt-v4 against itself with another
# seed for the noise of that figure; our photon map against our path tracer.
#
# Usage: PBRT=path/to/pbrt bench/image-lights.sh goniometric|projection|area-image|area-image-shapes [WIDTH HEIGHT SPP]
#   (200 150 256). Renders are left in target/<scene>-bench/. Another scene
#   of bench/scenes that needs no generated image may be named too;
#   INTEGRATORS lists ours to compare with our path tracer ("photon").
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
scene=${1:?goniometric, projection, area-image or area-image-shapes}
w=${2:-200} h=${3:-150} spp=${4:-256}
root=$(cd "$(dirname "$0")/.." && pwd)
(cd "$root" && cargo build --release --quiet --bin raytracer)
bin=$root/target/release/raytracer
out=$root/target/$scene-bench
mkdir -p "$out"
case $scene in
goniometric) python3 "$root/bench/goniometric_map.py" "$out/gonio.pfm" 64 ;;
projection) python3 "$root/bench/projection_slide.py" "$out/slide.pfm" ;;
area-image | area-image-shapes) python3 "$root/bench/area_image.py" "$out/screen.png" ;;
*) [ -f "$root/bench/scenes/$scene.pbrt" ] || { echo "unknown scene $scene" >&2; exit 2; } ;;
esac
sed -e "s/\"integer xresolution\" \[ [0-9]* \]/\"integer xresolution\" [ $w ]/" \
    -e "s/\"integer yresolution\" \[ [0-9]* \]/\"integer yresolution\" [ $h ]/" \
    -e "s/\"integer pixelsamples\" \[ [0-9]* \]/\"integer pixelsamples\" [ $spp ]/" \
    "$root/bench/scenes/$scene.pbrt" >"$out/$scene.pbrt"
cd "$out"
start=$(date +%s.%N)
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --outfile pbrt.pfm "$scene.pbrt"
mid=$(date +%s.%N)
"$bin" -q --scene "$scene.pbrt" -o ours.pfm
end=$(date +%s.%N)
awk -v a="$start" -v b="$mid" -v c="$end" 'BEGIN { printf "pbrt-v4 %.1f s, ours %.1f s\n", b - a, c - b }'
echo "ours against pbrt-v4: $("$bin" compare ours.pfm pbrt.pfm --max-luminance 4)"
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --seed 1 --outfile pbrt-seed1.pfm "$scene.pbrt"
echo "pbrt-v4, seed 1, against pbrt-v4: $("$bin" compare pbrt-seed1.pfm pbrt.pfm --max-luminance 4)"
for i in ${INTEGRATORS:-photon}; do
    "$bin" -q --scene "$scene.pbrt" --integrator "$i" -o "$i.pfm"
    echo "ours ($i) against ours (path): $("$bin" compare "$i.pfm" ours.pfm --max-luminance 4)"
done
