#!/bin/bash
# Usage: [SHARED_PHOTONS=1] submit.sh BANDS [render options...]
# Queues BANDS array tasks and a merge job that waits for all of them. With
# SHARED_PHOTONS=1 (photon integrator), one job first traces the photon map
# and the bands, queued after it, load it.
set -euo pipefail
bands=${1:?usage: [SHARED_PHOTONS=1] submit.sh BANDS [render options...]}
shift
mkdir -p logs
after=()
if [ "${SHARED_PHOTONS:-0}" = 1 ]; then
    export PHOTON_MAP="${OUT:-parts}/photons.phm"
    photons=$(sbatch --parsable photons.sbatch "$@")
    after=(--dependency=afterok:"$photons")
fi
array=$(sbatch --parsable ${after[@]+"${after[@]}"} --array=0-$((bands - 1)) render-array.sbatch "$@")
sbatch --dependency=afterok:"$array" merge.sbatch
