#!/usr/bin/env bash
# Choosing the light of each shadow ray: by power, uniformly, or through the
# light tree (pbrt-v4's `bvh`, the default of pbrt-v4 scenes). Each scene is
# rendered by our path tracer with each light sampler at several sample
# counts, in alternating rounds, and compared with a converged render of its
# own (made once with the tree, cached in target/light-sampler/): seconds
# (the whole process), relative MSE and mean luminance ratio
# (`raytracer compare --max-luminance 4`), and K = relative MSE x seconds
# (lower is better at equal time).
#
#   bench/light-sampler.sh
#   ROUNDS=3 SPPS="16 64 256" REF_SPP=4096 SCENES="a.pbrt b.pbrt" bench/light-sampler.sh
#
# SCENES defaults to bench/scenes/many-lights.pbrt (60 ceiling lamps) and
# ../shared/bitterli's cornell-box and veach-mis; the Bitterli scenes are
# rendered at 256 x 256 and 320 x 180 as bench/bitterli.sh renders them,
# other scenes at their file's size. With PBRT set to a pbrt-v4 binary, each
# scene is also rendered by pbrt-v4 at the first count with the file's light
# sampler, for its seconds and its mean luminance against our reference.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=${ROUNDS:-2}
spps=${SPPS:-16 64 256}
ref_spp=${REF_SPP:-4096}
samplers=${SAMPLERS:-power uniform bvh}
out=$root/target/light-sampler
mkdir -p "$out"
(cd "$root" && cargo build --release --quiet --bin raytracer)
bin=$root/target/release/raytracer
shared=$root/../shared/bitterli
scenes=${SCENES:-"$root/bench/scenes/many-lights.pbrt $shared/cornell-box/scene-v4.pbrt $shared/veach-mis/scene-v4.pbrt"}

size_of() {
    case "$1" in
        */cornell-box/*) echo "--width 256 --height 256" ;;
        */veach-mis/*) echo "--width 320 --height 180" ;;
        *) echo "" ;;
    esac
}
name_of() {
    case "$1" in
        */scene-v4.pbrt) basename "$(dirname "$1")" ;;
        *) basename "$1" .pbrt ;;
    esac
}

printf '%-14s %-8s %6s %8s %10s %8s %10s\n' scene sampler spp seconds rel_mse lum K
for s in $scenes; do
    name=$(name_of "$s")
    size=$(size_of "$s")
    ref=$out/$name-ref-$ref_spp.exr
    if [ ! -f "$ref" ]; then
        echo "$name: rendering the reference once ($ref_spp spp, the tree)" >&2
        # shellcheck disable=SC2086
        "$bin" -q --scene "$s" $size --integrator path --spp "$ref_spp" --light-sampler bvh --seed 1000 -o "$ref.part.exr"
        mv "$ref.part.exr" "$ref"
    fi
    for r in $(seq "$rounds"); do
        for spp in $spps; do
            for ls in $samplers; do
                img=$out/$name-$ls-$spp.exr
                start=$(date +%s.%N)
                # shellcheck disable=SC2086
                "$bin" -q --scene "$s" $size --integrator path --spp "$spp" --light-sampler "$ls" --seed "$r" -o "$img"
                end=$(date +%s.%N)
                read -r _ _ _ rel _ lum < <("$bin" compare "$img" "$ref" --max-luminance 4)
                awk -v n="$name" -v l="$ls" -v spp="$spp" -v a="$start" -v b="$end" -v rel="$rel" -v lum="$lum" \
                    'BEGIN { t = b - a; printf "%-14s %-8s %6d %8.2f %10.6f %8.4f %10.6f\n", n, l, spp, t, rel, lum, rel * t }'
            done
        done
    done
    if [ -n "${PBRT:-}" ]; then
        first=${spps%% *}
        w=$(grep -o '"integer xresolution" *\[* *[0-9]*' "$s" | grep -o '[0-9]*$' || true)
        h=$(grep -o '"integer yresolution" *\[* *[0-9]*' "$s" | grep -o '[0-9]*$' || true)
        case "$s" in */cornell-box/*) w=256 h=256 ;; */veach-mis/*) w=320 h=180 ;; esac
        pimg=$out/$name-pbrt-$first.exr
        start=$(date +%s.%N)
        PBRT=$PBRT "$root/../shared/tools/pbrt-v4/render.sh" "$s" "$pimg" "$w" "$h" "$first" >/dev/null 2>&1
        end=$(date +%s.%N)
        read -r _ _ _ rel _ lum < <("$bin" compare "$pimg" "$ref" --max-luminance 4)
        awk -v n="$name" -v spp="$first" -v a="$start" -v b="$end" -v rel="$rel" -v lum="$lum" \
            'BEGIN { t = b - a; printf "%-14s %-8s %6d %8.2f %10.6f %8.4f %10.6f\n", n, "pbrt-v4", spp, t, rel, lum, rel * t }'
    fi
done
