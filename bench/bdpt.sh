#!/usr/bin/env bash
# The bidirectional path tracer against the path tracer on a Bitterli scene,
# over several seeds: bdpt at SPP samples a pixel, then the path tracer at
# the samples a pixel that take as long (sized from bdpt's mean time and a
# short calibration render of the path tracer), each compared with the
# scene's reference by `raytracer compare --max-luminance 4` (the reference
# box-averaged by `compare` itself when it is an integer multiple of the size).
#
#   bench/bdpt.sh                                   # veach-mis, 320 x 180, 256 spp, seeds 1-4
#   SCENE=cornell-box SIZE="256 256" SPP=64 bench/bdpt.sh
#
# SCENE  a folder of ../shared/bitterli [veach-mis]
# SIZE   "W H" [320 180]
# SPP    bdpt's samples a pixel [256]
# SEEDS  [1 2 3 4]
set -euo pipefail
cd "$(dirname "$0")/.."
SCENE=${SCENE:-veach-mis}
read -r W H <<<"${SIZE:-320 180}"
SPP=${SPP:-256}
SEEDS=${SEEDS:-1 2 3 4}
dir=../shared/bitterli/$SCENE
cargo build --release --quiet --bin raytracer
rt=target/release/raytracer
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

calc() { awk "BEGIN { print $* }"; }
# Wall seconds of one render (the whole process).
render() {
    local start end
    start=$(date +%s.%N)
    "$rt" --quiet --scene "$dir/scene-v4.pbrt" --width "$W" --height "$H" "$@" >/dev/null
    end=$(date +%s.%N)
    calc "$end - $start"
}
# Relative MSE and luminance ratio of an image against the reference.
judge() {
    "$rt" compare "$1" "$dir/reference.exr" --max-luminance 4 | awk '{print $4, $6}'
}

echo "| integrator | seed | spp | seconds | rel. MSE | luminance ratio |"
echo "|---|---|---|---|---|---|"
total=0
n=0
for seed in $SEEDS; do
    s=$(render --integrator bdpt --spp "$SPP" --seed "$seed" -o "$out/bdpt-$seed.exr")
    read -r rel lum < <(judge "$out/bdpt-$seed.exr")
    printf "| bdpt | %s | %s | %.1f | %s | %s |\n" "$seed" "$SPP" "$s" "$rel" "$lum"
    total=$(calc "$total + $s")
    n=$((n + 1))
done
budget=$(calc "$total / $n")
# The path tracer's fixed part (1 spp) and per-sample time (32 spp).
t1=$(render --integrator path --spp 1 -o "$out/calib.exr")
t32=$(render --integrator path --spp 32 -o "$out/calib.exr")
per=$(calc "($t32 - $t1) / 31")
path_spp=$(calc "int(($budget - $t1) / $per + 0.5)")
[ "$path_spp" -ge 1 ] || path_spp=1
for seed in $SEEDS; do
    s=$(render --integrator path --spp "$path_spp" --seed "$seed" -o "$out/path-$seed.exr")
    read -r rel lum < <(judge "$out/path-$seed.exr")
    printf "| path | %s | %s | %.1f | %s | %s |\n" "$seed" "$path_spp" "$s" "$rel" "$lum"
done
for seed in $SEEDS; do
    s=$(render --integrator path --spp "$SPP" --seed "$seed" -o "$out/path-same-$seed.exr")
    read -r rel lum < <(judge "$out/path-same-$seed.exr")
    printf "| path | %s | %s | %.1f | %s | %s |\n" "$seed" "$SPP" "$s" "$rel" "$lum"
done
