#!/usr/bin/env bash
# Accuracy of photon mapping against path-traced references.
#
#   bench/accuracy.sh                      # 256 x 256, references at 4096 spp
#   SIZE=128 REF_SPP=8192 bench/accuracy.sh
#
# References are rendered once and cached in bench/out/ (gitignored); later
# runs reuse them. For each configuration the script prints wall and CPU time
# and `raytracer compare`'s figures against the reference (relative MSE, RMSE,
# mean luminance ratio), leaving out the light's own pixels (reference
# luminance above 10: the light is ~100 times brighter than the room and equal
# in every integrator). It then renders `cornell-final` (the report's preset,
# needs ../shared/assets/stanford-bunny.obj or BUNNY=path) against its own
# reference, and writes small PNGs of the three gather filters to docs/.
set -euo pipefail
cd "$(dirname "$0")/.."
SIZE=${SIZE:-256}
REF_SPP=${REF_SPP:-4096}
BUNNY=${BUNNY:-../shared/assets/stanford-bunny.obj}
OUT=bench/out
mkdir -p "$OUT" docs
cargo build --release --quiet --bin raytracer
R=target/release/raytracer
LOG=$OUT/accuracy-${SIZE}px.txt
rm -f "$LOG"

# reference SCENE [options...]: the cached path-traced reference's file name.
reference() {
    local scene=$1
    shift
    local ref=$OUT/$scene-path-${SIZE}px-${REF_SPP}spp.pfm
    if [ ! -f "$ref" ]; then
        echo "rendering the path-traced reference once: $ref" >&2
        "$R" --scene "$scene" "$@" --integrator path --spp "$REF_SPP" --width "$SIZE" --height "$SIZE" -q -o "$ref"
    fi
    echo "$ref"
}

# run REF NAME [options...]: render at SIZE, print times and errors.
run() {
    local ref=$1 name=$2
    shift 2
    local img=$OUT/$name-${SIZE}px.pfm
    local TIMEFORMAT="%R %U"
    local t
    t=$({ time "$R" --width "$SIZE" --height "$SIZE" -q -o "$img" "$@" >/dev/null; } 2>&1)
    printf "%-22s wall %7.2f s  cpu %7.2f s  %s\n" "$name" ${t% *} ${t#* } \
        "$("$R" compare "$img" "$ref" --max-luminance 10)" | tee -a "$LOG"
}

REF=$(reference cornell)
echo "cornell ${SIZE}x${SIZE} against the ${REF_SPP}-spp path-traced reference"
run "$REF" photon-default
run "$REF" no-precompute --precompute-irradiance false
run "$REF" 200k-r0.1-no-precompute --photons 200000 --gather-radius 0.1 --precompute-irradiance false
run "$REF" 200k-r0.1 --photons 200000 --gather-radius 0.1
run "$REF" direct --integrator direct
run "$REF" path-64spp --integrator path --spp 64
run "$REF" path-256spp --integrator path --spp 256
for f in none normal report; do
    run "$REF" "filter-$f" --gather-filter "$f"
done
run "$REF" max-bounces-5 --max-bounces 5
run "$REF" photons-400k-r0.07 --photons 400000 --gather-radius 0.07
run "$REF" photons-2m-r0.05 --photons 2000000 --gather-radius 0.05
run "$REF" knn-100 --gather-k 100 --precompute-irradiance false
run "$REF" cone-filter --cone-filter
run "$REF" final-gather-16 --final-gather 16 --ssaa 2 --photons 100000
# The reference's own noise: a path-traced image's relMSE falls as 1/spp.
awk -v spp="$REF_SPP" '/^path-64spp/ { for (i = 1; i <= NF; i++) if ($i == "rel_mse") printf "reference noise floor: rel_mse about %.6f (path-64spp x 64 / %d)\n", $(i + 1) * 64 / spp, spp }' "$LOG"

if [ -f "$BUNNY" ]; then
    FREF=$(reference cornell-final --mesh "$BUNNY")
    echo "cornell-final ${SIZE}x${SIZE} against its ${REF_SPP}-spp path-traced reference"
    run "$FREF" final-preset --scene cornell-final --mesh "$BUNNY"
    for f in none normal; do
        run "$FREF" "final-filter-$f" --scene cornell-final --mesh "$BUNNY" --gather-filter "$f"
    done
    run "$FREF" final-path-64spp --scene cornell-final --mesh "$BUNNY" --integrator path --spp 64
else
    echo "skipping cornell-final: $BUNNY not found (set BUNNY=path/to/bunny.obj)"
fi

# Small pictures of the gather filters for the docs.
for f in none normal report; do
    "$R" --width 256 --height 256 -q --gather-filter "$f" -o "docs/photon-filter-$f.png"
done
"$R" --width 256 --height 256 -q --integrator path --spp 1024 -o docs/photon-reference-path.png
echo "wrote docs/photon-filter-{none,normal,report}.png and docs/photon-reference-path.png"
