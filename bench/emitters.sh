#!/usr/bin/env bash
# Area lights that reflect by their material (bench/scenes/reflecting-emitters.pbrt:
# a grey ceiling panel, a copper and a glass sphere, a textured disk and a
# textured quad seen from behind, all emitting) rendered by pbrt-v4 itself
# and by us at the same size and sample count, compared with
# `raytracer compare --max-luminance 4`; pbrt-v4 against itself with another
# seed for the noise of that figure; our other integrators against our path
# tracer.
#
# Usage: PBRT=path/to/pbrt bench/emitters.sh [WIDTH HEIGHT SPP]  (200 150 256)
#   Renders are left in target/emitters-bench/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
w=${1:-200} h=${2:-150} spp=${3:-256}
root=$(cd "$(dirname "$0")/.." && pwd)
(cd "$root" && cargo build --release --quiet --bin raytracer)
bin=$root/target/release/raytracer
out=$root/target/emitters-bench
scene=reflecting-emitters
mkdir -p "$out"
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
for i in bdpt photon sppm; do
    "$bin" -q --scene "$scene.pbrt" --integrator $i -o $i.pfm
    echo "ours ($i) against ours (path): $("$bin" compare $i.pfm ours.pfm --max-luminance 4)"
done
