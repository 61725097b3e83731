#!/bin/sh
# Anti-aliasing in the fovea (issue 17 item 5): a still view (gaze at the image centre, head at
# the scene's default viewpoint, no DoF) rendered FRAMES frames with --fovea-aa on and off,
# against the supersampled reference (`fovea-replay --reference SPP --dof none`: SPP pinhole rays
# spread over each pixel, the same shading). Prints the luma PSNR (fovea-compare) in the disc of
# DISC_R pixels around the gaze for every frame, and a table of frames 1 and FRAMES (1-based).
#   tools/measure_fovea_aa.sh [OUT_DIR]   (env: BUILD=build SIZE=1280x1440 FRAMES=16 SPP=64 DISC_R=75
#                                          SCENES="assets/range.glb <shared>/FlightHelmet.gltf"
#                                          EXTRA= more fovea-replay flags for both runs)
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
SIZE=${SIZE:-1280x1440}
FRAMES=${FRAMES:-16}
SPP=${SPP:-64}
DISC_R=${DISC_R:-75}
SHARED=${SHARED:-../shared}
SCENES=${SCENES:-assets/range.glb $SHARED/assets/scenes/FlightHelmet/FlightHelmet.gltf}
EXTRA=${EXTRA:-}
OUT=${1:-out/fovea-aa}
R=$BUILD/bin/fovea-replay
C=$BUILD/bin/fovea-compare
W=${SIZE%x*} H=${SIZE#*x}
# the gaze pixel at the image centre (fv_gaze_px: pixel centre coordinates of gaze 0.5)
CX=$(awk -v w="$W" 'BEGIN {printf "%.1f", int(0.5 * w) + 0.5}')
CY=$(awk -v h="$H" 'BEGIN {printf "%.1f", int(0.5 * h) + 0.5}')
mkdir -p "$OUT"
TABLE="$OUT/table.md"
echo "| scene | fovea-aa | PSNR frame 1 dB | PSNR frame $FRAMES dB | gain dB |" >"$TABLE"
echo "|---|---|---|---|---|" >>"$TABLE"
for scene in $SCENES; do
    name=$(basename "$scene" | sed 's/\.[^.]*$//')
    d="$OUT/$name"
    mkdir -p "$d"
    if [ ! -e "$d/ref/frame_00000.png" ]; then # kept between runs: the reference is the slow part
        echo "measure_fovea_aa: $name: reference, $SPP rays per pixel" >&2
        $R --scene "$scene" --frames 1 --size "$SIZE" --dof none --reference "$SPP" --quiet --out "$d/ref"
    fi
    for aa in on off; do
        echo "measure_fovea_aa: $name: --fovea-aa $aa, $FRAMES frames" >&2
        # shellcheck disable=SC2086
        $R --scene "$scene" --frames "$FRAMES" --size "$SIZE" --dof none --fovea-aa "$aa" $EXTRA --quiet --out "$d/$aa"
        : >"$d/psnr_$aa.txt"
        f=0
        while [ "$f" -lt "$FRAMES" ]; do
            p=$($C "$d/ref/frame_00000.png" "$(printf '%s/%s/frame_%05d.png' "$d" "$aa" "$f")" \
                --fovea "$CX,$CY,$DISC_R" | awk '$1 == "psnr_db" {print $2}')
            echo "$((f + 1)) $p" >>"$d/psnr_$aa.txt"
            f=$((f + 1))
        done
        awk -v s="$name" -v a="$aa" -v n="$FRAMES" '$1 == 1 {p1 = $2} $1 == n {pn = $2}
            END {printf "| %s | %s | %.2f | %.2f | %+.2f |\n", s, a, p1, pn, pn - p1}' "$d/psnr_$aa.txt" >>"$TABLE"
        echo "$name --fovea-aa $aa: disc PSNR per frame: $(awk '{printf "%s ", $2}' "$d/psnr_$aa.txt")" >&2
    done
done
cat "$TABLE"
