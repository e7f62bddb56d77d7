#!/usr/bin/env bash
# pbrt-v4's measured BSDF (`Material "measured"`, RGL .bsdf tensor files):
# bench/scenes/measured.pbrt, two spheres reading a synthetic GGX file that
# bench/measured-bsdf.py writes (alpha 0.3, reflectance 0.2 at 400 nm to
# 0.9 at 700 nm) and a rough conductor of the same alpha between them,
# rendered by pbrt-v4 itself and by us at the same size and sample count and
# compared by bench/against-pbrt.sh (`raytracer compare --max-luminance 4`).
# The file and a copy of the scene beside it go to target/measured-bench/,
# not into bench/scenes/.
#
# Usage: PBRT=path/to/pbrt bench/measured.sh [WIDTH HEIGHT SPP]  (200 150 256)
#   MEASURED_ARGS passes options to bench/measured-bsdf.py (e.g.
#   "--alpha 0.15 --res 64"); PYTHON names a python3 with numpy (found by
#   itself otherwise). Renders are left in target/against-pbrt/.
set -euo pipefail
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
w=${1:-200} h=${2:-150} spp=${3:-256}
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/target/measured-bench
mkdir -p "$out"
py=${PYTHON:-}
if [ -z "$py" ]; then
    for p in python3 /usr/bin/python3; do
        if "$p" -c 'import numpy' 2>/dev/null; then py=$p; break; fi
    done
    [ -n "$py" ] || { echo "$0: no python3 with numpy (set PYTHON)" >&2; exit 2; }
fi
# shellcheck disable=SC2086
"$py" "$root/bench/measured-bsdf.py" "$out/measured.bsdf" ${MEASURED_ARGS:-}
cp "$root/bench/scenes/measured.pbrt" "$out/measured.pbrt"
if ! "$root/bench/against-pbrt.sh" "$out/measured.pbrt" "$w" "$h" "$spp"; then
    echo "$0: bench/against-pbrt.sh failed (until we read Material \"measured\", our side does);" \
        "pbrt-v4's render, if any: target/against-pbrt/measured-pbrt.exr" >&2
    exit 1
fi
