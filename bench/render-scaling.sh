#!/usr/bin/env bash
# Default render: wall time and rays per second on 1 and 2 threads, side by
# side in one run. Usage: bench/render-scaling.sh [extra render options]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
bin=target/release/raytracer
printf '%-8s %-10s %-12s\n' threads seconds Mrays/s
declare -A secs
for t in 1 2; do
    # Best of three, to keep other load on a shared machine out of the figure.
    best=""
    for _ in 1 2 3; do
        line=$("$bin" --threads "$t" -o "$out/r.png" "$@")
        s=$(sed -E 's/.*: ([0-9.]+) s, ([0-9.]+) Mrays.*/\1 \2/' <<<"$line")
        if [ -z "$best" ] || awk -v a="${s% *}" -v b="${best% *}" 'BEGIN{exit !(a<b)}'; then best=$s; fi
    done
    secs[$t]=${best% *}
    printf '%-8s %-10s %-12s\n' "$t" "${best% *}" "${best#* }"
done
awk -v a="${secs[1]}" -v b="${secs[2]}" 'BEGIN{printf "speedup 1 -> 2 threads: %.2fx\n", a/b}'
