#!/usr/bin/env bash
# An infinite light with a portal (bench/scenes/portal.pbrt: a closed room
# lit through its window by an environment map with a sun, a post outside
# the window) rendered by pbrt-v4 itself and by us at the same size and
# sample count, compared with `raytracer compare --max-luminance 4`; then
# pbrt-v4 against itself with another seed (the figures' noise), our photon
# integrators against our path tracer, and what the portal is for: the
# path tracer's noise with and without it on the same room without the
# post (where the two agree in mean), as the error between two seeds.
#
# Usage: PBRT=path/to/pbrt [PNG_OUT=docs/portal.png] bench/portal.sh [WIDTH HEIGHT SPP]
#   (200 150 256; pbrt-v4 built as ../shared/tools/pbrt-v4/ says). Renders
#   are left in target/portal-bench/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
w=${1:-200} h=${2:-150} spp=${3:-256}
root=$(cd "$(dirname "$0")/.." && pwd)
(cd "$root" && cargo build --release --quiet --bin raytracer)
bin=$root/target/release/raytracer
out=$root/target/portal-bench
mkdir -p "$out"
png=${PNG_OUT:+$(realpath -m "$PNG_OUT")}
python3 "$root/bench/portal_sky.py" "$out/sky.pfm" 128
sed -e "s/\"integer xresolution\" \[ [0-9]* \]/\"integer xresolution\" [ $w ]/" \
    -e "s/\"integer yresolution\" \[ [0-9]* \]/\"integer yresolution\" [ $h ]/" \
    -e "s/\"integer pixelsamples\" \[ [0-9]* \]/\"integer pixelsamples\" [ $spp ]/" \
    "$root/bench/scenes/portal.pbrt" >"$out/portal.pbrt"
# The room without the post, with and without the portal.
awk '/reflectance" \[ 0.3 0.3 0.3 \]/ { exit } { print }' "$out/portal.pbrt" | sed '$d' >"$out/room.pbrt"
grep -v '"point3 portal"' "$out/room.pbrt" >"$out/room-open.pbrt"
cd "$out"
timed() {
    local start end
    start=$(date +%s.%N)
    "$@" >/dev/null
    end=$(date +%s.%N)
    awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }'
}
t_pbrt=$(timed "$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --outfile pbrt.pfm portal.pbrt)
t_ours=$(timed "$bin" -q --scene portal.pbrt -o ours.pfm)
echo "pbrt-v4 $t_pbrt s, ours (path) $t_ours s"
echo "ours against pbrt-v4: $("$bin" compare ours.pfm pbrt.pfm --max-luminance 4)"
"$PBRT" --quiet --nthreads "${PBRT_THREADS:-2}" --seed 1 --outfile pbrt-seed1.pfm portal.pbrt
echo "pbrt-v4, seed 1, against pbrt-v4: $("$bin" compare pbrt-seed1.pfm pbrt.pfm --max-luminance 4)"
for i in photon sppm; do
    t=$(timed "$bin" -q --scene portal.pbrt --integrator "$i" -o "$i.pfm")
    echo "ours ($i, $t s) against ours (path): $("$bin" compare "$i.pfm" ours.pfm --max-luminance 4)"
done
for s in room room-open; do
    t1=$(timed "$bin" -q --scene "$s.pbrt" --seed 1 -o "$s-1.pfm")
    t2=$(timed "$bin" -q --scene "$s.pbrt" --seed 2 -o "$s-2.pfm")
    echo "$s: seeds 1 and 2 ($t1 s, $t2 s): $("$bin" compare "$s-1.pfm" "$s-2.pfm" --max-luminance 4)"
done
echo "room with the portal against without: $("$bin" compare room-1.pfm room-open-1.pfm --max-luminance 4)"
if [ -n "$png" ]; then
    python3 "$root/bench/pfm.py" "$png" "$out/ours.pfm" "$out/pbrt.pfm"
fi
