#!/usr/bin/env bash
# pbrt-v4's named camera sensors, ours against pbrt-v4 itself: Bitterli's
# cornell-box at 128 x 128, 256 spp, each camera beside the CIE observer
# balanced at the same temperature, once with the file's saturated orange
# light (rgb 17 12 4) and once with a white one (rgb 12 12 12). Prints the
# mean of each channel (the light's pixels, luminance >= 4, left out) as
# ratios: camera / observer in each renderer, and ours / pbrt-v4 for each.
#
# Usage: PBRT=path/to/pbrt bench/sensors.sh
#   (pbrt-v4 built as ../shared/tools/pbrt-v4/ says)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${PBRT:?set PBRT to a pbrt-v4 binary}"
cargo build --release --quiet
bin=$PWD/target/release/raytracer
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
scene=../shared/bitterli/cornell-box/scene-v4.pbrt
# name|Film parameters; pairs are (camera, observer at its temperature).
variants=(
    'cie|'
    'canon_eos_100d|"string sensor" "canon_eos_100d"'
    'cie3200|"float whitebalance" [ 3200 ]'
    'canon_eos_100d@3200|"string sensor" "canon_eos_100d" "float whitebalance" [ 3200 ]'
    'cie5000|"float whitebalance" [ 5000 ]'
    'nikon_d850@5000|"string sensor" "nikon_d850" "float whitebalance" [ 5000 ]'
)
for light in orange white; do
    for v in "${variants[@]}"; do
        name=${v%%|*} params=${v#*|}
        file=$out/$light-$name.pbrt
        sed -e "s/\"integer yresolution\" \[ 1024 \] \"integer xresolution\" \[ 1024 \]/\"integer yresolution\" [ 128 ] \"integer xresolution\" [ 128 ] $params/" \
            "$scene" >"$file"
        [ "$light" = white ] && sed -i 's/"rgb L" \[ 17 12 4 \]/"rgb L" [ 12 12 12 ]/' "$file"
        grep -q 'xresolution" \[ 128 \]' "$file" || { echo "could not edit the film" >&2; exit 1; }
        "$PBRT" --quiet --nthreads 2 --spp 256 --outfile "$out/$light-$name-pbrt.pfm" "$file"
        "$bin" -q --scene "$file" --integrator path --spp 256 -o "$out/$light-$name-ours.pfm"
    done
done
python3 - "$out" <<'PY'
import struct, sys
out = sys.argv[1]
def means(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        fmt = "<" if scale < 0 else ">"
        data = struct.unpack(f"{fmt}{w * h * 3}f", f.read(w * h * 12))
    sums, n = [0.0, 0.0, 0.0], 0
    for i in range(w * h):
        r, g, b = data[3 * i:3 * i + 3]
        if 0.2126 * r + 0.7152 * g + 0.0722 * b < 4:
            sums[0] += r; sums[1] += g; sums[2] += b; n += 1
    return [s / n for s in sums]
ratio = lambda a, b: " ".join(f"{x / y:.4f}" for x, y in zip(a, b))
pairs = [("canon_eos_100d", "cie"), ("canon_eos_100d@3200", "cie3200"), ("nikon_d850@5000", "cie5000")]
for light in ("orange", "white"):
    m = {}
    for cam, obs in pairs:
        for n in (cam, obs):
            for r in ("pbrt", "ours"):
                m[n, r] = means(f"{out}/{light}-{n}-{r}.pfm")
    print(f"light {light}: mean R G B ratios")
    for cam, obs in pairs:
        print(f"  {cam} / {obs}: pbrt-v4 {ratio(m[cam, 'pbrt'], m[obs, 'pbrt'])}, ours {ratio(m[cam, 'ours'], m[obs, 'ours'])}")
    for cam, obs in pairs:
        print(f"  ours / pbrt-v4, {cam}: {ratio(m[cam, 'ours'], m[cam, 'pbrt'])}; "
              f"the observer in its place: {ratio(m[obs, 'ours'], m[cam, 'pbrt'])}")
PY
