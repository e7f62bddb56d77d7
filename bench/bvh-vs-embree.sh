#!/usr/bin/env bash
# Times our BVH, Embree 3 and the obvhs crate on the same cornell-bunny ray
# sets, single-threaded, one after the other, and prints a table with the
# ratios to Embree, the build times (Embree at quality MEDIUM and HIGH, on one
# and two threads) and the instruction set Embree's kernels use. Installs
# Embree (Debian's libembree-dev) when its header is missing. See
# BENCHMARKS.md.
#
# Usage: bench/bvh-vs-embree.sh [reps] [builds]
#   reps    timed passes over each ray set; the best is kept (default 5)
#   builds  BVH builds; the median time is kept (default 9)
#
# ROUNDS=N (default 0) then times ours and Embree (HIGH) N more times,
# alternating which goes first, and prints per ray set the median, range and
# count of the rounds' ratios ours / Embree. The two share each round's
# minute, so the machine's drift (10 to 20% within minutes here) cancels in
# the ratios, which a single run of each cannot promise.
set -euo pipefail
reps=${1:-5}
builds=${2:-9}
cd "$(dirname "$0")/.."

if [ ! -f /usr/include/embree3/rtcore.h ]; then
    sudo=""
    [ "$(id -u)" -ne 0 ] && sudo=sudo
    $sudo apt-get update
    $sudo apt-get install -y libembree-dev
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
gcc -O3 -o "$work/embree_bench" bench/embree/embree_bench.c -lembree3
cargo build --release --example bvh_rays

echo "== ours and obvhs"
target/release/examples/bvh_rays --write "$work/rays.bin" --reps "$reps" --builds "$builds" | tee "$work/out.txt"
echo "== Embree's kernels (device \"threads=1,verbose=2\")"
"$work/embree_bench" --kernels "$work/rays.bin" >"$work/kernels.txt" 2>&1 || true
# The CPU's instruction sets and the ones this Embree was compiled for (what
# verbose=1 prints), then the builder and single-ray kernel per build quality.
awk '/^ +ISA +:/ && !isa { isa = 1; sub(/^ +ISA +: */, ""); print "CPU:                    " $0 }
     /^ +Targets +:.*supported/ { sub(/^ +Targets +: */, ""); print "Embree can use:         " $0; t = 1; next }
     t { sub(/^ */, ""); print "Embree was compiled for: " $0; t = 0 }
     /^kernels quality=/ { q = substr($2, 9) }
     /^building / { print "quality " q ": builds " $2 " with " $4 }
     /intersector1 *=/ && !(q in done) { done[q] = 1; print "quality " q ": rays with " $3 }' "$work/kernels.txt"

echo "== Embree"
"$work/embree_bench" "$work/rays.bin" "$reps" "$builds" | tee -a "$work/out.txt"

