#!/bin/bash
# Renders one frame in bands on Slurm and merges them.
#
#   [SHARED_PHOTONS=1] [CHECKPOINT=1] submit.sh BANDS [render options...]
#   submit.sh --status [OUT]     which bands are done, queued, running or failed
#   submit.sh --resubmit [OUT]   queue the failed bands again, the merge after them
#
# Queues BANDS array tasks (render-array.sbatch) and a merge job
# (merge.sbatch) that waits for all of them (--dependency=afterok). With
# SHARED_PHOTONS=1 (photon integrator), one job (photons.sbatch) first traces
# the photon map and the bands, queued after it, load it. Jobs run in the
# folder submit.sh is run from, writing logs/ there.
#
# What the jobs ask for, from the environment (unset: each .sbatch file's
# #SBATCH line, given here):
#   CPUS_PER_TASK  CPUs (and render threads) of the photon job and of each
#                  band: 8. The merge runs on one.
#   MEM            memory of every job: photons 4G, band 4G, merge 2G
#   TIME           time limit of every job: photons 00:30:00, band 01:00:00,
#                  merge 00:10:00
# Slurm's own variables (SBATCH_PARTITION, SBATCH_ACCOUNT, SBATCH_QOS, ...)
# apply as usual: submit.sh passes no partition, account or QOS.
#
# Other settings:
#   SCENE          --scene of every job (unset: the raytracer's default, or
#                  a --scene among the render options)
#   OUT            folder of the bands, the photon map and the checkpoints
#                  (parts)
#   RESULT         the merged image (render.exr)
#   SHARED_PHOTONS=1  one photon map for all the bands
#   CHECKPOINT=1   progressive renders (--integrator path, bdpt or sppm): each band
#                  keeps a checkpoint (OUT/band-K.ckpt), is submitted with
#                  --requeue --signal=TERM@120 (SBATCH_SIGNAL replaces the
#                  signal), and resumes from its checkpoint when it finds one
#
# --status and --resubmit read OUT/submission, which submit.sh writes.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
usage="usage: [SHARED_PHOTONS=1] [CHECKPOINT=1] submit.sh BANDS [render options...] | --status [OUT] | --resubmit [OUT]"

fail() {
    echo "submit.sh: $*" >&2
    exit 2
}

# The sbatch options every job gets from CPUS_PER_TASK, MEM and TIME.
requests() {
    case ${CPUS_PER_TASK:-} in
        '') ;;
        *[!0-9]* | 0) fail "CPUS_PER_TASK must be a whole number >= 1, not '$CPUS_PER_TASK'" ;;
    esac
    cpus=(${CPUS_PER_TASK:+--cpus-per-task="$CPUS_PER_TASK"})
    req=(${MEM:+--mem="$MEM"} ${TIME:+--time="$TIME"})
    band_opts=()
    if [ "${CHECKPOINT:-0}" = 1 ]; then
        band_opts=(--requeue --signal="${SBATCH_SIGNAL:-TERM@120}")
    fi
}

# sbatch --parsable prints "id" or "id;cluster".
submit() {
    local id
    id=$(sbatch --parsable "$@")
    echo "${id%%;*}"
}

# Writes OUT/submission: what --status and --resubmit need.
record() {
    local f="$OUT/submission"
    {
        echo "# Written by submit.sh; read by submit.sh --status and --resubmit."
        # -g: the file is sourced inside a function.
        declare -p dir bands args photons_job merge_job band_job \
            SCENE OUT RESULT PHOTON_MAP CHECKPOINT CPUS_PER_TASK MEM TIME | sed 's/^declare /declare -g /'
    } >"$f.tmp"
    mv "$f.tmp" "$f"
}

# Reads OUT/submission (OUT from the argument, else the environment, else parts).
load() {
    local out=${1:-${OUT:-parts}}
    [ -f "$out/submission" ] || fail "$out/submission: no submission there (give the OUT folder submit.sh printed)"
    # shellcheck disable=SC1091
    source "$out/submission"
    cd "$dir"
    export SCENE OUT RESULT PHOTON_MAP CHECKPOINT BANDS=$bands
}

