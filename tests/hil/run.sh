#!/bin/bash
# make test-hil: boots Debian's kernel in QEMU (TCG) from a small initramfs and runs the
# hardware-in-the-loop checks of tests/hil/guest.c against real kernel drivers (vivid, gpio-sim,
# bochs-drm), fovea-headset itself among them. docs/hil.md says what runs and how.
#
#   BUILD=build tests/hil/run.sh      (make test-hil builds $BUILD/hil/fovea-hil first)
#
# Environment: HIL_DIR (cache, default $BUILD/hil), HIL_TIMEOUT (seconds for the whole guest run,
# default 240), HIL_FRAMES (eye frames through the V4L2 loop, default 60), HIL_GPIO_SECONDS
# (default 4), HIL_SMP (guest CPUs, default 1). Exit 0 when every check passed, 1 otherwise.
set -eu
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
HIL_DIR=${HIL_DIR:-$BUILD/hil}
TIMEOUT=${HIL_TIMEOUT:-240}
FRAMES=${HIL_FRAMES:-60}
GPIO_SECONDS=${HIL_GPIO_SECONDS:-4}
SMP=${HIL_SMP:-1}
# fovea-headset in the guest: eye size and run time (a 128x144 stereo frame takes ~0.3 s under TCG)
HS_SIZE=${HIL_HS_SIZE:-64x72}
HS_SECONDS=${HIL_HS_SECONDS:-4}
# the headset's vsync source, default the gpio-sim line; HIL_HS_VSYNC=timer:90 is the negative
# control of the vsync check (photons on a timer, not on the line's edges: it must fail)
HS_VSYNC=${HIL_HS_VSYNC:+HIL_HS_VSYNC=$HIL_HS_VSYNC }
# the calibration check: the scripted wearer's target time and video frame rate, and how long
# fovea-headset renders with the calibration it wrote
CAL_DWELL_MS=${HIL_CAL_DWELL_MS:-1000}
CAL_FPS=${HIL_CAL_FPS:-30}
CAL_READBACK_SECONDS=${HIL_CAL_READBACK_SECONDS:-4}
# the rate the video is played at, default CAL_FPS; another one is the negative control of
# calib-run (the wearer drifts off the procedure's schedule: it must fail)
CAL_PLAY=${HIL_CAL_PLAY_FPS:+HIL_CAL_PLAY_FPS=$HIL_CAL_PLAY_FPS }
# extra QEMU options, e.g. HIL_QEMU_EXTRA="-icount shift=auto"
QEMU_EXTRA=${HIL_QEMU_EXTRA:-}
guest_bin=$BUILD/hil/fovea-hil
say() { echo "hil: $*"; }
die() { echo "hil: error: $*" >&2; exit 1; }

[ -x "$guest_bin" ] || die "$guest_bin missing (make test-hil builds it)"
[ -f assets/eye_synth.y4m ] && [ -f assets/eye_synth.csv ] ||
    die "assets/eye_synth.{y4m,csv} missing (make builds them)"
t_start=$(date +%s.%N)
tools/hil/prepare.sh "$HIL_DIR"
# shellcheck disable=SC1091
. "$HIL_DIR/env"
t_prep=$(date +%s.%N)

# --- initramfs: busybox, the modules (load order from modprobe --show-depends), the guest program
run=$HIL_DIR/run
rm -rf "$run"
mkdir -p "$run/initrd/bin" "$run/initrd/lib/modules" "$run/initrd/data" "$run/initrd/dev" "$run/initrd/proc" \
    "$run/initrd/sys"
