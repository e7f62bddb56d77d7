#!/usr/bin/env bash
# Error against wall time: Mitsuba 3's path tracer (llvm_ad_rgb) side by side
# with our path tracer and our photon integrators (issue 15).
#
#   bench/vs-mitsuba.sh                          # the default run: ~12 min, ~28 the first time (references)
#   CASES="cornell:256" SPP_256="16 64" SKIP_PHOTON=1 bench/vs-mitsuba.sh   # a quick look
#
# CASES            scene:size pairs [cornell:256 cornell:512 cornell-box:256]
#                  (cornell: the built-in room, exported from scenes/cornell.toml
#                  by bench/mitsuba_export.py; cornell-box: ../shared/bitterli/
#                  cornell-box, its scene-v4.pbrt for us, scene-mitsuba3.xml for Mitsuba;
#                  cornell-box-box: the same with a box pixel filter in both)
# SPP_256, SPP_512 path tracers' samples per pixel [16 64 256], [16 64 256]
# REF_SPP_CORNELL  references of cornell, rendered at 512 x 512 [512]
# REF_SPP_BOX      references of cornell-box at the case's size [1024]
# MITSUBA_K_SPP    the Mitsuba row whose K the ratios divide by [256]
# OURS_PATH_VARIANTS  our path tracer's variants, each a row at every count:
#                  options separated by spaces, variants by ";" ["": the
#                  scene's settings], e.g. ";--sampler zsobol"
# SKIP_PHOTON=1    leaves out our photon integrators
# CHECK_ONLY=1     only the reference checks (agreement, framing)
# MITSUBA_RR_DEPTH a diagnostic: Mitsuba's Russian roulette from this depth (its default 5)
# PLOT_ONLY=1      redraws PNG_OUT from CSV_OUT
# CSV_OUT, PNG_OUT [docs/vs-mitsuba.csv], [docs/vs-mitsuba.png]
# MITSUBA_VENV     the virtual environment [target/mitsuba-venv]
#
# Installs what it needs when missing: Debian's libllvm19 (Mitsuba's LLVM
# backend loads it through DRJIT_LIBLLVM_PATH) and, in a virtual environment
# under the build folder (target/mitsuba-venv), mitsuba, numpy and matplotlib
# from the Python package index. References are rendered once by each renderer
# and cached in target/vs-mitsuba/refs/ (delete them to render them again).
#
# Timing: Mitsuba in-process and warm: each measured render is preceded by a
# render at the same sample count with another seed, which compiles its
# kernels; the second is timed from mi.render() to the image in memory (the
# EXR is written outside the timing). Ours: the whole process (start, scene and
# BVH build, photon tracing, rendering, writing the EXR). Both use every core.
# The method of the error figure is in bench/vs_mitsuba.py.
set -euo pipefail
cd "$(dirname "$0")/.."
export PYTHONDONTWRITEBYTECODE=1

VENV=${MITSUBA_VENV:-target/mitsuba-venv}
MITSUBA_VERSION=${MITSUBA_VERSION:-3.9.1}

if ! dpkg -s libllvm19 >/dev/null 2>&1; then
    echo "installing libllvm19 (apt)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null
fi
DRJIT_LIBLLVM_PATH=$(dpkg -L libllvm19 | grep -E '/libLLVM[^/]*\.so[.0-9]*$' | head -n 1)
if [ -z "$DRJIT_LIBLLVM_PATH" ]; then
    echo "libllvm19 is installed but its libLLVM shared library was not found" >&2
    exit 1
fi
export DRJIT_LIBLLVM_PATH

if ! "$VENV/bin/python" -c "import mitsuba, numpy, matplotlib" 2>/dev/null; then
    echo "installing mitsuba $MITSUBA_VERSION into $VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q "mitsuba==$MITSUBA_VERSION" numpy matplotlib
fi

cargo build --release --quiet --bin raytracer
"$VENV/bin/python" -c "import mitsuba; print('mitsuba', mitsuba.__version__)"
exec "$VENV/bin/python" bench/vs_mitsuba.py
