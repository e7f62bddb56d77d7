#!/usr/bin/env bash
# pbrt-v4's procedural textures and texture mappings (bench/scenes/
# textures.pbrt) rendered by pbrt-v4 itself and by us at the same size and
# sample count, compared with `raytracer compare --max-luminance 4`.
#
# pbrt-v4 shows a `dots` texture's "inside" outside the dots and its
# "outside" inside them: its `DotsTexture::Create` passes them to a
# constructor that takes them the other way round. We follow the
# parameters' names (pbrt-v3 and the file format's documentation), so the
# script prints two figures: ours against pbrt-v4 on the file as it is, and
# ours, with the two exchanged in our copy, against the same pbrt-v4 render
# (the rest of the picture being the same); then pbrt-v4 against itself
# with another seed, the noise of both figures.
#
# PNG_OUT=file.png writes ours (the file as it is) and pbrt-v4's side by side.
#
# Usage: PBRT=path/to/pbrt [PNG_OUT=docs/textures.png] bench/textures.sh [WIDTH HEIGHT SPP]
#   (400 400 256; pbrt-v4 built as ../shared/tools/pbrt-v4/ says). Renders
#   are left in target/textures-bench/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
w=${1:-400} h=${2:-400} spp=${3:-256}
root=$(cd "$(dirname "$0")/.." && pwd)
(cd "$root" && cargo build --release --quiet --bin raytracer)
bin=$root/target/release/raytracer
out=$root/target/textures-bench
mkdir -p "$out"
scene=$root/bench/scenes/textures.pbrt
# Copies beside the scene, so that its image resolves: one at the size and
# count asked for, one with the dots' two textures exchanged.
copy=$(mktemp "$root/bench/scenes/.textures-XXXXXX.pbrt")
swapped=$(mktemp "$root/bench/scenes/.textures-swapped-XXXXXX.pbrt")
trap 'rm -f "$copy" "$swapped"' EXIT
sed -e "s/\"integer xresolution\" \[ [0-9]* \]/\"integer xresolution\" [ $w ]/" \
    -e "s/\"integer yresolution\" \[ [0-9]* \]/\"integer yresolution\" [ $h ]/" \
    -e "s/\"integer pixelsamples\" \[ [0-9]* \]/\"integer pixelsamples\" [ $spp ]/" "$scene" >"$copy"
sed -e 's/"texture inside"/"texture OUTSIDE"/; s/"texture outside"/"texture inside"/; s/"texture OUTSIDE"/"texture outside"/' \
    "$copy" >"$swapped"
start=$(date +%s.%N)
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --outfile "$out/pbrt.pfm" "$copy"
mid=$(date +%s.%N)
"$bin" -q --scene "$copy" -o "$out/ours.pfm"
end=$(date +%s.%N)
"$bin" -q --scene "$swapped" -o "$out/ours-dots-swapped.pfm"
awk -v a="$start" -v b="$mid" -v c="$end" 'BEGIN { printf "pbrt-v4 %.1f s, ours %.1f s\n", b - a, c - b }'
echo "ours against pbrt-v4: $("$bin" compare "$out/ours.pfm" "$out/pbrt.pfm" --max-luminance 4)"
echo "ours, dots exchanged, against pbrt-v4: $("$bin" compare "$out/ours-dots-swapped.pfm" "$out/pbrt.pfm" --max-luminance 4)"
# The noise of the figures: pbrt-v4 against itself with another seed.
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --seed 1 --outfile "$out/pbrt-seed1.pfm" "$copy"
echo "pbrt-v4, seed 1, against pbrt-v4: $("$bin" compare "$out/pbrt-seed1.pfm" "$out/pbrt.pfm" --max-luminance 4)"
if [ -n "${PNG_OUT:-}" ]; then
    python3 "$root/bench/pfm.py" "$PNG_OUT" "$out/ours.pfm" "$out/pbrt.pfm"
fi