echo
awk '
function field(name,   i, kv) {
    for (i = 2; i <= NF; i++) { split($i, kv, "="); if (kv[1] == name) return kv[2] }
    return ""
}
$1 == "build" {
    t = field("threads"); im = field("impl"); tris = field("triangles")
    q = field("quality")
    if (im == "ours" && t != 1) { wall["ours/all"] = field("ms"); pcpu["ours/all"] = field("process_cpu_ms"); all = t }
    else if (im == "embree") { wall[im, q, t] = field("ms"); cpu[im, q, t] = field("cpu_ms"); pcpu[im, q, t] = field("process_cpu_ms") }
    else { wall[im] = field("ms"); cpu[im] = field("cpu_ms") }
}
$1 == "result" {
    s = field("set"); im = field("impl")
    if (!(s in seen)) { seen[s] = 1; order[++n] = s }
    r[im, s] = field("mrays_per_s"); h[im, s] = field("hits")
}
END {
    printf "Rays per second (millions), single thread (thread CPU time, best of the passes);\n"
    printf "Embree at build quality HIGH, and MEDIUM in the last column:\n"
    printf "%-11s %8s %8s %8s %11s %12s %13s\n", "ray set", "ours", "Embree", "obvhs", "ours/Embree", "obvhs/Embree", "Embree MEDIUM"
    bad = 0
    for (k = 1; k <= n; k++) {
        s = order[k]
        printf "%-11s %8.2f %8.2f %8.2f %11.2f %12.2f %13.2f\n", s, r["ours", s], r["embree", s], r["obvhs", s],
            r["ours", s] / r["embree", s], r["obvhs", s] / r["embree", s], r["embree-medium", s]
        # Sanity: the same rays must find (almost) the same number of hits.
        d = h["ours", s] - h["embree", s]; if (d < 0) d = -d
        if (d > 1e-4 * h["embree", s] + 1) { printf "  hit counts disagree: ours %d, Embree %d\n", h["ours", s], h["embree", s]; bad = 1 }
        else printf "  hits: ours %d, Embree %d (MEDIUM %d), obvhs %d\n", h["ours", s], h["embree", s], h["embree-medium", s], h["obvhs", s]
    }
    printf "\nBVH build over %s triangles (median; ms wall clock / ms CPU of the building thread;\n", tris
    printf "for two threads, ms wall clock / ms CPU of all threads):\n"
    printf "  ours             %s threads: %s / %s\n", all, wall["ours/all"], pcpu["ours/all"]
    printf "  ours             1 thread:  %s / %s\n", wall["ours"], cpu["ours"]
    printf "  Embree MEDIUM    2 threads: %s / %s\n", wall["embree", "medium", 2], pcpu["embree", "medium", 2]
    printf "  Embree MEDIUM    1 thread:  %s / %s\n", wall["embree", "medium", 1], cpu["embree", "medium", 1]
    printf "  Embree HIGH      2 threads: %s / %s\n", wall["embree", "high", 2], pcpu["embree", "high", 2]
    printf "  Embree HIGH      1 thread:  %s / %s\n", wall["embree", "high", 1], cpu["embree", "high", 1]
    printf "  obvhs            1 thread:  %s / %s (medium_build)\n", wall["obvhs"], cpu["obvhs"]
    exit bad
}' "$work/out.txt"

rounds=${ROUNDS:-0}
[ "$rounds" -gt 0 ] || exit 0
echo
echo "== $rounds interleaved rounds (ours --ours-only, Embree HIGH; best of $reps passes each)"
ours() { target/release/examples/bvh_rays --ours-only --reps "$reps" --builds 1 | grep '^result'; }
embree() { "$work/embree_bench" "$work/rays.bin" "$reps" 1 | grep '^result impl=embree '; }
for i in $(seq 1 "$rounds"); do
    if [ $((i % 2)) -eq 1 ]; then
        o=$(ours); e=$(embree)
    else
        e=$(embree); o=$(ours)
    fi
    printf '%s\n%s\n' "$o" "$e" | sed "s/^result /round=$i /"
done | tee "$work/rounds.txt" | awk '{ print "  " $0 }' | grep 'set=shadow' || true
awk '
function field(name,   i, kv) {
    for (i = 2; i <= NF; i++) { split($i, kv, "="); if (kv[1] == name) return kv[2] }
    return ""
}
{ split($1, kv, "="); r[kv[2], field("impl"), field("set")] = field("mrays_per_s"); n = kv[2] > n ? kv[2] : n
  s = field("set"); if (!(s in seen)) { seen[s] = 1; order[++ns] = s } }
END {
    printf "\nours / Embree HIGH per round (%d rounds): median [min, max], rounds >= 1\n", n
    for (k = 1; k <= ns; k++) {
        s = order[k]; m = 0; wins = 0
        for (i = 1; i <= n; i++) { q[++m] = r[i, "ours", s] / r[i, "embree", s]; if (q[m] >= 1) wins++ }
        # insertion sort: a few dozen rounds at most
        for (i = 2; i <= m; i++) { x = q[i]; j = i - 1; while (j > 0 && q[j] > x) { q[j + 1] = q[j]; j-- } q[j + 1] = x }
        med = (m % 2) ? q[(m + 1) / 2] : (q[m / 2] + q[m / 2 + 1]) / 2
        printf "%-11s %.3f [%.3f, %.3f] %d of %d\n", s, med, q[1], q[m], wins, m
    }
}' "$work/rounds.txt"
