#!/usr/bin/env bash
# The Slurm workflow of docs/distributed, run as a user would on a real
# one-node Slurm on this machine, checked byte for byte against
# single-machine renders. Usage: bench/slurm-local.sh (as root)
#
# Installs slurm-wlm and munge when they are missing (Debian packages), writes
# a one-node configuration for this machine in a temporary folder (its CPUs
# and memory, proctrack/linuxproc, task/none), starts munged, slurmctld and
# slurmd unless they are already running, and stops what it started, and
# cancels its jobs, on exit. Then:
#  1. SHARED_PHOTONS=1 CPUS_PER_TASK=1 MEM=1G ./submit.sh 3 ... (photon map
#     traced once, three bands, the merge): the merged image must equal a
#     single-machine render; submit.sh's refusals are checked on the way.
#  2. CHECKPOINT=1, a progressive render (path tracer) in three bands:
#     band 1 gets `scancel --signal=TERM` mid-render, is reported failed by
#     `submit.sh --status`, and `submit.sh --resubmit` queues it again; band 0
#     is requeued by `scontrol requeue`, as a preempted job is. Both resume
#     from their checkpoints, and the merge must again equal the
#     single-machine render.
#  3. SCENE=../shared/bitterli/cornell-box/scene-v4.pbrt ./submit.sh 2 ...:
#     a pbrt-v4 scene in two bands, merged, equal to the single render.
# Exits non-zero, saying what differed, on any failure. KEEP=1 keeps the
# temporary folder (configuration, daemon logs, job logs, images).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
export PATH="$PATH:/usr/sbin:/sbin"
t0=$(date +%s)

say() { echo "== slurm-local: $*"; }
fail() {
    echo "slurm-local: FAILED: $*" >&2
    exit 1
}
elapsed() { echo "$(($(date +%s) - t0)) s"; }

# The packages: installed when missing, and a failure to install fails the run.
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null ||
    ! command -v munged >/dev/null; then
    [ "$(id -u)" = 0 ] || fail "Slurm is not installed and only root can install it (apt-get install slurm-wlm munge)"
    say "installing slurm-wlm and munge"
    export DEBIAN_FRONTEND=noninteractive
    { timeout 600 apt-get update -qq &&
        timeout 600 apt-get install -y -qq --no-install-recommends slurm-wlm munge; } </dev/null >/dev/null ||
        fail "could not install slurm-wlm and munge with apt-get"
    t0=$(date +%s) # the figure is for the test, not the download
fi

say "building the binary"
cargo build --release --quiet
tmp=$(mktemp -d)
mkdir -p "$tmp/bin"
ln -s "$repo/target/release/raytracer" "$tmp/bin/raytracer"
export PATH="$tmp/bin:$PATH"