# Fills state[k] for every band: done, pending, running, failed, ... and
# why[k] with the scheduler's reason or exit code.
band_states() {
    local ids id st reason code k
    declare -gA sched=()
    ids=$(printf '%s\n' "${band_job[@]%%_*}" "$photons_job" "$merge_job" | grep . | sort -u | paste -sd,)
    # Jobs the scheduler still knows (finished ones for MinJobAge, 300 s by default).
    while IFS='|' read -r id st reason code _; do
        # squeue's exit code is a wait status: the exit code times 256, or a signal.
        if [[ $code =~ ^[0-9]+$ ]] && [ "$code" -gt 0 ]; then
            if [ $((code & 127)) -gt 0 ]; then code="signal $((code & 127))"; else code=$((code >> 8)); fi
        fi
        if [ -n "$id" ]; then sched[$id]="$st|$reason|$code"; fi
    done < <(squeue -h -r --states=all -j "$ids" -O 'JobArrayID:|,State:|,Reason:|,exit_code:|' 2>/dev/null || true)
    # Older jobs, where accounting is on.
    while IFS='|' read -r id st code; do
        if [ -n "$id" ] && [ -z "${sched[$id]:-}" ]; then sched[$id]="${st%% *}||${code%%:*}"; fi
    done < <(sacct -n -X -P -j "$ids" -o JobID,State,ExitCode 2>/dev/null || true)
    # Bands waiting for a photon map whose job failed wait for good (before
    # Slurm says so, with DependencyNeverSatisfied).
    photons_failed=0
    if [ -n "$photons_job" ] && [ ! -f "$PHOTON_MAP" ]; then
        case $(job_state "$photons_job") in
            PENDING* | RUNNING* | CONFIGURING* | COMPLETING*) ;;
            *) photons_failed=1 ;;
        esac
    fi
    state=()
    why=()
    local f
    for ((k = 0; k < bands; k++)); do
        IFS='|' read -r st reason code <<<"${sched[${band_job[k]}]:-}"
        f="$OUT/band-$(printf %04d "$k")"
        if [[ $st == @(PENDING|RUNNING|COMPLETING|CONFIGURING|REQUEUED|SUSPENDED|RESIZING|SIGNALING|STAGE_OUT) ]]; then
            state[k]=${st,,}
            if [ "$reason" = DependencyNeverSatisfied ]; then
                state[k]=stuck
                why[k]="waits for a job that failed"
            elif [ "$st" = PENDING ] && [ "$photons_failed" = 1 ]; then
                state[k]=stuck
                why[k]="waits for the photon map, whose job failed"
            elif [ "$st" = PENDING ] && [ -n "$reason" ] && [ "$reason" != None ]; then
                why[k]=$reason
            fi
        elif [[ $st == @(COMPLETED|) ]] && [ -f "$f.exr" ] && [ ! -f "$f.partial.exr" ] && [ ! -f "$f.ckpt" ]; then
            # (An SPPM band with --write-every writes its image before it is
            # done; a band that finished has left no partial image or checkpoint.)
            state[k]="done"
        elif [ -z "$st" ]; then
            state[k]=failed
            why[k]="not finished, and the scheduler no longer knows job ${band_job[k]}"
        else
            state[k]=failed
            why[k]="$st, exit code ${code:-?}"
            case $st/$code in
                */130) why[k]+=" (interrupted)" ;;
                COMPLETED/0) why[k]="$st, but no image" ;;
            esac
        fi
    done
}

# One job's state as the scheduler tells it: "PENDING (Dependency)",
# "FAILED, exit code 2", or "gone" once it has forgotten the job.
job_state() {
    local st reason code
    IFS='|' read -r st reason code <<<"${sched[$1]:-}"
    case $st in
        '') echo gone ;;
        PENDING | RUNNING | CONFIGURING | COMPLETING | REQUEUED | SUSPENDED) echo "$st${reason:+ ($reason)}" | sed 's/ (None)//' ;;
        *) echo "$st${code:+, exit code $code}" ;;
    esac
}

# The merge's state: "done, FILE" once the merged image is newer than the
# submission, else what the scheduler says.
merge_state() {
    if [ -f "$RESULT" ] && [ "$RESULT" -nt "$OUT/submission" ]; then
        echo "done, $RESULT"
    else
        job_state "$merge_job"
    fi
}

# Whether the merge is done or on its way: not failed, and not waiting for
# good on bands that failed (Slurm keeps such a dependency failed even once
# the bands are requeued and done).
merge_ok() {
    case $1 in
        *DependencyNeverSatisfied*) return 1 ;;
        done* | RUNNING* | COMPLETING* | CONFIGURING* | PENDING*) return 0 ;;
        *) return 1 ;;
    esac
}

