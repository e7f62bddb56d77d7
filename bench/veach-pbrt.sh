#!/usr/bin/env bash
# veach-mis's path-tracer target (issue 13: relative MSE <= 0.016 at 256 spp,
# 320 x 180) measured on pbrt-v4's own path tracer beside ours, seed by seed:
# the same file (its film cut to 320 x 180 in a copy, nothing else changed),
# the same sample count, each image against the shipped reference with
# `compare --max-luminance 4`.
#
# Usage: PBRT=path/to/pbrt bench/veach-pbrt.sh [SEEDS]   (default "1 2 3 4 5 6 7 8")
#   (pbrt-v4 built as ../shared/tools/pbrt-v4/ says)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
seeds=${1:-1 2 3 4 5 6 7 8}
dir=../shared/bitterli/veach-mis
ref=$dir/reference.exr
cargo build --release --quiet
bin=target/release/raytracer
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# The scene has no meshes or images, so the copy needs nothing beside it.
sed -e 's/"integer yresolution" \[ 720 \]/"integer yresolution" [ 180 ]/' \
    -e 's/"integer xresolution" \[ 1280 \]/"integer xresolution" [ 320 ]/' \
    "$dir/scene-v4.pbrt" >"$out/scene.pbrt"
grep -q '"integer xresolution" \[ 320 \]' "$out/scene.pbrt" || { echo "could not resize the film" >&2; exit 1; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
printf '%-9s %-5s %-8s %-10s %-10s\n' renderer seed seconds rel_mse lum_ratio
for s in $seeds; do
    t0=$(date +%s.%N)
    "$PBRT" --quiet --nthreads 2 --spp 256 --seed "$s" --outfile "$out/pbrt.exr" "$out/scene.pbrt"
    t1=$(date +%s.%N)
    read -r _ _ _ rel _ lum < <("$bin" compare "$out/pbrt.exr" "$ref" --max-luminance 4)
    printf '%-9s %-5s %-8s %-10s %-10s\n' pbrt-v4 "$s" "$(secs "$t0" "$t1")" "$rel" "$lum"
    t0=$(date +%s.%N)
    "$bin" -q --scene "$dir/scene-v4.pbrt" --integrator path --spp 256 --width 320 --height 180 \
        --seed "$s" -o "$out/ours.exr"
    t1=$(date +%s.%N)
    read -r _ _ _ rel _ lum < <("$bin" compare "$out/ours.exr" "$ref" --max-luminance 4)
    printf '%-9s %-5s %-8s %-10s %-10s\n' ours "$s" "$(secs "$t0" "$t1")" "$rel" "$lum"
done