cp /bin/busybox "$run/initrd/bin/busybox"
file_type=$(od -An -c -N4 "$run/initrd/bin/busybox" | tr -d ' ')
[ "$file_type" = '177ELF' ] || die "/bin/busybox is not an ELF (busybox-static)"
cp "$guest_bin" "$run/initrd/bin/fovea-hil"
cp tests/hil/init "$run/initrd/init"
# fovea-headset as make all built it, with its shared libraries (ldd: Embree, TBB and tinygltf
# exist only as shared libraries in Debian, so no static link) and the dynamic loader. The
# libraries (66 MB, 45 of them for SDL2, which the program links for --display window) go into
# a second cpio archive, cached while the ldd list and the files are unchanged; the kernel
# unpacks the two archives one after the other.
headset_bin=$BUILD/bin/fovea-headset
[ -x "$headset_bin" ] || die "$headset_bin missing (make test-hil builds it)"
ldd "$headset_bin" | grep -q 'not found' && die "ldd $headset_bin: a library was not found"
cp "$headset_bin" "$run/initrd/bin/fovea-headset"
interp=$(ldd "$headset_bin" | awk '$1 ~ /^\/.*ld-linux/ { print $1 }')
[ -n "$interp" ] || die "ldd $headset_bin names no dynamic loader"
libs=$(ldd "$headset_bin" | awk '$2 == "=>" && $3 ~ /^\// { print $3 }')
# shellcheck disable=SC2086
key=$(for f in "$interp" $libs; do printf '%s %s\n' "$f" "$(stat -L -c '%s %Y' "$f")"; done | md5sum | cut -c1-16)
libs_cpio=$(cd "$HIL_DIR" && pwd)/libs-$key.cpio.gz
if [ ! -s "$libs_cpio" ]; then
    rm -rf "$HIL_DIR/libs-tree" "$HIL_DIR"/libs-*.cpio.gz
    mkdir -p "$HIL_DIR/libs-tree/lib64" "$HIL_DIR/libs-tree/lib/x86_64-linux-gnu"
    cp -L "$interp" "$HIL_DIR/libs-tree/lib64/$(basename "$interp")"
    for l in $libs; do
        cp -L "$l" "$HIL_DIR/libs-tree/lib/x86_64-linux-gnu/$(basename "$l")"
    done
    (cd "$HIL_DIR/libs-tree" && find . | LC_ALL=C sort | cpio -o -H newc --quiet | gzip -1 > "$libs_cpio.tmp")
    mv "$libs_cpio.tmp" "$libs_cpio"
    rm -rf "$HIL_DIR/libs-tree"
fi
n_libs=$(echo "$libs" | wc -l)
cp assets/range.glb "$run/initrd/data/range.glb"
chmod 755 "$run/initrd/init"
# the first FRAMES frames of the eye video (header line + FRAMES x ("FRAME\n" + 320x240 luma))
head -n1 assets/eye_synth.y4m | grep -q '^YUV4MPEG2 W320 H240 .*Cmono' ||
    die "assets/eye_synth.y4m is not the 320x240 Cmono video the V4L2 check expects"
hdr=$(head -n1 assets/eye_synth.y4m | wc -c)
head -c $((hdr + FRAMES * (6 + 320 * 240))) assets/eye_synth.y4m > "$run/initrd/data/eye_synth.y4m"
head -n $((FRAMES + 1)) assets/eye_synth.csv > "$run/initrd/data/eye_synth.csv"
# the calibration check's scripted wearer (gen_eye --calibration: the procedure's own schedule),
# made once per gen_eye binary and settings (5 s, 32 MB at the defaults)
gen_eye=$BUILD/tools/gen_eye
[ -x "$gen_eye" ] || die "$gen_eye missing (make builds it)"
cal_key=$( (md5sum < "$gen_eye"; echo "$CAL_DWELL_MS $CAL_FPS") | md5sum | cut -c1-16)
cal_video=$HIL_DIR/calib-$cal_key.y4m
if [ ! -s "$cal_video" ] || [ ! -s "${cal_video%.y4m}.csv" ]; then
    rm -f "$HIL_DIR"/calib-*.y4m "$HIL_DIR"/calib-*.csv
    "$gen_eye" --calibration "$CAL_DWELL_MS" --fps "$CAL_FPS" --out "$cal_video" --truth "${cal_video%.y4m}.csv" ||
        die "gen_eye --calibration failed"
