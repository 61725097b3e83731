#!/bin/sh
# Depth-of-field quality against the thin-lens ground truth (issue 4's table): two scenes, each
# focused near and far, every built model (full sampling, so only the DoF model differs) against
# `fovea-replay --reference SPP` with the same pupil and focus; luma PSNR and SSIM from
# fovea-compare. Then foveated vs full sampling with and without DoF in the periphery.
#   tools/measure_dof.sh [OUT_DIR]     (env: BUILD=build SPP=64 SIZE=1280x1440 PUPIL=4.49)
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
SPP=${SPP:-64}
SIZE=${SIZE:-1280x1440}
PUPIL=${PUPIL:-4.49}
OUT=${1:-out/dof}
MODELS=${MODELS:-"weier hussain mantiuk konrad liu"}
R=$BUILD/bin/fovea-replay
C=$BUILD/bin/fovea-compare
mkdir -p "$OUT"
# scene name, file, near focus (m), far focus (m): the near object under the centre gaze
cases="range assets/range.glb 1.2 40
helmet assets/scenes/FlightHelmet/FlightHelmet.gltf 0.494 1000"
echo "| scene | focus | model | PSNR dB | SSIM |" > "$OUT/table.md"
echo "|---|---|---|---|---|" >> "$OUT/table.md"
echo "$cases" | while read -r name file fnear ffar; do
    for focus in "$fnear" "$ffar"; do
        tag="$name-$focus"
        # the reference is kept between runs (same SPP, size and pupil: delete OUT to redo it)
        if [ ! -f "$OUT/$tag-ref/frame_00000.png" ]; then
            echo "measure_dof: $tag: reference ($SPP lens samples per pixel)" >&2
            $R --scene "$file" --frames 1 --size "$SIZE" --quiet --reference "$SPP" --focus-m "$focus" \
                --pupil-mm "$PUPIL" --out "$OUT/$tag-ref"
        fi
        for model in none $MODELS; do
            if [ "$model" = none ]; then dof="--dof none"; else dof="--dof weak --dof-model $model"; fi
            # shellcheck disable=SC2086
            $R --scene "$file" --frames 1 --size "$SIZE" --quiet --full $dof --focus-m "$focus" \
                --pupil-mm "$PUPIL" --out "$OUT/$tag-$model"
            res=$($C "$OUT/$tag-ref/frame_00000.png" "$OUT/$tag-$model/frame_00000.png")
            psnr=$(echo "$res" | awk '/psnr_db/ {print $2}')
            ssim=$(echo "$res" | awk '/ssim/ {print $2}')
            echo "| $name | $focus m | $model | $psnr | $ssim |" >> "$OUT/table.md"
            echo "measure_dof: $tag $model: $psnr dB, SSIM $ssim" >&2
        done
    done
done
cat "$OUT/table.md"
