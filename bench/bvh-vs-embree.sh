#!/usr/bin/env bash
# Times our BVH, Embree 3 and the obvhs crate on the same cornell-bunny ray
# sets, single-threaded, one after the other, and prints a table with the
# ratios to Embree. Installs Embree (Debian's libembree-dev) when its header
# is missing. See BENCHMARKS.md.
#
# Usage: bench/bvh-vs-embree.sh [reps] [builds]
#   reps    timed passes over each ray set; the best is kept (default 5)
#   builds  BVH builds; the median time is kept (default 9)
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
    if (im == "ours" && t != 1) { wall["ours/all"] = field("ms"); all = t }
    else { wall[im] = field("ms"); cpu[im] = field("cpu_ms") }
}
$1 == "result" {
    s = field("set"); im = field("impl")
    if (!(s in seen)) { seen[s] = 1; order[++n] = s }
    r[im, s] = field("mrays_per_s"); h[im, s] = field("hits")
}
END {
    printf "Rays per second, single thread (thread CPU time, best of the passes):\n"
    printf "%-11s %12s %12s %12s %11s %12s\n", "ray set", "ours Mray/s", "Embree", "obvhs", "ours/Embree", "obvhs/Embree"
    bad = 0
    for (k = 1; k <= n; k++) {
        s = order[k]
        printf "%-11s %12.2f %12.2f %12.2f %11.2f %12.2f\n", s, r["ours", s], r["embree", s], r["obvhs", s],
            r["ours", s] / r["embree", s], r["obvhs", s] / r["embree", s]
        # Sanity: the same rays must find (almost) the same number of hits.
        d = h["ours", s] - h["embree", s]; if (d < 0) d = -d
        if (d > 1e-4 * h["embree", s] + 1) { printf "  hit counts disagree: ours %d, Embree %d\n", h["ours", s], h["embree", s]; bad = 1 }
        else printf "  hits: ours %d, Embree %d, obvhs %d\n", h["ours", s], h["embree", s], h["obvhs", s]
    }
    printf "\nBVH build over %s triangles (median; ms wall clock / ms CPU of the building thread):\n", tris
    printf "  ours     %s threads: %s\n", all, wall["ours/all"]
    printf "  ours     1 thread:  %s / %s\n", wall["ours"], cpu["ours"]
    printf "  Embree   1 thread:  %s / %s (RTC_BUILD_QUALITY_HIGH)\n", wall["embree"], cpu["embree"]
    printf "  obvhs    1 thread:  %s / %s (medium_build)\n", wall["obvhs"], cpu["obvhs"]
    exit bad
}' "$work/out.txt"
