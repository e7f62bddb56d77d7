#!/usr/bin/env bash
# The path tracer's direct-light sampling: shadow rays only, BSDF-sampled
# rays only, and both combined by MIS, at equal samples, against a converged
# reference (cached in target/). Prints relative MSE, mean luminance ratio
# and seconds for each. The scene is `cornell` with its light grown to a
# radius of 0.35, so that BSDF sampling finds it often enough to matter.
# Usage: bench/light-sampling.sh [SPP]
set -euo pipefail
cd "$(dirname "$0")/.."
spp=${1:-16}
cargo build --release --quiet
bin=target/release/raytracer
scene=(--scene cornell --integrator path --light-radius 0.35 --width 128 --height 128)
ref=target/light-sampling-ref.exr
[ -f "$ref" ] || "$bin" -q "${scene[@]}" --spp 4096 --seed 99 -o "$ref"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf '%-6s %-10s %-10s %-8s\n' mode rel_mse lum_ratio seconds
for mode in light bsdf mis; do
    start=$(date +%s.%N)
    "$bin" -q "${scene[@]}" --spp "$spp" --light-sampling "$mode" -o "$out/$mode.exr"
    end=$(date +%s.%N)
    read -r _ _ _ rel _ lum < <("$bin" compare "$out/$mode.exr" "$ref" --max-luminance 20)
    printf '%-6s %-10s %-10s %-8s\n' "$mode" "$rel" "$lum" "$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')"
done
