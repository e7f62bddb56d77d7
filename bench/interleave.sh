#!/usr/bin/env bash
# Times two or more builds of the renderer against each other: a path-traced
# render of Bitterli's `cornell-box` (one thread, 192 x 192, 16 spp, tent by
# default), each binary in turn, ROUNDS times, and prints each binary's best
# and mean seconds. Interleaving shares the machine's drift (10 to 20% within
# minutes here) between the binaries. See BENCHMARKS.md.
#
# Usage: ROUNDS=6 bench/interleave.sh path/to/raytracer-a path/to/raytracer-b ...
#   SCENE    the scene [../shared/bitterli/cornell-box/scene-v4.pbrt]
#   THREADS  worker threads [1]; "all" for every core
#   SIZE     width and height [192]
#   SPP      samples per pixel [16]
#   WALL=1   wall-clock seconds of the whole process instead of user seconds
#            (what the pass and tile scheduling of a many-thread render costs)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${ROUNDS:-6}
scene=${SCENE:-../shared/bitterli/cornell-box/scene-v4.pbrt}
size=${SIZE:-192}
threads=()
[ "${THREADS:-1}" = all ] || threads=(--threads "${THREADS:-1}")
field=%U
[ $# -ge 2 ] || { echo "usage: ROUNDS=N $0 BINARY BINARY..." >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for _ in $(seq 1 "$rounds"); do
    for i in $(seq 1 $#); do
        bin=${!i}
        args=(--quiet --scene "$scene" --width "$size" --height "$size"
            --spp "${SPP:-16}" --filter tent --integrator path "${threads[@]}" -o "$out/img.exr")
        if [ "${WALL:-0}" = 1 ]; then
            # In milliseconds: time(1)'s hundredths are too coarse for a
            # render of a third of a second.
            start=$(date +%s%N)
            "$bin" "${args[@]}"
            echo "$i $(( ($(date +%s%N) - start) / 1000 ))e-6" >>"$out/times"
        else
            /usr/bin/time -f "$field" -o "$out/t" "$bin" "${args[@]}"
            echo "$i $(cat "$out/t")" >>"$out/times"
        fi
    done
done
for i in $(seq 1 $#); do
    awk -v i="$i" -v name="${!i}" '$1 == i { n++; s += $2; if (n == 1 || $2 < m) m = $2 }
        END { printf "%-40s best %.4f s, mean %.4f s (%d rounds)\n", name, m, s / n, n }' "$out/times"
done
