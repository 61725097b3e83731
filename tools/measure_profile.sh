#!/bin/sh
# The measurements of docs/bench-2026-11-22-profile.md: the per-stage table of the range scene and
# FlightHelmet at 1280x1440, foveated and full, 1 and 2 threads (with DoF on, so that every
# post-processing stage has a roofline figure), the kernel speed-ups, pmin / size / r0 sweeps, a
# trace, then the charts. Each JSON carries the load average when it ran.
#   tools/measure_profile.sh [OUT_DIR]     (default out/profile; BIN=build/bin,)
set -eu
OUT=${1:-out/profile}
BIN=${BIN:-build/bin}
HELMET=assets/scenes/FlightHelmet/FlightHelmet.gltf
FR=${FRAMES:-10}
mkdir -p "$OUT"
uptime | tee "$OUT/uptime-start.txt"
$BIN/fovea-bench --kernels --kernel-reps 7 --json "$OUT/kernels.json" | tee "$OUT/kernels.txt"
for s in range helmet; do
    if [ $s = range ]; then scene=assets/range.glb; else scene=$HELMET; fi
    [ -f "$scene" ] || { echo "measure_profile: $scene missing, skipped"; continue; }
    $BIN/fovea-bench --scene "$scene" --mode both --frames "$FR" --warmup 2 --dof weak --sweep threads=1..2 \
        --json "$OUT/$s.json" | tee "$OUT/$s.txt"
done
$BIN/fovea-bench --scene assets/range.glb --mode foveated --frames 5 --warmup 2 --dof weak \
    --sweep pmin=0.05,0.1,0.2,0.4 --sweep size=640x720,960x1080,1280x1440 --sweep r0=5,10,15 \
    --json "$OUT/range-sweeps.json" | tee "$OUT/range-sweeps.txt"
$BIN/fovea-bench --scene assets/range.glb --mode foveated --frames 3 --warmup 1 --dof weak \
    --trace-out "$OUT/range-trace.json" >"$OUT/range-trace.txt"
uptime | tee "$OUT/uptime-end.txt"
