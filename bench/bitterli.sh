#!/usr/bin/env bash
# Bitterli's three pbrt-v4 scenes (../shared/bitterli/) against their reference
# images: the path tracer (plain, and guided by caustic photons), and our
# photon integrators and bidirectional path tracer at the plain path tracer's
# wall time (issue 13, "A bench").
#
#   bench/bitterli.sh                           # all three scenes, ~10 min on 2 cores
#   SCENES=cornell-box PATH_SPP=64 WRITE_DOCS=0 bench/bitterli.sh   # a quick look
#
# SCENES         [cornell-box water-caustic veach-mis]; sizes: cornell-box and
#                water-caustic 256 x 256, veach-mis 320 x 180 (half the
#                references' sizes over again, so the references are box-averaged 2 x 2)
# PATH_SPP       the path tracer's samples a pixel, whose wall time is the
#                budget of the other integrators [256]
# GUIDE_PHOTONS  caustic photons guiding the path tracer's second row [100000]
# PHOTONS        photons of the photon integrator (precomputed irradiance) [1000000]
# SPPM_PHOTONS   photons per SPPM pass [200000]
# MAX_LUMINANCE  `compare --max-luminance` [4]
# FILTER         box, tent or gaussian for every render [each file's own]
# WRITE_DOCS=0   prints only: no table in BENCHMARKS.md, no docs/bitterli-*.png
#
# A scene the renderer refuses (today veach-mis: rough conductors) is reported
# with the renderer's message, and the bench goes on. The table goes into
# BENCHMARKS.md between the bitterli-bench marker comments (replaced on each
# run), the pictures (ours | reference | error) into docs/bitterli-SCENE.png.
# Needs python3; numpy, matplotlib and OpenEXR are installed into a virtual
# environment under the build folder (target/bench-venv) when missing.
# The method is described at the top of bench/bitterli.py.
set -euo pipefail
cd "$(dirname "$0")/.."
export PYTHONDONTWRITEBYTECODE=1

VENV=${BENCH_VENV:-target/bench-venv}
if ! "$VENV/bin/python" -c "import numpy, matplotlib, OpenEXR" 2>/dev/null; then
    echo "installing numpy, matplotlib and OpenEXR into $VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q numpy matplotlib OpenEXR
fi
cargo build --release --quiet --bin raytracer
exec "$VENV/bin/python" bench/bitterli.py
