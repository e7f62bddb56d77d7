#!/usr/bin/env bash
# pbrt-v4's realistic camera (`Camera "realistic"`, rays traced through a
# lens prescription) against pbrt-v4 itself: Bitterli's `cornell-box` seen
# through a lens (and, as the baseline of the two renderers' colour
# conversions, through its own pinhole), and a white sky seen through the
# lens alone (the lens' radiometry: cos^4 fall-off, vignetting, the stop),
# each rendered by both at the same size and samples and compared by
# bench/against-pbrt.sh (`raytracer compare --max-luminance 4`).
#
# Usage: PBRT=path/to/pbrt bench/realistic.sh [WIDTH HEIGHT SPP]  (192 128 256)
#   LENS=file.dat uses that prescription (pbrt-v4's format: radius,
#   thickness, eta, aperture in mm a row, scene side first) instead of the
#   landscape lens below; APERTURE (mm, 8) and FOCUS (m, 5.5) set the stop
#   and the focus, ISO the film's sensitivity for the box (100: a lens'
#   picture is dim). Scenes go to target/realistic-bench/, renders to
#   target/against-pbrt/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
w=${1:-192} h=${2:-128} spp=${3:-256}
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/target/realistic-bench
mkdir -p "$out"
if [ -n "${LENS:-}" ]; then
    cp "$LENS" "$out/lens.dat"
else
    # A landscape lens: the stop 8 mm before a meniscus of crown glass and
    # a second, weaker element behind it (about 50 mm); its edges vignette.
    cat > "$out/lens.dat" <<'DAT'
# radius  thickness  eta  aperture (mm), scene side first
0        8.0   0      12.0
-60.0    4.0   1.52   22.0
-22.0    1.0   1      24.0
80.0     3.0   1.62   24.0
-400.0   40.0  1      24.0
DAT
fi
cb=$root/../shared/bitterli/cornell-box/scene-v4.pbrt
camera="Camera \"realistic\" \"string lensfile\" \"lens.dat\" \"float aperturediameter\" ${APERTURE:-8} \"float focusdistance\" ${FOCUS:-5.5}"
# The cornell box with its own camera and with the lens; meshes are inline.
sed 's|^Camera .*|Camera "perspective" "float fov" [ 19.5 ]|' "$cb" > "$out/pinhole.pbrt"
sed -e "s|^Camera .*|$camera|" -e "s|^Film \"rgb\"|Film \"rgb\" \"float iso\" [ ${ISO:-100} ]|" "$cb" > "$out/lens.pbrt"
cat > "$out/sky.pbrt" <<PBRT
LookAt 0 0 0  0 0 1  0 1 0
Sampler "sobol" "integer pixelsamples" [ 64 ]
PixelFilter "box"
Film "rgb" "integer xresolution" [ 96 ] "integer yresolution" [ 64 ] "string filename" [ "sky.exr" ]
$camera
WorldBegin
LightSource "infinite" "rgb L" [ 1 1 1 ]
PBRT
for s in pinhole lens sky; do
    echo "== $s"
    "$root/bench/against-pbrt.sh" "$out/$s.pbrt" "$w" "$h" "$spp"
done
