#!/usr/bin/env bash
# pbrt-v4's goniometric light (bench/scenes/goniometric.pbrt: a turned
# light with a two-lobed image in a closed room) rendered by pbrt-v4 itself
# and by us at the same size and sample count, compared with `raytracer
# compare --max-luminance 4`; pbrt-v4 against itself with another seed for
# the noise of that figure; our photon map against our path tracer.
#
# Usage: PBRT=path/to/pbrt bench/goniometric.sh [WIDTH HEIGHT SPP]
#   (200 150 256). Renders are left in target/goniometric-bench/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
w=${1:-200} h=${2:-150} spp=${3:-256}
root=$(cd "$(dirname "$0")/.." && pwd)
(cd "$root" && cargo build --release --quiet --bin raytracer)
bin=$root/target/release/raytracer
out=$root/target/goniometric-bench
mkdir -p "$out"
python3 "$root/bench/goniometric_map.py" "$out/gonio.pfm" 64
sed -e "s/\"integer xresolution\" \[ [0-9]* \]/\"integer xresolution\" [ $w ]/" \
    -e "s/\"integer yresolution\" \[ [0-9]* \]/\"integer yresolution\" [ $h ]/" \
    -e "s/\"integer pixelsamples\" \[ [0-9]* \]/\"integer pixelsamples\" [ $spp ]/" \
    "$root/bench/scenes/goniometric.pbrt" >"$out/goniometric.pbrt"
cd "$out"
start=$(date +%s.%N)
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --outfile pbrt.pfm goniometric.pbrt
mid=$(date +%s.%N)
"$bin" -q --scene goniometric.pbrt -o ours.pfm
end=$(date +%s.%N)
awk -v a="$start" -v b="$mid" -v c="$end" 'BEGIN { printf "pbrt-v4 %.1f s, ours %.1f s\n", b - a, c - b }'
echo "ours against pbrt-v4: $("$bin" compare ours.pfm pbrt.pfm --max-luminance 4)"
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --seed 1 --outfile pbrt-seed1.pfm goniometric.pbrt
echo "pbrt-v4, seed 1, against pbrt-v4: $("$bin" compare pbrt-seed1.pfm pbrt.pfm --max-luminance 4)"
"$bin" -q --scene goniometric.pbrt --integrator photon -o photon.pfm
echo "ours (photon) against ours (path): $("$bin" compare photon.pfm ours.pfm --max-luminance 4)"
