#!/usr/bin/env bash
# Instructions executed by a small path-traced render of Bitterli's
# `cornell-box` (64 x 64, 8 spp, tent filter, one thread), counted by
# callgrind: a figure that does not drift with the machine's load, for
# comparing two builds of the renderer (timings on a shared machine vary by
# 10-20% within minutes). Also prints the five functions with the most
# instructions of their own.
#
#   bench/instructions.sh                  # this checkout's release build
#   bench/instructions.sh path/to/raytracer [more options for the render]
#
# Installs valgrind (apt) when missing.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v valgrind >/dev/null; then
    echo "installing valgrind (apt)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind >/dev/null
fi
if [ $# -ge 1 ] && [ -x "$1" ]; then
    bin=$1
    shift
else
    cargo build --release --quiet --bin raytracer
    bin=target/release/raytracer
fi
scene=${SCENE:-../shared/bitterli/cornell-box/scene-v4.pbrt}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
valgrind --tool=callgrind --callgrind-out-file="$out/cg" "$bin" --quiet --scene "$scene" \
    --width 64 --height 64 --spp 8 --filter tent --integrator path --threads 1 -o "$out/img.exr" "$@" \
    2>"$out/log"
grep -E "Collected" "$out/log" | sed 's/.*Collected : /instructions: /'
callgrind_annotate "$out/cg" 2>/dev/null | grep -E '^ *[0-9,]+ +\([ 0-9.]+%\) +[^ ]' | grep -v "PROGRAM TOTALS" | head -5