status() {
    load "$@"
    band_states
    local k n_failed=0 log ck
    echo "$bands bands in $OUT, merged into $RESULT"
    if [ -n "$photons_job" ]; then
        if [ -f "$PHOTON_MAP" ]; then
            echo "photons (job $photons_job): done, $PHOTON_MAP"
        else
            echo "photons (job $photons_job): $(job_state "$photons_job")"
            if [ "$photons_failed" = 1 ]; then
                n_failed=$((n_failed + 1))
                if [ -f logs/photons.log ]; then tail -n "${TAIL:-10}" logs/photons.log | sed 's/^/    | /'; fi
            fi
        fi
    fi
    for ((k = 0; k < bands; k++)); do
        echo "band $k (job ${band_job[k]}): ${state[k]}${why[k]:+: ${why[k]}}"
        ck="$OUT/band-$(printf %04d "$k").ckpt"
        if [ "${state[k]}" = failed ] || [ "${state[k]}" = stuck ]; then
            n_failed=$((n_failed + 1))
            if [ -f "$ck" ]; then echo "    checkpoint $ck: --resubmit resumes from it"; fi
            log="logs/band-$k.log"
            if [ -f "$log" ]; then
                echo "    $log:"
                tail -n "${TAIL:-10}" "$log" | sed 's/^/    | /'
            fi
        fi
    done
    m=$(merge_state)
    echo "merge (job $merge_job): $m"
    # A merge left waiting by failed bands is not one more failure.
    if ! merge_ok "$m" && { [[ $m != *DependencyNeverSatisfied* ]] || [ "$n_failed" = 0 ]; }; then
        n_failed=$((n_failed + 1))
        if [[ $m == *DependencyNeverSatisfied* ]]; then
            echo "    a band it waits for failed once: Slurm keeps the dependency failed even after a requeue"
        fi
        if [ -f logs/merge.log ] && [[ $m != PENDING* ]]; then tail -n "${TAIL:-10}" logs/merge.log | sed 's/^/    | /'; fi
    fi
    if [ "$n_failed" -gt 0 ]; then
        echo "$n_failed failed; once the cause is fixed, queue them again: $here/submit.sh --resubmit $OUT"
        return 1
    fi
}

