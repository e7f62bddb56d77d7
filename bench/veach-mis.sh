#!/usr/bin/env bash
# Veach's MIS scene (../shared/bitterli/veach-mis) at 320 x 180 with the path
# tracer's three ways of finding direct light: shadow rays only (light),
# BSDF-sampled rays only (bsdf), and both weighted by the power heuristic
# (mis), at equal wall time. A short trial of each sets its samples per pixel
# for the budget; each render is compared against the scene's reference
# (box-filtered down, the lights' pixels and their border left out).
#
# Usage: bench/veach-mis.sh [SECONDS]     (default 20 s a render)
set -euo pipefail
cd "$(dirname "$0")/.."
budget=${1:-20}
scene=../shared/bitterli/veach-mis/scene-v4.pbrt
ref=../shared/bitterli/veach-mis/reference.exr
cargo build --release --quiet
bin=target/release/raytracer
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() { # mode spp -> seconds
    local start end
    start=$(date +%s.%N)
    "$bin" -q --scene "$scene" --integrator path --width 320 --height 180 \
        --light-sampling "$1" --spp "$2" -o "$out/$1.exr"
    end=$(date +%s.%N)
    awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }'
}
printf '%-6s %-6s %-8s %-10s %-10s\n' mode spp seconds rel_mse lum_ratio
for mode in light bsdf mis; do
    trial=$(run "$mode" 8)
    spp=$(awk -v t="$trial" -v b="$budget" 'BEGIN { s = int(8 * b / t); print (s < 1 ? 1 : s) }')
    secs=$(run "$mode" "$spp")
    read -r _ _ _ rel _ lum < <("$bin" compare "$out/$mode.exr" "$ref" --max-luminance 4)
    printf '%-6s %-6s %-8s %-10s %-10s\n' "$mode" "$spp" "$secs" "$rel" "$lum"
done
