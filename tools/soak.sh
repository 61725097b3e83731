#!/bin/sh
# make soak (docs/robustness.md): long runs that must keep their memory and descriptors flat.
#  1. fovea-replay: SOAK_FRAMES (default 100000) frames at 64x72 along the bundled trace with DoF,
#     stats only (--png off);
#  2. fovea-headset: SOAK_SECONDS (default 600) with the bundled eye video replayed (tracker on),
#     timer vsync at 90 Hz, no display, 128x144 per eye.
# Every SOAK_EVERY seconds (default 5) the process's VmRSS and open descriptors are sampled into
# OUT/<run>.csv. Flat means: over the second half of the samples (after warm-up) RSS grows by at
# most 4 MiB per hour (least-squares slope: a headset runs for hours, so a slow linear growth is a
# leak even when the run's own change is small) and the descriptor count does not change. Prints
# one line per run and exits 1 if either grew.
#   tools/soak.sh [OUT_DIR]   (env: BUILD=build SOAK_FRAMES SOAK_SECONDS SOAK_EVERY)
set -u
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
OUT=${1:-out/soak}
FRAMES=${SOAK_FRAMES:-100000}
SECONDS_HS=${SOAK_SECONDS:-600}
EVERY=${SOAK_EVERY:-5}
mkdir -p "$OUT"
status=0

# sample PID NAME: RSS (kB) and descriptors until the process ends
sample() {
    pid=$1 csv=$OUT/$2.csv
    echo "t_s,rss_kb,fds" >"$csv"
    t=0
    while kill -0 "$pid" 2>/dev/null; do
        rss=$(sed -n 's/^VmRSS:[[:space:]]*\([0-9]*\) kB/\1/p' "/proc/$pid/status" 2>/dev/null)
        fds=$(ls "/proc/$pid/fd" 2>/dev/null | wc -l)
        [ -n "$rss" ] && echo "$t,$rss,$fds" >>"$csv"
        sleep "$EVERY"
        t=$((t + EVERY))
    done
}

judge() {
    name=$1 csv=$OUT/$1.csv rc=$2
    verdict=$(awk -F, -v every="$EVERY" 'NR > 1 {t[n] = $1; r[n] = $2; f[n] = $3; n++}
        END {
            if (n < 8) {print "too few samples (" n ")"; exit}
            # least-squares slope of RSS over the second half (after warm-up), projected to an hour:
            # a headset runs for hours, so slow linear growth matters more than the end-to-end change
            h = int(n / 2); st = 0; sr = 0; m = n - h
            for (i = h; i < n; i++) {st += t[i]; sr += r[i]}
            st /= m; sr /= m; num = 0; den = 0
            for (i = h; i < n; i++) {num += (t[i] - st) * (r[i] - sr); den += (t[i] - st) ^ 2}
            slope = den > 0 ? num / den : 0      # kB per second
            per_hour = slope * 3600
            fd_changes = 0
            for (i = h + 1; i < n; i++) if (f[i] != f[h]) fd_changes++
            ok = per_hour <= 4096 && fd_changes == 0
            printf "%s: %d samples, RSS %.1f -> %.1f MiB, %+.2f MiB per hour (second half), descriptors %d -> %d (%d changes)\n",
                   ok ? "flat" : "GREW", n, r[h] / 1024, r[n - 1] / 1024, per_hour / 1024, f[h], f[n - 1], fd_changes
        }' "$csv")
    echo "soak $name: exit $rc, $verdict"
    case "$verdict" in flat*) [ "$rc" -eq 0 ] || status=1 ;; *) status=1 ;; esac
}

echo "soak replay: $FRAMES frames at 64x72 (samples every $EVERY s into $OUT/replay.csv)"
"$BUILD/bin/fovea-replay" --scene assets/range.glb --trace assets/gaze_sweep.csv --frames "$FRAMES" --size 64x72 \
    --threads 2 --dof medium --png off --quiet --out "$OUT/replay" &
pid=$!
sample $pid replay
wait $pid
judge replay $?

echo "soak headset: $SECONDS_HS s (samples every $EVERY s into $OUT/headset.csv)"
"$BUILD/bin/fovea-headset" --scene assets/range.glb --camera replay:assets/eye_synth.y4m --vsync timer:90 \
    --display none --size 128x144 --threads 2 --dof medium --seconds "$SECONDS_HS" >"$OUT/headset.txt" 2>&1 &
pid=$!
sample $pid headset
wait $pid
judge headset $?
head -n 3 "$OUT/headset.txt"
exit $status
