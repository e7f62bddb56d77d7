#!/usr/bin/env bash
# Dispersion against pbrt-v4 (a spectral renderer): scenes/dispersion.pbrt,
# an SF11 glass ball before a checkerboard under a uniform sky, 256 x 256,
# 1024 samples a pixel, rendered by ours with the glass's dispersion and with
# one index (SF11's at 550 nm), and twice by pbrt-v4 with two seeds (its own
# noise), each compared with pbrt-v4's first render; ours twice as well.
#
# Usage: PBRT=path/to/pbrt bench/dispersion.sh
#   (pbrt-v4 built as ../shared/tools/pbrt-v4/ says; its renders are cached
#   in target/dispersion/)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
cargo build --release --quiet --bin raytracer
bin=$PWD/target/release/raytracer
out=target/dispersion
mkdir -p "$out"
scene=scenes/dispersion.pbrt
sed 's/"spectrum eta" "glass-F11"/"float eta" 1.79115/' "$scene" >"$out/one-index.pbrt"
for seed in 0 7; do
    if [ ! -f "$out/pbrt-$seed.exr" ]; then
        sed "s|\"dispersion.exr\"|\"pbrt-$seed.exr\"|" "$scene" >"$out/pbrt-$seed.pbrt"
        (cd "$out" && "$PBRT" --quiet --seed "$seed" "pbrt-$seed.pbrt")
    fi
done
"$bin" -q --scene "$scene" -o "$out/ours.exr"
"$bin" -q --scene "$scene" --seed 5 -o "$out/ours-seed5.exr"
"$bin" -q --scene "$out/one-index.pbrt" -o "$out/ours-one-index.exr"
ref=$out/pbrt-0.exr
for img in pbrt-7 ours ours-seed5 ours-one-index; do
    printf '%-16s against pbrt-0: %s\n' "$img" "$("$bin" compare "$out/$img.exr" "$ref")"
done
printf '%-16s against ours:   %s\n' ours-seed5 "$("$bin" compare "$out/ours-seed5.exr" "$out/ours.exr")"
