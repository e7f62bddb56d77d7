#!/usr/bin/env bash
# The same render by an earlier commit's binary and by this tree's, side by
# side: runs alternate between the two so that other load on a shared
# machine falls on both alike; the best of N of each is reported, with their
# ratio. The images of the two are compared too (mean luminance ratio, and
# whether the bytes are the same).
#
# Usage: bench/before-after.sh REV [N] -- [render options]
#   bench/before-after.sh HEAD~5 3 -- --scene cornell
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:?usage: bench/before-after.sh REV [N] -- [render options]}
shift
n=3
if [ "${1:-}" != "--" ] && [ -n "${1:-}" ]; then n=$1; shift; fi
[ "${1:-}" = "--" ] && shift
work=$(mktemp -d)
trap 'git worktree remove --force "$work/before" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
git worktree add --detach --quiet "$work/before" "$rev"
(cd "$work/before" && CARGO_TARGET_DIR="$work/target" cargo build --release --quiet)
cargo build --release --quiet
before="$work/target/release/raytracer"
after=target/release/raytracer
best() { sort -n | head -1; }
: >"$work/b" && : >"$work/a"
for _ in $(seq "$n"); do
    for side in b a; do
        bin=$before; [ "$side" = a ] && bin=$after
        start=$(date +%s.%N)
        "$bin" -q -o "$work/$side.exr" "$@"
        end=$(date +%s.%N)
        awk -v a="$start" -v b="$end" 'BEGIN { print b - a }' >>"$work/$side"
    done
done
tb=$(best <"$work/b"); ta=$(best <"$work/a")
awk -v r="$rev" -v b="$tb" -v a="$ta" 'BEGIN { printf "before (%s): %.2f s   after: %.2f s   after/before: %.3f\n", r, b, a, a / b }'
if cmp -s "$work/b.exr" "$work/a.exr"; then
    echo "images: byte-identical"
else
    echo "images differ: $("$after" compare "$work/a.exr" "$work/b.exr")"
fi
