#!/usr/bin/env bash
# The path tracer with and without caustic photons guiding its diffuse
# bounces (`--guide-photons`), seed by seed, against a scene's reference:
# relative MSE (`compare --max-luminance 4`), mean luminance ratio and wall
# time of each render, then per setting the mean, median and range of the
# error, how many seeds reach TARGET, the mean time and K = mean relative
# MSE x mean seconds. The settings alternate within each seed, so a slow
# minute of a shared machine falls on all of them alike.
#
#   bench/guide-seeds.sh                        # veach-mis, seeds 1-16, ~6 min on 2 cores
#   SEEDS="1 2" GUIDES="0 30000 100000 300000" bench/guide-seeds.sh
#
# SCENE   [../shared/bitterli/veach-mis/scene-v4.pbrt]; REF its reference.exr
# SIZE    --width and --height [320 180]
# SPP     samples a pixel [256]
# SEEDS   [1 .. 16]
# GUIDES  caustic photons of each setting, 0 for none [0 100000]
# TARGET  relative MSE counted as reached [0.016, issue 13's for veach-mis]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${SCENE:-../shared/bitterli/veach-mis/scene-v4.pbrt}
ref=${REF:-$(dirname "$scene")/reference.exr}
read -r width height <<<"${SIZE:-320 180}"
spp=${SPP:-256}
seeds=${SEEDS:-$(seq 1 16)}
guides=${GUIDES:-0 100000}
target=${TARGET:-0.016}
cargo build --release --quiet --bin raytracer
bin=target/release/raytracer
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
results="$out/results.txt"
printf '%-6s %-8s %-8s %-10s %-8s\n' seed guide seconds rel_mse lum_ratio
for seed in $seeds; do
    for g in $guides; do
        start=$(date +%s.%N)
        "$bin" -q --scene "$scene" --integrator path --width "$width" --height "$height" \
            --spp "$spp" --seed "$seed" --guide-photons "$g" -o "$out/img.exr"
        end=$(date +%s.%N)
        secs=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')
        read -r _ _ _ rel _ lum < <("$bin" compare "$out/img.exr" "$ref" --max-luminance 4)
        printf '%-6s %-8s %-8s %-10s %-8s\n' "$seed" "$g" "$secs" "$rel" "$lum"
        echo "$g $secs $rel $lum" >>"$results"
    done
done
echo
printf '%-8s %-6s %-10s %-10s %-20s %-8s %-10s %-8s %-8s\n' \
    guide seeds mean median range "<=$target" lum_mean seconds K
for g in $guides; do
    awk -v g="$g" '$1 == g' "$results" | sort -k3 -g | awk -v g="$g" -v t="$target" '
        { s[NR] = $2; e[NR] = $3; l[NR] = $4; se += $2; ee += $3; le += $4; ok += ($3 <= t) }
        END {
            med = (NR % 2) ? e[(NR + 1) / 2] : (e[NR / 2] + e[NR / 2 + 1]) / 2
            printf "%-8s %-6d %-10.5f %-10.5f %-20s %-8d %-10.4f %-8.2f %-8.4f\n",
                g, NR, ee / NR, med, sprintf("%.4f-%.4f", e[1], e[NR]), ok, le / NR, se / NR, ee / NR * se / NR
        }'
done