fi
cp "$cal_video" "$run/initrd/data/calib.y4m"
cp "${cal_video%.y4m}.csv" "$run/initrd/data/calib.csv"
: > "$run/initrd/modules.list"
mods=$(for m in vivid bochs gpio-sim; do
    modprobe -d "$HIL_ROOT" -S "$HIL_KVER" --show-depends "$m" || die "modprobe --show-depends $m failed"
done | awk '$1 == "insmod" && !seen[$2]++ { print $2 }')
[ -n "$mods" ] || die "no modules resolved"
for p in $mods; do
    b=$(basename "$p")
    case "$b" in
        *.ko) cp "$p" "$run/initrd/lib/modules/$b" ;;
        *.ko.xz) xz -dc "$p" > "$run/initrd/lib/modules/${b%.xz}"; b=${b%.xz} ;;
        *) die "unexpected module file $p" ;;
    esac
    case "$b" in
        vivid.ko) echo "$b n_devs=1 node_types=0x101" ;;
        *) echo "$b" ;;
    esac >> "$run/initrd/modules.list"
done
(cd "$run/initrd" && find . | LC_ALL=C sort | cpio -o -H newc --quiet | gzip -1 > ../initrd-main.gz)
cat "$libs_cpio" "$run/initrd-main.gz" > "$run/initrd.gz"
say "kernel $HIL_KVER ($HIL_IMG_PKG $HIL_IMG_VER), initramfs $(($(stat -c %s "$run/initrd.gz") / 1024)) KiB," \
    "$(wc -l < "$run/initrd/modules.list") modules: $(awk '{printf "%s%s", sep, $1; sep=" "}' "$run/initrd/modules.list");" \
    "fovea-headset with $n_libs shared libraries ($(($(stat -c %s "$libs_cpio") / 1024)) KiB of it)"
t_initrd=$(date +%s.%N)

# --- QEMU: console on ttyS0 (a file), the host's answers on ttyS1, the monitor on a pipe
mkfifo "$run/ctl.in" "$run/ctl.out" "$run/mon.in" "$run/mon.out"
exec 3<>"$run/ctl.in" 4<>"$run/ctl.out" 5<>"$run/mon.in" 6<>"$run/mon.out"
console=$run/console.log
: > "$console"
# shellcheck disable=SC2206,SC2054
qemu_args=(-accel tcg -cpu max -m 512 -smp "$SMP" $QEMU_EXTRA -nodefaults -no-reboot -display none -vga none
    -device bochs-display
    -chardev "file,id=con,path=$console" -serial chardev:con
    -chardev "pipe,id=ctl,path=$run/ctl" -serial chardev:ctl
    -chardev "pipe,id=mon,path=$run/mon" -mon chardev=mon,mode=readline
    -kernel "$HIL_VMLINUX" -initrd "$run/initrd.gz"
    -append "console=ttyS0 quiet panic=-1 rdinit=/init $HS_VSYNC$CAL_PLAY""HIL_HS_SIZE=$HS_SIZE HIL_HS_SECONDS=$HS_SECONDS HIL_FRAMES=$FRAMES HIL_GPIO_SECONDS=$GPIO_SECONDS HIL_CAL_DWELL_MS=$CAL_DWELL_MS HIL_CAL_FPS=$CAL_FPS HIL_CAL_READBACK_SECONDS=$CAL_READBACK_SECONDS")
say "booting: qemu-system-x86_64 ${qemu_args[*]}"
t_boot=$(date +%s.%N)
timeout --kill-after=5 "$TIMEOUT" qemu-system-x86_64 "${qemu_args[@]}" > "$run/qemu.log" 2>&1 &
qpid=$!
trap 'kill "$qpid" 2>/dev/null || true' EXIT INT TERM # no QEMU left behind if this script is stopped
shot_done=0 hs_shot_done=0
kms_w='' kms_h=''
# waits until QEMU has written the screendump $1 (its size is only known from its header: poll
# until it stops growing)
wait_dump() {
    local last=-1 cur
    for _ in $(seq 100); do
        cur=$(stat -c %s "$1" 2>/dev/null || echo -1)
        [ "$cur" -gt 0 ] && [ "$cur" = "$last" ] && return 0
        last=$cur
        sleep 0.1
    done
}
while kill -0 "$qpid" 2>/dev/null; do
    if [ $hs_shot_done = 0 ] && grep -q '^HIL-READY headset' "$console" 2>/dev/null; then
        # stop the VM for the screendump: the guest's clocks stand still, so the frame loop
        # under test does not see it
        rm -f "$run/headset.ppm"
        printf 'stop\nscreendump %s\n' "$run/headset.ppm" >&5
        wait_dump "$run/headset.ppm"
        echo cont >&5
        echo >&3
        hs_shot_done=1
    fi
    if [ $shot_done = 0 ] && line=$(grep -m1 '^HIL-READY kms ' "$console" 2>/dev/null); then
        read -r _ _ kms_w kms_h <<< "$line"
        kms_h=${kms_h%$'\r'}
        rm -f "$run/shot.ppm"
        echo "screendump $run/shot.ppm" >&5
        for _ in $(seq 100); do
            [ -f "$run/shot.ppm" ] && [ "$(stat -c %s "$run/shot.ppm")" -ge $((kms_w * kms_h * 3)) ] && break
            sleep 0.1
        done
        sleep 0.2
        echo >&3 # the guest may tear down its framebuffers now
        shot_done=1
    fi
    sleep 0.1
