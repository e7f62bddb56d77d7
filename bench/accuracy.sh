#!/usr/bin/env bash
# Accuracy of photon mapping on `cornell` against a path-traced reference.
#
#   bench/accuracy.sh            # 512 x 512, reference at 2048 spp
#   SIZE=128 REF_SPP=4096 bench/accuracy.sh
#
# The reference is rendered once and cached in bench/out/ (gitignored); later
# runs reuse it. For each configuration the script prints wall and CPU time and
# the error against the reference (examples/compare.rs: mean relative squared
# error, RMSE and mean luminance ratio, the light's own pixels left out), and it
# writes small PNGs of the three gather filters to docs/.
set -euo pipefail
cd "$(dirname "$0")/.."
SIZE=${SIZE:-512}
REF_SPP=${REF_SPP:-2048}
OUT=bench/out
mkdir -p "$OUT" docs
cargo build --release --quiet --bin raytracer --example compare
R=target/release/raytracer
C=target/release/examples/compare
REF=$OUT/cornell-path-${SIZE}px-${REF_SPP}spp.pfm

if [ ! -f "$REF" ]; then
    echo "rendering the path-traced reference once: $REF"
    "$R" --integrator path --spp "$REF_SPP" --width "$SIZE" --height "$SIZE" -o "$REF"
fi

# run NAME [options...]: render at SIZE, print times and errors.
run() {
    local name=$1
    shift
    local img=$OUT/$name-${SIZE}px.pfm
    local TIMEFORMAT="%R %U"
    local t
    t=$({ time "$R" --width "$SIZE" --height "$SIZE" -q -o "$img" "$@" >/dev/null; } 2>&1)
    printf "%-18s wall %7.2f s  cpu %7.2f s  %s\n" "$name" ${t% *} ${t#* } "$("$C" "$REF" "$img")" |
        tee -a "$OUT/accuracy-${SIZE}px.txt"
}

rm -f "$OUT/accuracy-${SIZE}px.txt"
echo "cornell ${SIZE}x${SIZE} against the ${REF_SPP}-spp path-traced reference"
run photon-default
run direct --integrator direct
run path-64spp --integrator path --spp 64
run path-256spp --integrator path --spp 256
for f in none normal report; do
    run "filter-$f" --gather-filter "$f"
done
run max-bounces-5 --max-bounces 5
run photons-100k --photons 100000
run photons-400k --photons 400000
run knn-100 --gather-k 100
run cone-filter --cone-filter
run final-gather-16 --final-gather 16 --ssaa 2 --photons 100000
# The reference's own noise: a path-traced image's relMSE falls as 1/spp.
awk -v spp="$REF_SPP" '/^path-64spp/ { for (i = 1; i <= NF; i++) if ($i == "relMSE") printf "reference noise floor: relMSE about %.6f (path-64spp x 64 / %d)\n", $(i + 1) * 64 / spp, spp }' "$OUT/accuracy-${SIZE}px.txt"

# Small pictures of the gather filters for the docs.
for f in none normal report; do
    "$R" --width 256 --height 256 -q --gather-filter "$f" -o "docs/photon-filter-$f.png"
done
"$R" --width 256 --height 256 -q --integrator path --spp 1024 -o docs/photon-reference-path.png
echo "wrote docs/photon-filter-{none,normal,report}.png and docs/photon-reference-path.png"
