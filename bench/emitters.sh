#!/usr/bin/env bash
# Area lights that reflect by their material (bench/scenes/reflecting-emitters.pbrt:
# a grey ceiling panel, a copper and a glass sphere, a textured disk and a
# textured quad seen from behind, all emitting) rendered by pbrt-v4 itself
# and by us at the same size and sample count, compared with
# `raytracer compare --max-luminance 4`; pbrt-v4 against itself with another
# seed for the noise of that figure; our other integrators against our path
# tracer (as bench/image-lights.sh does for its scenes).
#
# Usage: PBRT=path/to/pbrt bench/emitters.sh [WIDTH HEIGHT SPP]  (200 150 256)
#   Renders are left in target/reflecting-emitters-bench/.
set -euo pipefail
INTEGRATORS="bdpt photon sppm" exec "$(dirname "$0")/image-lights.sh" reflecting-emitters "$@"
