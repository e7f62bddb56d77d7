#!/bin/bash
# Usage: submit.sh BANDS [render options...]
# Queues BANDS array tasks and a merge job that waits for all of them.
set -euo pipefail
bands=${1:?usage: submit.sh BANDS [render options...]}
shift
mkdir -p logs
array=$(sbatch --parsable --array=0-$((bands - 1)) render-array.sbatch "$@")
sbatch --dependency=afterok:"$array" merge.sbatch
