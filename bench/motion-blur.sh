#!/usr/bin/env bash
# Motion blur against pbrt-v4 itself: bench/scenes/motion-blur.pbrt (a cube
# sliding, a gold one turning about its axis, one flying forward while it
# grows and tips, under a sphere light; pbrt-v4's ActiveTransform) rendered
# by both at the file's size and sample count with the path tracer, and
# compared: relative MSE and mean luminance ratio, ours over pbrt-v4's.
# Then bench/scenes/motion-blur-camera.pbrt: the same seen by a camera that
# turns and slides, and an instanced cube moving by its ObjectInstance; and
# bench/scenes/motion-blur-spheres.pbrt, moving spheres and a disk, by both.
# Our photon mappers and bdpt against our path tracer; pbrt-v4 against itself.
# PNG_OUT=file.png writes the first pair side by side (ours left).
#
# Usage: PBRT=path/to/pbrt [PNG_OUT=docs/motion-blur.png] bench/motion-blur.sh
#   (pbrt-v4 built as ../shared/tools/pbrt-v4/ says). Renders are left in
#   target/motion-blur/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
cd "$(dirname "$0")/.."
cargo build --release --quiet --bin raytracer
bin=target/release/raytracer
out=target/motion-blur
mkdir -p "$out"
# The camera scene twice for pbrt-v4: in its default rendering space, then in
# world space (see docs/pbrt.md, ActiveTransform: it interpolates a moving
# instance in its rendering space).
for run in "motion-blur" "motion-blur-camera" "motion-blur-camera --render-coord-sys world" "motion-blur-spheres"; do
    set -- $run
    name=$1
    shift
    scene=bench/scenes/$name.pbrt
    start=$(date +%s.%N)
    "$PBRT" --quiet --nthreads 2 "$@" --outfile "$out/$name-pbrt.pfm" "$scene"
    echo "$run: pbrt-v4 $(echo "$(date +%s.%N) - $start" | bc) s"
    if [ $# -eq 0 ]; then
        start=$(date +%s.%N)
        "$bin" -q --threads 2 --scene "$scene" -o "$out/$name-ours.pfm"
        echo "$name: ours $(echo "$(date +%s.%N) - $start" | bc) s"
    fi
    "$bin" compare "$out/$name-ours.pfm" "$out/$name-pbrt.pfm" --max-luminance 4
done
# Our photon integrators against our path tracer's render of the first
# scene: SPPM (a moment of the shutter a pass), the photon mapper (one map of
# photons at times of their own over the shutter, those on moving shapes
# kept where the shapes start). BLOCKS=1 prints each 40 x 40 block's mean
# luminance over the path tracer's.
for integrator in "sppm --passes 64 --photons 200000 --gather-radius 0.05" photon; do
    set -- $integrator
    start=$(date +%s.%N)
    "$bin" -q --threads 2 --scene bench/scenes/motion-blur.pbrt --integrator "$@" -o "$out/motion-blur-$1.pfm"
    echo "motion-blur: ours, $integrator, $(echo "$(date +%s.%N) - $start" | bc) s, against our path tracer"
    "$bin" compare "$out/motion-blur-$1.pfm" "$out/motion-blur-ours.pfm" --max-luminance 4
    if [ -n "${BLOCKS:-}" ]; then
        python3 - "$out/motion-blur-ours.pfm" "$out/motion-blur-$1.pfm" <<'PY'
import sys
sys.path.insert(0, "bench")
from pfm import load
w, h, ref = load(sys.argv[1])
_, _, img = load(sys.argv[2])
lum = lambda c: 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
B = 40
for by in range(h // B):
    ratios = []
    for bx in range(w // B):
        px = [(y * w + x) for y in range(by * B, (by + 1) * B) for x in range(bx * B, (bx + 1) * B)]
        r = sum(lum(ref[i]) for i in px)
        ratios.append(sum(lum(img[i]) for i in px) / r if r > 0 else 0.0)
    print(" ".join(f"{v:6.3f}" for v in ratios))
PY
    fi
done
# bdpt on the moving camera's scene (its light subpaths at the camera ray's
# time, light tracing's particles at times of their own) against our path
# tracer's render of it.
start=$(date +%s.%N)
"$bin" -q --threads 2 --scene bench/scenes/motion-blur-camera.pbrt --integrator bdpt --spp 64 \
    -o "$out/motion-blur-camera-bdpt.pfm"
echo "motion-blur-camera: ours, bdpt 64 spp, $(echo "$(date +%s.%N) - $start" | bc) s, against our path tracer"
"$bin" compare "$out/motion-blur-camera-bdpt.pfm" "$out/motion-blur-camera-ours.pfm" --max-luminance 4
# Both renderers' noise: pbrt-v4 against itself with another seed.
"$PBRT" --quiet --nthreads 2 --seed 2 --outfile "$out/motion-blur-pbrt-seed2.pfm" bench/scenes/motion-blur.pbrt
echo "motion-blur: pbrt-v4 seed 2 against seed 0"
"$bin" compare "$out/motion-blur-pbrt-seed2.pfm" "$out/motion-blur-pbrt.pfm" --max-luminance 4
if [ -n "${PNG_OUT:-}" ]; then
    python3 - "$out" "$PNG_OUT" <<'PY'
import sys
sys.path.insert(0, "bench")
from pfm import load, write_png
out, png = sys.argv[1], sys.argv[2]
w, h, ours = load(f"{out}/motion-blur-ours.pfm")
_, _, pbrt = load(f"{out}/motion-blur-pbrt.pfm")
write_png(png, w, h, (ours, pbrt))
print(f"wrote {png}")
PY
fi