started=() # "name pid" of the daemons this script started
child=     # a single-machine render under way
cleanup() {
    local status=$? d dir id
    set +e
    [ -z "$child" ] || kill "$child" 2>/dev/null
    # Our jobs first, so that no step outlives the daemons.
    local jobs=()
    for dir in "$tmp"/run-*; do
        [ -f "$dir/parts/submission" ] || continue
        # shellcheck disable=SC2016
        mapfile -t ids < <(bash -c 'source "$1"; printf "%s\n" $photons_job $merge_job "${band_job[@]%%_*}"' _ "$dir/parts/submission")
        jobs+=("${ids[@]}")
    done
    if [ ${#jobs[@]} -gt 0 ]; then
        scancel "${jobs[@]}" 2>/dev/null
        for _ in $(seq 20); do
            [ -z "$(squeue -h -t PD,R,CG,CF -j "$(IFS=,; echo "${jobs[*]}")" 2>/dev/null)" ] && break
            sleep 0.5
        done
    fi
    if [ "$status" != 0 ] && [ -f "$tmp/slurmctld.log" ]; then
        echo "--- slurmctld.log (last lines)" >&2
        tail -n 15 "$tmp/slurmctld.log" >&2
        echo "--- slurmd.log (last lines)" >&2
        tail -n 15 "$tmp/slurmd.log" >&2
    fi
    for ((d = ${#started[@]} - 1; d >= 0; d--)); do
        id=${started[d]#* }
        kill "$id" 2>/dev/null
        for _ in $(seq 50); do kill -0 "$id" 2>/dev/null || break; sleep 0.2; done
        kill -0 "$id" 2>/dev/null && kill -KILL "$id"
    done
    if [ "${KEEP:-0}" = 1 ]; then echo "kept $tmp"; else rm -rf "$tmp"; fi
    exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# munged: the system's, started if it is not answering.
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    [ "$(id -u)" = 0 ] || fail "munged is not running and only root can start it"
    if [ ! -s /etc/munge/munge.key ]; then
        if ! { mungekey --create --keyfile=/etc/munge/munge.key && chown munge:munge /etc/munge/munge.key &&
            chmod 400 /etc/munge/munge.key; }; then
            fail "could not create /etc/munge/munge.key"
        fi
    fi
    mkdir -p /run/munge /var/lib/munge /var/log/munge
    chown munge:munge /run/munge /var/lib/munge /var/log/munge
    # In the foreground, in the background: $! is the daemon itself.
    setpriv --reuid=munge --regid=munge --init-groups munged --foreground >"$tmp/munged.out" 2>&1 &
    started+=("munged $!")
    for _ in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
        sleep 0.2
    done
    munge -n | unmunge >/dev/null || fail "munged does not answer: $(cat "$tmp/munged.out")"
fi

# Slurm: the one already running, else ours, configured for this machine.
partition=
if pgrep -x slurmctld >/dev/null || pgrep -x slurmd >/dev/null; then
    scontrol ping 2>/dev/null | grep -q UP ||
        fail "a slurmctld or slurmd is running (pids $(pgrep -x 'slurmctld|slurmd' | paste -sd' ')) but no controller answers: stop it first"
    say "using the Slurm already running"
else
    [ "$(id -u)" = 0 ] || fail "no Slurm is running and only root can start slurmd"
    node=$(slurmd -C | grep '^NodeName=') || fail "slurmd -C did not describe this machine"
    nodename=${node#NodeName=}
    nodename=${nodename%% *}
    mkdir -p "$tmp/state" "$tmp/spool"
    export SLURM_CONF="$tmp/slurm.conf"
    cat >"$SLURM_CONF" <<EOF
ClusterName=local
SlurmctldHost=$nodename
SlurmUser=root
AuthType=auth/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
$node
PartitionName=debug Nodes=$nodename Default=YES MaxTime=INFINITE State=UP
PartitionName=farm Nodes=$nodename MaxTime=INFINITE State=UP
EOF
    slurmctld -D -i >"$tmp/slurmctld.out" 2>&1 &
    started+=("slurmctld $!")
    slurmd -D >"$tmp/slurmd.out" 2>&1 &
    started+=("slurmd $!")
    partition=farm
fi
for _ in $(seq 60); do
    sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix)' && break
    sleep 0.5
done
sinfo -h -o %t | grep -qE '^(idle|mix)' || fail "no idle Slurm node after 30 s: $(sinfo 2>&1)"
say "Slurm up ($(sinfo -h -o '%D node, %c CPUs, %m MB' | head -1)) after $(elapsed)"

# Waits up to $2 seconds for file $1; fails with the farm's status if a
# job fails meanwhile or the file never comes.
wait_for() {
    local f=$1 limit=$2 i
    for ((i = 1; i <= limit * 5; i++)); do
        [ -e "$f" ] && return 0
        if ((i % 10 == 0)) && ! ./submit.sh --status parts >status.out 2>&1; then
            cat status.out >&2
            fail "a job failed while waiting for $f"
        fi
        sleep 0.2
    done
    ./submit.sh --status parts >&2 || true
    fail "no $f after $limit s"
}

# The single-machine render, in the background so that a signal stops the
# script at once (bash runs traps only between foreground commands).
reference() {
    raytracer "$@" --quiet -o reference.exr &
    child=$!
    wait "$child"
    child=
}

# A user's copy of the scripts in a working folder.
run_dir() {
    rm -rf "$tmp/run-$1"
    cp -r "$repo/docs/distributed" "$tmp/run-$1"
    cd "$tmp/run-$1"
}

# --- 1. Shared photon map, three bands, merge.
run_dir photons
opts=(--scene cornell --width 128 --height 128 --ssaa 2 --photons 20000)
for bad in 0 -1 x3 ''; do
    set +e
    # shellcheck disable=SC2086 # '' stands for no band count at all
    msg=$(CPUS_PER_TASK=1 ./submit.sh $bad "${opts[@]}" 2>&1)
    code=$?
    set -e
    if [ "$code" != 2 ] || [ "$(wc -l <<<"$msg")" != 1 ]; then
        fail "submit.sh ${bad:-(no band count)}: exit $code, '$msg' (want one line, exit 2)"
    fi
done
set +e
msg=$(PATH=${PATH//"$tmp/bin:"/} ./submit.sh 3 "${opts[@]}" 2>&1)
code=$?
set -e
if [ "$code" != 2 ] || ! grep -q 'raytracer is not on PATH' <<<"$msg"; then
    fail "submit.sh without raytracer: exit $code, '$msg'"
fi
[ -z "$partition" ] || [ -z "$(squeue -h)" ] || fail "a refused submission queued jobs: $(squeue)"

say "1. SHARED_PHOTONS=1 CPUS_PER_TASK=1 MEM=1G ./submit.sh 3 ${opts[*]}"
SBATCH_PARTITION=$partition SHARED_PHOTONS=1 CPUS_PER_TASK=1 MEM=1G ./submit.sh 3 "${opts[@]}" | tee submit.out
grep -q '^watch: *squeue -j [0-9]*,[0-9]*,[0-9]*' submit.out || fail "submit.sh did not print the command to watch the jobs"
grep -q "^output folder: $tmp/run-photons/parts" submit.out || fail "submit.sh did not print the output folder"
if [ -n "$partition" ]; then
    # Slurm's own SBATCH_PARTITION is left alone.
    parts=$(squeue -h -t all -o %P | sort -u | paste -sd,)
    [ "$parts" = "$partition" ] || fail "jobs went to partition(s) '$parts', not SBATCH_PARTITION=$partition"
fi
reference "${opts[@]}"
wait_for render.exr 60
./submit.sh --status parts
cmp reference.exr render.exr || fail "the merged image differs from the single-machine render"
say "1. merged image == single-machine render, after $(elapsed)"

# --- 2. Checkpoints: one band interrupted and resubmitted, one requeued.
run_dir checkpoint
opts=(--scene cornell --integrator path --width 96 --height 96 --spp 1024 --checkpoint-every 0.01)
say "2. CHECKPOINT=1 CPUS_PER_TASK=1 MEM=1G ./submit.sh 3 ${opts[*]}"
CHECKPOINT=1 CPUS_PER_TASK=1 MEM=1G ./submit.sh 3 "${opts[@]}" | tee submit.out
array=$(sed -n 's/^bands: *job \([0-9]*\).*/\1/p' submit.out)
[ -n "$array" ] || fail "no array job id in submit.sh's output"
# Once a band has saved a checkpoint (after its first passes), stop it.
wait_for parts/band-0001.ckpt 60
scancel --signal=TERM "${array}_1"
wait_for parts/band-0000.ckpt 60
scontrol requeue "${array}_0"
# A requeued job waits two minutes (Slurm's cred_expire) before it may start again; not here.
for _ in $(seq 50); do
    [ "$(squeue -h -j "${array}_0" -o %T)" = PENDING ] && break
    sleep 0.2
done
scontrol update JobId="${array}_0" StartTime=now
for _ in $(seq 150); do
    st=$(squeue -h -t all -j "${array}_1" -o %T 2>/dev/null || true)
    [[ $st == @(RUNNING|COMPLETING|CONFIGURING|PENDING) ]] || break
    sleep 0.2
done
set +e
./submit.sh --status parts | tee status.out
code=${PIPESTATUS[0]}
set -e
[ "$code" = 1 ] || fail "submit.sh --status: exit $code with a failed band (want 1)"
grep -q '^band 1 .*failed: FAILED, exit code 130 (interrupted)' status.out || fail "--status does not report band 1 interrupted"
grep -q 'checkpoint .*band-0001.ckpt' status.out || fail "--status does not name band 1's checkpoint"
grep -q '| interrupted: [1-9][0-9]*/64 passes rendered' status.out || fail "--status does not show the tail of band 1's log"
[ -f parts/band-0001.partial.exr ] || fail "the interrupted band left no partial image"
./submit.sh --resubmit parts
reference "${opts[@]}"
wait_for render.exr 120
./submit.sh --status parts
for k in 0 1; do
    grep -q "interrupted: [1-9][0-9]*/64 passes" "logs/band-$k.log" || fail "band $k was not interrupted mid-render: $(cat "logs/band-$k.log")"
    grep -q "resuming from .*band-000$k.ckpt" "logs/band-$k.log" || fail "band $k did not resume from its checkpoint: $(cat "logs/band-$k.log")"
done
leftover=$(ls parts/*.ckpt parts/*.partial.exr 2>/dev/null || true)
[ -z "$leftover" ] || fail "checkpoints or partial images left after the bands finished: $leftover"
cmp reference.exr render.exr || fail "the merged image of the resumed bands differs from the single-machine render"
at() { grep -o 'interrupted: [0-9]*/64' "logs/band-$1.log" | cut -d' ' -f2; }
say "2. band 1 stopped after $(at 1) passes and resubmitted, band 0 requeued after $(at 0); both resumed; merged image == single-machine render"
# --- 3. A pbrt-v4 scene on the farm: SCENE=path/to/scene.pbrt.
pbrt=$repo/../shared/bitterli/cornell-box/scene-v4.pbrt
if [ -f "$pbrt" ]; then
    run_dir pbrt
    opts=(--width 64 --height 64 --spp 8)
    say "3. SCENE=${pbrt#"$repo/"} CPUS_PER_TASK=1 MEM=1G ./submit.sh 2 ${opts[*]}"
    SBATCH_PARTITION=$partition SCENE=$pbrt CPUS_PER_TASK=1 MEM=1G ./submit.sh 2 "${opts[@]}" >submit.out
    reference --scene "$pbrt" "${opts[@]}"
    wait_for render.exr 60
    cmp reference.exr render.exr || fail "the merged pbrt-v4 render differs from the single-machine render"
    say "3. merged image == single-machine render of the pbrt-v4 scene, after $(elapsed)"
elif [ -n "${CI:-}" ]; then
    fail "$pbrt is missing"
else
    say "3. skipped: $pbrt is missing"
fi
say "passed in $(elapsed)"
