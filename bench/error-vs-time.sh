#!/usr/bin/env bash
# Error versus wall time of the path tracer, the photon mapper (its default
# settings) and SPPM on cornell, cornell-bunny and cornell-specular.
#
#   bench/error-vs-time.sh                  # 128 x 128, budgets x 1
#   SIZE=256 SCALE=4 bench/error-vs-time.sh # bigger images, 4x the budgets
#
# SIZE     image side in pixels [128]
# SCALE    multiplies every budget: path spp, photon counts, SPPM passes [1]
# REF_SPP  samples per pixel of each of the two reference halves [4096]
# SCENES   the scenes [cornell cornell-bunny cornell-specular]
#
# The reference is the path tracer at REF_SPP samples per pixel with two seeds
# (two independent halves), rendered once and cached in bench/out/ (gitignored).
# A reference has noise of its own, which adds to any error measured against
# it: with halves A and B, E[relMSE(X, A)] = e(X) + v(A) and
# E[relMSE(A, B)] = v(A) + v(B), so the error of X is estimated without the
# reference's share as (relMSE(X, A) + relMSE(X, B)) / 2 - relMSE(A, B) / 2
# (column rel_mse; rel_mse_raw is against A alone). On cornell-specular the path
# tracer finds the caustic only when a bounce happens to hit the light through
# the glass, so its reference is the noisiest.
#
# Wall time is the whole process (scene and BVH build, photon tracing,
# rendering), on all cores. Results go to bench/out/error-vs-time-SIZE.csv and
# docs/error-vs-time.csv, the plot to docs/error-vs-time.png (needs python3 with
# matplotlib: pip install matplotlib; without it only the CSV is written).
# cornell-bunny needs ../shared/assets/stanford-bunny.obj and is skipped, with a
# message, when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
SIZE=${SIZE:-128}
SCALE=${SCALE:-1}
REF_SPP=${REF_SPP:-4096}
SCENES=${SCENES:-cornell cornell-bunny cornell-specular}
BUNNY=../shared/assets/stanford-bunny.obj
OUT=bench/out
mkdir -p "$OUT" docs
cargo build --release --quiet --bin raytracer
R=target/release/raytracer
CSV=$OUT/error-vs-time-${SIZE}.csv
echo "scene,integrator,budget,seconds,rel_mse,rel_mse_raw,luminance_ratio" >"$CSV"

# field NAME LINE: the value after NAME in a `raytracer compare` line.
field() {
    echo "$2" | tr -s ' ' '\n' | grep -A1 -x "$1" | tail -n 1
}

for scene in $SCENES; do
    mesh=()
    if [ "$scene" = cornell-bunny ]; then
        if [ ! -f "$BUNNY" ]; then
            echo "skipping cornell-bunny: $BUNNY not found"
            continue
        fi
        mesh=(--mesh "$BUNNY")
    fi
    common=(--scene "$scene" "${mesh[@]}" --width "$SIZE" --height "$SIZE" -q)
    refs=()
    for seed in 1 2; do
        ref=$OUT/ref-$scene-${SIZE}px-${REF_SPP}spp-seed$seed.exr
        if [ ! -f "$ref" ]; then
            echo "rendering the reference once: $ref"
            "$R" "${common[@]}" --integrator path --spp "$REF_SPP" --seed "$seed" -o "$ref"
        fi
        refs+=("$ref")
    done
    ref_noise=$(field rel_mse "$("$R" compare "${refs[0]}" "${refs[1]}")")
    echo "$scene: relMSE between the reference halves $ref_noise"

    # run INTEGRATOR BUDGET [options...]: render, time, compare, append to the CSV.
    run() {
        local integrator=$1 budget=$2
        shift 2
        local img=$OUT/evt-$scene-$integrator-$budget-${SIZE}px.exr
        local t0 t1
        t0=$(date +%s.%N)
        "$R" "${common[@]}" --integrator "$integrator" -o "$img" "$@"
        t1=$(date +%s.%N)
        local a b
        a=$("$R" compare "$img" "${refs[0]}")
        b=$("$R" compare "$img" "${refs[1]}")
        local line
        line=$(awk -v t0="$t0" -v t1="$t1" -v a="$(field rel_mse "$a")" -v b="$(field rel_mse "$b")" \
            -v n="$ref_noise" -v l="$(field luminance_ratio "$a")" \
            -v s="$scene" -v i="$integrator" -v g="$budget" \
            'BEGIN { printf "%s,%s,%s,%.3f,%.6g,%.6g,%s", s, i, g, t1 - t0, (a + b) / 2 - n / 2, a, l }')
        echo "$line" | tee -a "$CSV"
    }

    for spp in 4 16 64 256 1024; do
        run path "$((spp * SCALE))spp" --spp "$((spp * SCALE))"
    done
    # The photon mapper at its default settings (the scene's presets) is the
    # middle point; a quarter and four times the photons and camera samples around it.
    for k in 1 2 4; do
        photons=$((50000 * k * k * SCALE))
        run photon "${photons}ph-ssaa$((2 * k))" --photons "$photons" --ssaa $((2 * k))
    done
    run photon default
    for passes in 4 16 64 256; do
        run sppm "$((passes * SCALE))passes" --passes "$((passes * SCALE))" --photons 50000
    done
done
cp "$CSV" docs/error-vs-time.csv
if python3 -c "import matplotlib" 2>/dev/null; then
    python3 bench/plot-error-vs-time.py docs/error-vs-time.csv docs/error-vs-time.png
else
    echo "matplotlib not found (pip install matplotlib): no plot, the CSV is in docs/error-vs-time.csv"
fi