resubmit() {
    load "$@"
    requests
    band_states
    local k todo=() stuck=() deps=() after=() array='' m
    for ((k = 0; k < bands; k++)); do
        case ${state[k]} in
            failed) todo+=("$k") ;;
            stuck) todo+=("$k") stuck+=("${band_job[k]}") ;;
        esac
    done
    m=$(merge_state)
    if [ ${#todo[@]} = 0 ] && merge_ok "$m"; then
        echo "nothing has failed: nothing to resubmit (merge: $m)"
        return 0
    fi
    if [ ${#stuck[@]} -gt 0 ]; then scancel "${stuck[@]}"; fi
    if [ ${#todo[@]} -gt 0 ]; then
        # A photon map that was never written is traced again first.
        if [ -n "$PHOTON_MAP" ] && [ ! -f "$PHOTON_MAP" ]; then
            if [ "$photons_failed" = 1 ]; then
                photons_job=$(submit ${cpus[@]+"${cpus[@]}"} ${req[@]+"${req[@]}"} "$here/photons.sbatch" "${args[@]}")
                echo "photons: job $photons_job"
            fi
            after=(--dependency=afterok:"$photons_job")
        fi
        array=$(submit ${after[@]+"${after[@]}"} ${cpus[@]+"${cpus[@]}"} ${req[@]+"${req[@]}"} \
            ${band_opts[@]+"${band_opts[@]}"} --array="$(IFS=,; echo "${todo[*]}")" \
            "$here/render-array.sbatch" "${args[@]}")
        for k in "${todo[@]}"; do band_job[k]=${array}_$k; done
    fi
    # The merge waits for every band not yet done: a new dependency, since
    # the old one stays failed.
    for ((k = 0; k < bands; k++)); do
        [ "${state[k]}" = "done" ] || deps+=("${band_job[k]}")
    done
    if [[ $m == PENDING* ]] && [ ${#deps[@]} -gt 0 ]; then
        scontrol update JobId="$merge_job" Dependency="afterok:$(IFS=:; echo "${deps[*]}")"
    elif ! merge_ok "$m" || [[ $m == PENDING* ]]; then
        if [[ $m == PENDING* ]]; then scancel "$merge_job"; fi
        after=()
        [ ${#deps[@]} = 0 ] || after=(--dependency="afterok:$(IFS=:; echo "${deps[*]}")")
        merge_job=$(submit ${after[@]+"${after[@]}"} ${req[@]+"${req[@]}"} "$here/merge.sbatch")
    fi
    record
    local resume=
    [ "$CHECKPOINT" != 1 ] || resume=" (resuming from their checkpoints where they have one)"
    [ -z "$array" ] || echo "bands ${todo[*]}: job $array$resume"
    echo "merge: job $merge_job${deps[*]:+, after them}"
    echo "watch: squeue -j ${array:+$array,}$merge_job -i 10    status: $here/submit.sh --status $OUT"
}

case ${1-} in
    --status)
        shift
        status "$@"
        exit
        ;;
    --resubmit)
        shift
        resubmit "$@"
        exit
        ;;
    -h | --help)
        sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
        exit 0
        ;;
esac

bands=${1-}
case $bands in
    '' | *[!0-9]*) fail "BANDS must be a whole number >= 1, not '${1-}' ($usage)" ;;
esac
if [ ${#bands} -gt 6 ] || [ "$((10#$bands))" -lt 1 ]; then
    fail "BANDS must be a whole number from 1 to 999999, not '$bands'"
fi
bands=$((10#$bands))
shift
command -v raytracer >/dev/null || fail "raytracer is not on PATH (the jobs run it from there)"
command -v sbatch >/dev/null || fail "sbatch is not on PATH: run this where Slurm jobs are submitted"
requests
args=("$@")
dir=$(pwd)
: "${SCENE:=}" "${OUT:=parts}" "${RESULT:=render.exr}" "${CHECKPOINT:=}" "${CPUS_PER_TASK:=}" "${MEM:=}" "${TIME:=}"
mkdir -p logs "$OUT"
# Absolute paths: the jobs, --status and --resubmit may run elsewhere.
OUT=$(cd "$OUT" && pwd)
[[ $RESULT == /* ]] || RESULT=$dir/$RESULT
PHOTON_MAP=
[ "${SHARED_PHOTONS:-0}" != 1 ] || PHOTON_MAP="$OUT/photons.phm"
export SCENE OUT RESULT PHOTON_MAP CHECKPOINT BANDS=$bands
# The images of this frame's bands are about to be rendered again; their
# checkpoints stay, for bands to resume from.
stale=()
for ((k = 0; k < bands; k++)); do
    stale+=("$OUT/band-$(printf %04d "$k").exr" "$OUT/band-$(printf %04d "$k").partial.exr" "logs/band-$k.log")
done
rm -f "${stale[@]}"

after=()
photons_job=
if [ -n "$PHOTON_MAP" ]; then
    photons_job=$(submit ${cpus[@]+"${cpus[@]}"} ${req[@]+"${req[@]}"} "$here/photons.sbatch" "$@")
    after=(--dependency=afterok:"$photons_job")
fi
array=$(submit ${after[@]+"${after[@]}"} ${cpus[@]+"${cpus[@]}"} ${req[@]+"${req[@]}"} \
    ${band_opts[@]+"${band_opts[@]}"} --array=0-$((bands - 1)) "$here/render-array.sbatch" "$@") || {
    [ -z "$photons_job" ] || scancel "$photons_job"
    exit 2
}
merge_job=$(submit --dependency=afterok:"$array" ${req[@]+"${req[@]}"} "$here/merge.sbatch") || {
    scancel ${photons_job:+"$photons_job"} "$array"
    exit 2
}
band_job=()
for ((k = 0; k < bands; k++)); do band_job[k]=${array}_$k; done
record

[ -z "$photons_job" ] || echo "photons: job $photons_job -> $PHOTON_MAP (logs/photons.log)"
echo "bands:   job $array, tasks 0-$((bands - 1)) -> $OUT/band-KKKK.exr (logs/band-K.log)"
echo "merge:   job $merge_job -> $RESULT (logs/merge.log)"
echo "output folder: $OUT"
echo "watch:  squeue -j ${photons_job:+$photons_job,}$array,$merge_job -i 10"
echo "status: $here/submit.sh --status $OUT"