done
qrc=0
wait "$qpid" || qrc=$?
t_end=$(date +%s.%N)
exec 3>&- 4>&- 5>&- 6>&-

# --- results
tr -d '\r' < "$console" > "$run/console.txt"
if [ $shot_done = 1 ]; then
    "$guest_bin" kms-compare "$run/shot.ppm" "$kms_w" "$kms_h" >> "$run/console.txt" || true
fi
# the headset checks' own test on synthetic runs (host side)
"$guest_bin" headset-selftest >> "$run/console.txt" 2>&1 || true
if [ $hs_shot_done = 1 ]; then
    # the same frame on the host: fovea-replay, same scene, size, view (the default), gaze (the
    # centre) and reprojection off
    rm -rf "$run/headset-ref"
    if "$BUILD/bin/fovea-replay" --scene assets/range.glb --size "$HS_SIZE" --reproject off --stereo --frames 1 \
        --out "$run/headset-ref" --quiet > "$run/headset-ref.log" 2>&1; then
        "$guest_bin" headset-compare "$run/headset.ppm" "$run/headset-ref/frame_00000.png" "$run/headset-shot.png" \
            >> "$run/console.txt" || true
    else
        echo "HIL headset-readback FAIL reason=\"fovea-replay failed: $(tail -n1 "$run/headset-ref.log")\"" >> "$run/console.txt"
    fi
fi
checks="boot modules v4l2-loop v4l2-track v4l2-buf-error v4l2-reopen gpio-lock gpio-dropped headset-selftest
    headset-run headset-vsync headset-flip headset-readback calib-run calib-readback kms-flip kms-readback"
pass=0 fail=0
for c in $checks; do
    line=$(grep -m1 "^HIL $c " "$run/console.txt" || true)
    if [ -z "$line" ]; then
        echo "  FAIL $c (no result line)"
        fail=$((fail + 1))
    else
        # shellcheck disable=SC2086
        set -- $line
        st=$3
        shift 3
        echo "  $st $c $*"
        if [ "$st" = PASS ]; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
    fi
done
if [ $qrc = 124 ] || [ $qrc = 137 ]; then
    echo "  FAIL guest timed out after ${TIMEOUT}s (killed); console: $run/console.txt"
    fail=$((fail + 1))
elif ! grep -q '^HIL done' "$run/console.txt"; then
    echo "  FAIL guest did not finish (qemu exit $qrc); console: $run/console.txt, qemu: $run/qemu.log"
    fail=$((fail + 1))
fi
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
say "times: prepare $(secs "$t_start" "$t_prep") s, initramfs $(secs "$t_prep" "$t_initrd") s," \
    "guest run $(secs "$t_boot" "$t_end") s (guest uptime at boot line $(sed -n 's/^HIL boot PASS uptime_s=\([0-9.]*\).*/\1/p' "$run/console.txt") s)"
if [ $fail -gt 0 ]; then
    say "console:"
    sed 's/^/    /' "$run/console.txt" | tail -n 60
fi
echo "hil: $pass passed, $fail failed"
[ $fail = 0 ]
