#!/bin/sh
# Does the blur conceal sparse sampling? Foveated against full sampling, each with the same DoF
# (or none), along the bundled gaze trace: mean luma PSNR in the periphery (outside r1) and over
# the whole image, from fovea-replay --vs-full, skipping the first 10 frames (history warm-up);
# samples: the foveated render's mean rays per frame over the same frames.
#   tools/measure_dof_fov.sh [OUT_DIR]   (env: BUILD=build SIZE=1280x1440 FRAMES=60 SCENE=assets/range.glb
#                                          SAMPLING=weier|liu LIU_DENSITY=0 DOFS="none weak medium strong"
#                                          DOF_SAMPLING=on|off (--dof-sampling) KAPPA= (--dof-sampling-kappa))
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
SIZE=${SIZE:-1280x1440}
FRAMES=${FRAMES:-60}
SCENE=${SCENE:-assets/range.glb}
SAMPLING=${SAMPLING:-weier}
LIU_DENSITY=${LIU_DENSITY:-0}
DOFS=${DOFS:-${PRESETS:-none weak medium strong}}
DOF_SAMPLING=${DOF_SAMPLING:-on}
OUT=${1:-out/dof-fov}
set -- --dof-sampling "$DOF_SAMPLING"
[ -n "${KAPPA:-}" ] && set -- "$@" --dof-sampling-kappa "$KAPPA"
mkdir -p "$OUT"
echo "| sampler | DoF | PSNR periphery dB | PSNR all dB | flicker periphery | samples |" > "$OUT/table.md"
echo "|---|---|---|---|---|---|" >> "$OUT/table.md"
for dof in $DOFS; do
    echo "measure_dof_fov: --sampling $SAMPLING --dof $dof" >&2
    "$BUILD/bin/fovea-replay" --scene "$SCENE" --trace assets/gaze_sweep.csv --frames "$FRAMES" --size "$SIZE" \
        --vs-full --dof "$dof" --sampling "$SAMPLING" --liu-density "$LIU_DENSITY" "$@" --quiet --out "$OUT/$dof"
    awk -F, -v d="$dof" -v s="$SAMPLING" 'NR == 1 {for (i = 1; i <= NF; i++) c[$i] = i; next}
        NR > 11 && $c["psnr_periph"] != "" {p += $c["psnr_periph"]; a += $c["psnr_all"]; f += $c["flicker_periph"];
                                            r += $c["samples"]; n++}
        END {printf "| %s | %s | %.2f | %.2f | %.4f | %.0f |\n", s, d, p / n, a / n, f / n, r / n}' \
        "$OUT/$dof/stats.csv" >> "$OUT/table.md"
done
cat "$OUT/table.md"
