#!/bin/sh
# Command-line contract tests for fovea-replay, fovea-bench and fovea-track: bad input gets a one-line reason
# and exit 2 with no output left behind as if complete; good runs write what DESIGN.md promises;
# frames are byte-identical for 1, 2 and 5 threads and across runs.
set -u
BUILD=${BUILD:-build}
B=$BUILD/bin
BT=$BUILD/tools
SCENE=assets/range.glb
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
pass=0 fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

# expect_usage NAME PATTERN CMD...: exit status 2 and exactly one line on stderr, which names
# the problem (matches the extended regex PATTERN)
expect_usage() {
    name=$1; pat=$2; shift 2
    "$@" >"$T/out" 2>"$T/err"
    rc=$?
    lines=$(wc -l <"$T/err")
    if [ "$rc" -eq 2 ] && [ "$lines" -eq 1 ] && grep -Eq -- "$pat" "$T/err"; then ok
    else bad "$name: exit $rc, $lines stderr lines, want /$pat/: $(head -c 300 "$T/err")"; fi
}

printf 't_ms,gaze_x,gaze_y\n0,0.5,0.5\n11.1,0.5\n' >"$T/truncated.csv"
printf 't_ms,gaze_x,gaze_y\n0,0.5,abc\n' >"$T/nan.csv"
printf 'time,x,y\n0,0.5,0.5\n' >"$T/header.csv"
printf 't_ms,gaze_x,gaze_y\n' >"$T/empty.csv"
printf 't_ms,gaze_x,gaze_y\n0,0.2,0.3\n50,0.8,0.7\n' >"$T/good.csv"
printf 'glTF garbage' >"$T/bad.glb"

for p in fovea-replay fovea-bench; do
    # only the replay takes --out; giving it to the bench would fail for the wrong reason
    if [ $p = fovea-replay ]; then O="--out $T/o1"; else O=; fi
    expect_usage "$p unknown flag" '--bogus: unknown option' $B/$p --scene $SCENE --bogus
    expect_usage "$p missing scene file" 'nope.glb.*No such file' $B/$p --scene "$T/nope.glb" $O
    expect_usage "$p corrupt scene" 'bad.glb' $B/$p --scene "$T/bad.glb" $O
    expect_usage "$p no scene" '--scene FILE is required' $B/$p $O
    expect_usage "$p bad threads" '--threads: 0 is out of range' $B/$p --scene $SCENE $O --threads 0
    expect_usage "$p bad threads text" '--threads: .two. is not a whole number' $B/$p --scene $SCENE $O --threads two
    expect_usage "$p bad size" '--size: .640x. is not WxH' $B/$p --scene $SCENE $O --size 640x
    expect_usage "$p bad pmin" '--pmin: 1.5 is out of range' $B/$p --scene $SCENE $O --pmin 1.5
    expect_usage "$p r0 > r1" '--r0 30 must not exceed --r1 20' $B/$p --scene $SCENE $O --r0 30 --r1 20
    expect_usage "$p dof model bad" '--dof-model: .bokeh. is not one of' $B/$p --scene $SCENE $O --dof weak --dof-model bokeh
    expect_usage "$p bad contrast gain" '--contrast-gain: 5 is out of range' $B/$p --scene $SCENE $O --dof weak --contrast-gain 5
    expect_usage "$p bad gaze error" '--gaze-error-deg: -1 is out of range' $B/$p --scene $SCENE $O --dof weak --gaze-error-deg -1
    expect_usage "$p bad chroma" '--chroma: .yes. is not one of on, off' $B/$p --scene $SCENE $O --chroma yes
    expect_usage "$p bad dof-sampling" '--dof-sampling: .yes. is not one of on, off' $B/$p --scene $SCENE $O --dof-sampling yes
    expect_usage "$p bad dof-sampling-kappa" '--dof-sampling-kappa: 0 is out of range' $B/$p --scene $SCENE $O --dof-sampling-kappa 0
    expect_usage "$p dof bad" '--dof: .blurry. is not one of' $B/$p --scene $SCENE $O --dof blurry
    expect_usage "$p stray arg" 'unexpected argument .extra.' $B/$p --scene $SCENE $O extra
    expect_usage "$p bad reproject" '--reproject: .maybe. is not one of on, off' $B/$p --scene $SCENE $O --reproject maybe
    expect_usage "$p bad taa-alpha" '--taa-alpha: 0 is out of range' $B/$p --scene $SCENE $O --taa-alpha 0
    expect_usage "$p bad taa-fill" '--taa-fill: .yes. is not one of on, off' $B/$p --scene $SCENE $O --taa-fill yes
    expect_usage "$p bad fovea-aa" '--fovea-aa: .yes. is not one of on, off' $B/$p --scene $SCENE $O --fovea-aa yes
    expect_usage "$p bad pattern" '--pattern: .spiral. is not one of rotate, static' $B/$p --scene $SCENE $O --pattern spiral
    expect_usage "$p bad sampling" '--sampling: .polar. is not one of weier, liu' $B/$p --scene $SCENE $O --sampling polar
    expect_usage "$p bad liu density" '--liu-density 0.5: must be 0' $B/$p --scene $SCENE $O --sampling liu --liu-density 0.5
    expect_usage "$p bad shadows" '--shadows: .maybe. is not one of on, off' $B/$p --scene $SCENE $O --shadows maybe
    $B/$p --help 2>&1 | grep -q -- '--shadows on|off' && ok || bad "$p --help lacks --shadows"
    if $B/$p --help >"$T/help" 2>&1 && grep -q -- --scene "$T/help"; then ok; else bad "$p --help"; fi
done
[ ! -e "$T/o1" ] && ok || bad "bad input left output directory $T/o1 behind"

R=$B/fovea-replay
expect_usage "replay no out" '--out DIR is required' $R --scene $SCENE
expect_usage "replay bad frames" '--frames: -3 is out of range' $R --scene $SCENE --out "$T/o2" --frames -3
expect_usage "replay missing trace" 'none.csv: No such file' $R --scene $SCENE --out "$T/o2" --trace "$T/none.csv"
expect_usage "replay trace is a directory" '(directory|read error)' $R --scene $SCENE --out "$T/o2" --trace "$T"
expect_usage "replay truncated trace" 'truncated.csv:3: 2 fields, expected 3' $R --scene $SCENE --out "$T/o2" --trace "$T/truncated.csv"
expect_usage "replay non-numeric trace" 'nan.csv:2: field 3 .*abc.* is not a finite number' $R --scene $SCENE --out "$T/o2" --trace "$T/nan.csv"
expect_usage "replay wrong header" 'header.csv:1: header must start with t_ms,gaze_x,gaze_y' $R --scene $SCENE --out "$T/o2" --trace "$T/header.csv"
expect_usage "replay empty trace" 'empty.csv: no samples' $R --scene $SCENE --out "$T/o2" --trace "$T/empty.csv"
expect_usage "replay reference spp 0" '--reference: 0 is out of range' $R --scene $SCENE --out "$T/o2" --reference 0
expect_usage "replay bad focus" '--focus-m: 0 is out of range' $R --scene $SCENE --out "$T/o2" --reference 4 --focus-m 0
expect_usage "replay bad pupil" '--pupil-mm: 25 is out of range' $R --scene $SCENE --out "$T/o2" --reference 4 --pupil-mm 25
expect_usage "replay reference dof none pupil" '--pupil-mm: --reference with --dof none is a pinhole' $R --scene $SCENE --out "$T/o2" --reference 4 --dof none --pupil-mm 3
expect_usage "replay reference vs-full" '--vs-full and --reference exclude each other' $R --scene $SCENE --out "$T/o2" --reference 4 --vs-full
[ ! -e "$T/o2" ] && ok || bad "bad trace left output directory behind"
# values checked at the type they are used in: a head position finite as a double, infinite as a float
# (it aborted Embree with exit 134 and left stats.csv.tmp behind)
printf 't_ms,gaze_x,gaze_y,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw\n0,0.5,0.5,0,1e30,0,0,0,0,1\n' >"$T/far.csv"
expect_usage "replay head position 1e30" 'far.csv:2: head position head_py = 1e\+30 m out of range' $R --scene $SCENE --out "$T/o3" --trace "$T/far.csv"
[ ! -e "$T/o3" ] && ok || bad "1e30 head position left output behind"
expect_usage "replay trace from /dev/zero" '/dev/zero: not a text file' $R --scene $SCENE --out "$T/o3" --trace /dev/zero
# sizes judged before reading: a sparse 2 GiB trace and a zero-filled 2 GiB .gltf (read whole for 12 s before)
truncate -s 2G "$T/huge.csv" && truncate -s 2G "$T/huge.gltf"
expect_usage "replay 2 GiB trace" 'huge.csv: 2147483648 bytes, larger than the 1024 MiB limit' $R --scene $SCENE --out "$T/o3" --trace "$T/huge.csv"
expect_usage "replay 2 GiB zero gltf" 'huge.gltf: not a glTF file' $R --scene "$T/huge.gltf" --out "$T/o3"
[ ! -e "$T/o3" ] && ok || bad "oversized inputs left output behind"
rm -f "$T/huge.csv" "$T/huge.gltf"
# a scene's external files stay in its folder tree: a URI leading out is refused and named (exit 2);
# --asset-root widens the tree
mkdir -p "$T/esc/scene"
printf '\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\77\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\77\0\0\0\0' >"$T/esc/tri.bin"
printf '{"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"%%2e%%2e/tri.bin"}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}' >"$T/esc/scene/s.gltf"
expect_usage "replay scene URI outside its folder" "esc/scene/\\.\\./tri.bin' is outside the scene's folder" $R --scene "$T/esc/scene/s.gltf" --out "$T/o5" --size 64x72
expect_usage "bench scene URI outside its folder" "is outside the scene's folder" $B/fovea-bench --scene "$T/esc/scene/s.gltf" --size 64x72 --frames 1
if $R --scene "$T/esc/scene/s.gltf" --asset-root "$T/esc" --out "$T/o5" --size 64x72 --quiet >/dev/null 2>"$T/err" && [ -s "$T/o5/frame_00000.png" ]; then ok
else bad "replay --asset-root: $(head -c 300 "$T/err")"; fi
expect_usage "replay bad asset root" "--asset-root $T/none: No such file" $R --scene "$T/esc/scene/s.gltf" --asset-root "$T/none" --out "$T/o6"
# glTF 1.0 and unsupported required extensions: one line naming the version or the extension
printf '{"asset":{"version":"1.0"},"meshes":{}}' >"$T/v1.gltf"
expect_usage "replay glTF 1.0" 'v1.gltf: glTF 1.0 is not supported, only glTF 2.0' $R --scene "$T/v1.gltf" --out "$T/o7"
printf '{"asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"],"accessors":[{"componentType":5126,"count":3,"type":"VEC3"}]}' >"$T/draco.gltf"
expect_usage "replay draco" 'required extension KHR_draco_mesh_compression is not supported' $R --scene "$T/draco.gltf" --out "$T/o7"
expect_usage "replay unwritable out" '/proc/fovea-no' $R --scene $SCENE --size 64x72 --out /proc/fovea-no/o
expect_usage "replay unwritable y4m" '/proc/fovea-no/v.y4m' $R --scene $SCENE --size 64x72 --out "$T/o4" --y4m /proc/fovea-no/v.y4m
[ ! -e "$T/o4/stats.csv" ] && [ ! -e "$T/o4/stats.csv.tmp" ] && ok || bad "unwritable y4m left stats.csv behind"
expect_usage "replay unwritable trace-out" '/proc/fovea-no/p.json' $R --scene $SCENE --size 64x72 --out "$T/o4" --trace-out /proc/fovea-no/p.json
expect_usage "bench unwritable json" '/proc/fovea-no/b.json' $B/fovea-bench --scene $SCENE --size 64x72 --json /proc/fovea-no/b.json
expect_usage "bench json is a directory" "$T: is a directory" $B/fovea-bench --scene $SCENE --size 64x72 --json "$T"
expect_usage "track unwritable out" '/proc/fovea-no/t.csv' $B/fovea-track --video assets/eye_synth.y4m --out /proc/fovea-no/t.csv
expect_usage "bench bad mode" '--mode: .fast. is not one of' $B/fovea-bench --scene $SCENE --mode fast
expect_usage "bench bad yaw rate" '--yaw-rate: 1000 is out of range' $B/fovea-bench --scene $SCENE --yaw-rate 1000

# A good run: frames and stats with the documented columns
if $R --scene $SCENE --trace "$T/good.csv" --frames 3 --size 96x108 --out "$T/run" --quiet 2>"$T/err"; then
    n=$(ls "$T/run" | grep -c '^frame_0000[0-2]\.png$')
    head=$(head -n 1 "$T/run/stats.csv")
    rows=$(wc -l <"$T/run/stats.csv")
    want="frame,t_ms,gaze_x,gaze_y,samples,trace_ms,reproject_ms,reconstruct_ms,coc_ms,dof_filter_ms,combine_ms,output_ms,total_ms,dluma_periph,psnr_all,psnr_fovea,psnr_periph,flicker_periph,focus_m"
    [ "$n" -eq 3 ] && ok || bad "replay wrote $n frames, expected 3"
    [ "$head" = "$want" ] && ok || bad "stats.csv header: $head"
    [ "$rows" -eq 4 ] && ok || bad "stats.csv has $rows lines, expected 4"
    ls "$T/run" | grep -q '\.tmp$' && bad "temporary files left in output" || ok
else
    bad "replay good run failed: $(cat "$T/err")"
fi
# --vs-full: every frame also rendered fully sampled; PSNR columns filled from the first frame,
# the frame-to-frame columns from the second; a static view converges (PSNR rises)
if $R --scene $SCENE --frames 6 --size 96x108 --vs-full --out "$T/vs" --quiet 2>"$T/err"; then
    awk -F, 'NR == 2 && $15 != "" && $14 == "" {ok++} NR == 3 && $14 != "" && $18 != "" {ok++}
             NR == 2 {first = $15} NR == 7 {last = $15} END {exit !(ok == 2 && (last == "inf" || last > first + 10))}' \
        "$T/vs/stats.csv" && ok || bad "--vs-full columns: $(sed -n '2p;3p;7p' "$T/vs/stats.csv")"
else
    bad "replay --vs-full failed: $(cat "$T/err")"
fi
# --frames defaults to the trace's length at 90 Hz: 50 ms -> frames 0..4
if $R --scene $SCENE --trace "$T/good.csv" --size 48x54 --out "$T/run5" --quiet 2>"$T/err"; then
    n=$(ls "$T/run5" | grep -c '^frame_.*\.png$')
    [ "$n" -eq 5 ] && ok || bad "default frame count $n, expected 5"
else
    bad "replay default frames failed: $(cat "$T/err")"
fi

# Determinism: same bytes for 1, 2 and 5 threads, and on a second run (the bundled trace moves
# the head: the later frames reproject their history)
for th in 1 2 5; do
    $R --scene $SCENE --trace assets/gaze_sweep.csv --frames 3 --size 160x180 --threads $th --out "$T/d$th" --quiet \
        2>"$T/err" || bad "replay --threads $th failed: $(cat "$T/err")"
done
$R --scene $SCENE --trace assets/gaze_sweep.csv --frames 3 --size 160x180 --threads 2 --out "$T/d2b" --quiet 2>/dev/null
for f in frame_00000.png frame_00001.png frame_00002.png; do
    for d in d2 d5 d2b; do
        if cmp -s "$T/d1/$f" "$T/$d/$f"; then ok; else bad "$f differs between d1 and $d"; fi
    done
done
# The still head in place (no trace: identical cameras from frame 1 on, docs/reproject.md): the
# same bytes for 1, 2 and 5 threads, with DoF-driven thinning (medium) and with a fovea of many
# anti-aliased tiles (r0 40 deg), whose history the tiles of other threads overwrite meanwhile
for th in 1 2 5; do
    $R --scene $SCENE --frames 6 --size 160x180 --dof medium --threads $th --out "$T/s$th" --quiet \
        2>"$T/err" || bad "replay (still) --threads $th failed: $(cat "$T/err")"
    $R --scene $SCENE --frames 6 --size 160x180 --r0 40 --r1 50 --threads $th --out "$T/sa$th" --quiet \
        2>"$T/err" || bad "replay (still, r0 40) --threads $th failed: $(cat "$T/err")"
done
for f in frame_00002.png frame_00005.png; do
    for d in 2 5; do
        cmp -s "$T/s1/$f" "$T/s$d/$f" && ok || bad "still head: $f differs between 1 and $d threads"
        cmp -s "$T/sa1/$f" "$T/sa$d/$f" && ok || bad "still head, r0 40: $f differs between 1 and $d threads"
    done
done
# Fovea anti-aliasing (issue 17 item 5): with a fovea of many whole tiles (r0 40 deg) along the
# trace (head and gaze move), the same bytes for 1, 2 and 5 threads; --fovea-aa off gives other
# frames after the first (frame 0's rays go through the pixel centres either way)
for th in 1 2 5; do
    $R --scene $SCENE --trace assets/gaze_sweep.csv --frames 4 --size 160x180 --r0 40 --r1 50 --threads $th \
        --out "$T/aa$th" --quiet 2>"$T/err" || bad "replay --r0 40 --threads $th failed: $(cat "$T/err")"
done
$R --scene $SCENE --trace assets/gaze_sweep.csv --frames 4 --size 160x180 --r0 40 --r1 50 --fovea-aa off \
    --out "$T/aaoff" --quiet 2>/dev/null
for f in frame_00001.png frame_00003.png; do
    for d in aa2 aa5; do
        if cmp -s "$T/aa1/$f" "$T/$d/$f"; then ok; else bad "fovea-aa: $f differs between aa1 and $d"; fi
    done
done
cmp -s "$T/aa1/frame_00000.png" "$T/aaoff/frame_00000.png" && ok || bad "fovea-aa: frame 0 differs from --fovea-aa off"
cmp -s "$T/aa1/frame_00003.png" "$T/aaoff/frame_00003.png" && bad "fovea-aa on and off give the same frame 3" || ok
# Liu's polar sampler (issue 15 item 3): the same bytes for 1 and 5 threads, not Weier's frames,
# and the bench names it and its rays agree with the ceiling's
for th in 1 5; do
    $R --scene $SCENE --trace assets/gaze_sweep.csv --frames 3 --size 160x180 --threads $th --sampling liu \
        --out "$T/l$th" --quiet 2>"$T/err" || bad "replay --sampling liu --threads $th failed: $(cat "$T/err")"
done
for f in frame_00000.png frame_00002.png; do
    cmp -s "$T/l1/$f" "$T/l5/$f" && ok || bad "--sampling liu: $f differs between 1 and 5 threads"
    cmp -s "$T/l1/$f" "$T/d1/$f" && bad "--sampling liu: $f is Weier's" || ok
done
if $B/fovea-bench --scene $SCENE --size 96x108 --frames 2 --warmup 1 --threads 2 --ceiling --sampling liu \
    --json "$T/l.json" >/dev/null 2>"$T/err"; then
    [ "$(grep -c '"sampler": "liu"' "$T/l.json")" = 2 ] && ok || bad "--sampling liu bench JSON: $(cat "$T/l.json")"
else
    bad "--sampling liu bench failed: $(cat "$T/err")"
fi
# --reference: same files and header; the stage columns are empty, total_ms is the render time,
# samples = (SPP + 1 depth ray) per pixel; a zero pupil at SPP 1 is the full pinhole render;
# same bytes for 1 and 2 threads
if $R --scene $SCENE --frames 2 --size 48x54 --reference 4 --out "$T/ref" --quiet 2>"$T/err"; then
    [ "$(head -n 1 "$T/ref/stats.csv")" = "$(head -n 1 "$T/run/stats.csv")" ] && ok || bad "reference stats header differs"
    awk -F, 'NR == 2 && $5 == 48 * 54 * 5 && $6 == "" && $11 == "" && $12 == "" && $13 > 0 {ok = 1} END {exit !ok}' "$T/ref/stats.csv" \
        && ok || bad "reference stats row: $(sed -n 2p "$T/ref/stats.csv")"
    [ -e "$T/ref/frame_00001.png" ] && ok || bad "reference frames missing"
else
    bad "replay --reference failed: $(cat "$T/err")"
fi
$R --scene $SCENE --frames 1 --size 64x72 --full --out "$T/pin" --quiet 2>/dev/null
$R --scene $SCENE --frames 1 --size 64x72 --reference 1 --pupil-mm 0 --out "$T/ref0" --quiet 2>/dev/null
cmp -s "$T/pin/frame_00000.png" "$T/ref0/frame_00000.png" && ok || bad "reference with a zero pupil differs from --full"
# --reference SPP --dof none: pinhole rays spread over each pixel (anti-aliased, so not the
# pixel-centre image), the same bytes for 1 and 2 threads
for th in 1 2; do
    $R --scene $SCENE --frames 1 --size 64x72 --reference 8 --dof none --threads $th --out "$T/ra$th" --quiet 2>/dev/null
done
[ -e "$T/ra1/frame_00000.png" ] && cmp -s "$T/ra1/frame_00000.png" "$T/ra2/frame_00000.png" && ok \
    || bad "jittered pinhole reference missing or differs between 1 and 2 threads"
cmp -s "$T/pin/frame_00000.png" "$T/ra1/frame_00000.png" && bad "jittered pinhole reference equals the pixel-centre image" || ok
for th in 1 2; do
    $R --scene $SCENE --frames 1 --size 64x72 --reference 6 --focus-m 1.5 --threads $th --out "$T/rt$th" --quiet 2>/dev/null
done
cmp -s "$T/rt1/frame_00000.png" "$T/rt2/frame_00000.png" && ok || bad "reference differs between 1 and 2 threads"
cmp -s "$T/pin/frame_00000.png" "$T/rt1/frame_00000.png" && bad "reference with a pupil is not blurred" || ok
# fovea-compare: PSNR and SSIM of two PNGs (the frames above)
C=$B/fovea-compare
P1="$T/pin/frame_00000.png" P2="$T/rt1/frame_00000.png"
head -c 100 "$P1" >"$T/trunc.png"
expect_usage "compare missing file" 'nope.png: No such file' $C "$T/nope.png" "$P1"
expect_usage "compare not png" 'bad.glb: not a PNG file' $C "$P1" "$T/bad.glb"
expect_usage "compare corrupt png" 'trunc.png: corrupt PNG' $C "$T/trunc.png" "$P1"
# an 83-byte PNG whose IDAT length lies (stb reserved the 2 GiB it claims): refused from its chunks
printf '\211PNG\r\n\032\n\0\0\0\rIHDR\0\0\0\1\0\0\0\1\10\6\0\0\0\37\25\304\211\177\377\377\0IDATx\234c\370\317\300\360\37\0\5\0\1\377\211\231=\35\0\0\0\0IEND\256B`\202' >"$T/lying.png"
expect_usage "compare lying png" 'lying.png: corrupt PNG \(PNG chunk IDAT claims 2147483392 bytes' $C "$T/lying.png" "$P1"
expect_usage "compare size mismatch" 'is 64x72 but .* is 96x108: sizes must match' $C "$P1" "$T/run/frame_00000.png"
expect_usage "compare malformed region" '--fovea: .1,2. is not CX,CY,R' $C "$P1" "$P2" --fovea 1,2
expect_usage "compare region text" '--periphery: .a,b,c. is not CX,CY,R' $C "$P1" "$P2" --periphery a,b,c
expect_usage "compare bad radius" '--fovea: radius -3 must be positive' $C "$P1" "$P2" --fovea 10,10,-3
expect_usage "compare two regions" 'give one of --fovea, --periphery' $C "$P1" "$P2" --fovea 1,2,3 --periphery 1,2,3
expect_usage "compare empty region" '--fovea 500,500,3: the region holds no pixel' $C "$P1" "$P2" --fovea 500,500,3
expect_usage "compare one file" 'expected two PNG files' $C "$P1"
expect_usage "compare unknown flag" '--bogus: unknown option' $C "$P1" "$P2" --bogus
$C --help | grep -q -- --periphery && ok || bad "compare --help"
out=$($C "$P1" "$T/ref0/frame_00000.png" 2>&1)
[ "$out" = "$(printf 'psnr_db inf\nssim 1.000000')" ] && ok || bad "compare identical: $out"
# the blurred reference against the pinhole frame: finite PSNR, SSIM below 1; the periphery of
# a small disc is nearly the whole image, the fovea a part of it
if $C "$P1" "$P2" >"$T/c_all" && $C "$P1" "$P2" --fovea 32,36,12 >"$T/c_fov" && $C "$P1" "$P2" --periphery 32,36,12 >"$T/c_per"; then
    awk '$1 == "psnr_db" && $2 > 5 && $2 < 80 {p = 1} $1 == "ssim" && $2 > 0 && $2 < 0.999 {s = 1} END {exit !(p && s)}' "$T/c_all" \
        && ok || bad "compare values: $(cat "$T/c_all")"
    cmp -s "$T/c_fov" "$T/c_per" && bad "fovea and periphery give the same numbers" || ok
else
    bad "compare good runs failed"
fi
$R --scene $SCENE --frames 1 --size 160x180 --stereo --out "$T/st" --quiet 2>"$T/err" && ok || bad "stereo: $(cat "$T/err")"
# Y4M: header, then per frame "FRAME\n" + a 4:2:0 picture (w*h*3/2 bytes); stereo is side by side
if $R --scene $SCENE --frames 2 --size 64x72 --stereo --y4m "$T/v.y4m" --out "$T/y" --quiet 2>"$T/err"; then
    hdr=$(head -n 1 "$T/v.y4m")
    size=$(wc -c <"$T/v.y4m")
    want=$(( ${#hdr} + 1 + 2 * (6 + 128 * 72 * 3 / 2) ))
    case "$hdr" in "YUV4MPEG2 W128 H72 F90:1 "*) ok ;; *) bad "y4m header: $hdr" ;; esac
    [ "$size" -eq "$want" ] && ok || bad "y4m is $size bytes, expected $want"
else
    bad "y4m run failed: $(cat "$T/err")"
fi
expect_usage "replay odd y4m size" 'even frame sizes' $R --scene $SCENE --frames 1 --size 63x72 --y4m "$T/odd.y4m" --out "$T/odd"
[ ! -e "$T/odd.y4m" ] && [ ! -e "$T/odd.y4m.tmp" ] && [ ! -e "$T/odd/stats.csv" ] && ok || bad "failed y4m run left files behind"

# --window: without a display (or without SDL2 in the build) a one-line usage error and no
# output; under a virtual X server (xvfb-run, when installed) every frame is shown and written
expect_usage "replay window without display" '--window: (no display|fovea was built without SDL2)' \
    env -u DISPLAY -u WAYLAND_DISPLAY -u SDL_VIDEODRIVER $R --scene $SCENE --frames 2 --size 64x72 --window --out "$T/win0"
[ ! -e "$T/win0" ] && ok || bad "--window without a display left $T/win0 behind"
if command -v xvfb-run >/dev/null 2>&1 && ! grep -q 'built without SDL2' "$T/err"; then
    # (under ASan, leak checks off for this run: the X / D-Bus libraries SDL loads keep their own
    # allocations to exit; every other replay run checks the program's)
    if env -u WAYLAND_DISPLAY -u SDL_VIDEODRIVER ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
        xvfb-run -a $R --scene $SCENE --frames 3 --size 64x72 --stereo --window --out "$T/win" --quiet 2>"$T/err"; then
        [ "$(ls "$T/win" | grep -c '^frame_0000[0-2]\.png$')" -eq 3 ] && [ "$(wc -l <"$T/win/stats.csv")" -eq 4 ] && ok ||
            bad "--window under xvfb: $(ls "$T/win")"
    else
        bad "--window under xvfb failed: $(cat "$T/err")"
    fi
else
    echo "skip: --window under xvfb-run (no xvfb-run or no SDL2 in this build)"
fi

# Depth of field: the DoF stage columns and the focus are filled; the blurred frame differs from
# the sharp one; a fixed focus is reported as such; the same bytes for 1 and 3 threads
if $R --scene $SCENE --frames 2 --size 96x108 --dof strong --out "$T/dof" --quiet 2>"$T/err" &&
    $R --scene $SCENE --frames 2 --size 96x108 --dof strong --threads 3 --out "$T/dof3" --quiet 2>>"$T/err" &&
    $R --scene $SCENE --frames 2 --size 96x108 --dof strong --focus-m 1.5 --out "$T/doff" --quiet 2>>"$T/err" &&
    $R --scene $SCENE --frames 2 --size 96x108 --out "$T/nodof" --quiet 2>>"$T/err"; then
    awk -F, 'NR == 3 && $9 != "" && $10 != "" && $11 != "" && $12 != "" && $19 > 0 {ok = 1} END {exit !ok}' "$T/dof/stats.csv" && ok ||
        bad "--dof stats: $(sed -n 3p "$T/dof/stats.csv")"
    awk -F, 'NR == 3 && $9 == "" && $12 != "" && $19 == "" {ok = 1} END {exit !ok}' "$T/nodof/stats.csv" && ok ||
        bad "--dof none stats: $(sed -n 3p "$T/nodof/stats.csv")"
    awk -F, 'NR >= 2 && $19 != "1.5000" {bad = 1} END {exit bad}' "$T/doff/stats.csv" && ok ||
        bad "--focus-m 1.5 not reported: $(cut -d, -f19 "$T/doff/stats.csv" | tr '\n' ' ')"
    cmp -s "$T/dof/frame_00001.png" "$T/nodof/frame_00001.png" && bad "--dof strong changed nothing" || ok
    cmp -s "$T/dof/frame_00001.png" "$T/dof3/frame_00001.png" && ok || bad "--dof frames differ between 1 and 3 threads"
else
    bad "replay --dof failed: $(cat "$T/err")"
fi

# every model renders, and changes the image (focused at 0.3 m: the tunnel blurs by ~5 px)
$R --scene $SCENE --frames 1 --size 320x360 --out "$T/m_none" --quiet 2>/dev/null
for m in weier hussain mantiuk konrad liu; do
    if $R --scene $SCENE --frames 1 --size 320x360 --dof strong --dof-model $m --focus-m 0.3 --out "$T/m_$m" --quiet 2>"$T/err"; then
        cmp -s "$T/m_$m/frame_00000.png" "$T/m_none/frame_00000.png" && bad "--dof-model $m changed nothing" || ok
    else
        bad "--dof-model $m failed: $(cat "$T/err")"
    fi
done
$R --scene $SCENE --frames 1 --size 320x360 --dof strong --dof-model liu --chroma on --focus-m 0.3 --out "$T/m_liuc" --quiet 2>/dev/null &&
    ! cmp -s "$T/m_liuc/frame_00000.png" "$T/m_liu/frame_00000.png" && ok || bad "--chroma on changed nothing"

# Bench JSON has the documented fields; null for stages not built yet (and for reprojection in
# the full mode, which needs none)
if $B/fovea-bench --scene $SCENE --size 96x108 --frames 2 --warmup 1 --json "$T/b.json" >"$T/out" 2>"$T/err"; then
    for k in '"scene"' '"width": 96' '"height": 108' '"threads"' '"frames": 2' '"mode": "foveated"' '"mode": "full"' \
        '"samples_per_frame"' '"total_ms"' '"stages_ms"' '"trace": [0-9]' '"reproject": [0-9]' '"reproject": null' '"reconstruct": [0-9]' \
        '"coc": null' '"dof_filter": null' '"combine": null' '"mrays_per_s"'; do
        grep -q "$k" "$T/b.json" && ok || bad "bench JSON lacks $k"
    done
    grep -q 'Ray Tracing' "$T/out" && ok || bad "bench table header missing"
    # the shading share of the ray stage per mode (issue 17): a time in the JSON, a line in the output
    [ "$(grep -c '"shade_ms": [0-9]' "$T/b.json")" = 2 ] && ok || bad "bench JSON shade_ms: $(cat "$T/b.json")"
    grep -q 'shading inside the ray stage.*foveated [0-9.]* ms ([0-9]* %), full [0-9.]* ms' "$T/out" && ok ||
        bad "bench shading line: $(cat "$T/out")"
    # a turning head: the reprojection column is measured, and the JSON says the rate
    if $B/fovea-bench --scene $SCENE --size 96x108 --frames 2 --warmup 1 --mode foveated --yaw-rate 30 \
        --json "$T/t.json" >/dev/null 2>"$T/err"; then
        grep -q '"yaw_rate_dps": 30' "$T/t.json" && grep -q '"reproject": [0-9]' "$T/t.json" && ok ||
            bad "turning bench JSON: $(cat "$T/t.json")"
    else
        bad "turning bench failed: $(cat "$T/err")"
    fi
    # with depth of field its three stages are measured
    if $B/fovea-bench --scene $SCENE --size 96x108 --frames 2 --warmup 1 --mode foveated --dof weak \
        --json "$T/d.json" >/dev/null 2>"$T/err"; then
        grep -q '"coc": [0-9]' "$T/d.json" && grep -q '"dof_filter": [0-9]' "$T/d.json" &&
            grep -q '"combine": [0-9]' "$T/d.json" && ok || bad "DoF bench JSON: $(cat "$T/d.json")"
    else
        bad "DoF bench failed: $(cat "$T/err")"
    fi
    # without --ceiling: ceiling_ms null, the sampler named; with it (issue 15): a time per mode,
    # the comparison block, a valid JSON (the ray counts of stage and ceiling agree, or it fails)
    grep -q '"ceiling_ms": null' "$T/b.json" && grep -q '"sampler": "weier"' "$T/b.json" && ok ||
        bad "bench JSON without --ceiling: $(cat "$T/b.json")"
    if $B/fovea-bench --scene $SCENE --size 96x108 --frames 2 --warmup 1 --threads 2 --ceiling \
        --json "$T/c.json" >"$T/out" 2>"$T/err"; then
        [ "$(grep -c '"ceiling_ms": [0-9]' "$T/c.json")" = 2 ] && ok || bad "--ceiling JSON: $(cat "$T/c.json")"
        grep -q 'trace/ceiling' "$T/out" && grep -q 'a foveated ray costs [0-9.]* full-frame bare-Embree rays' "$T/out" &&
            ok || bad "--ceiling table: $(cat "$T/out")"
        out=$(python3 tools/check_schema.py docs/bench.schema.json "$T/c.json") && ok || bad "--ceiling JSON schema: $out"
    else
        bad "--ceiling bench failed: $(cat "$T/err")"
    fi
    # --stereo: the pair one eye after the other and through fv_pipeline_render_stereo, against
    # the ceiling on both eyes' rays (the run fails if the ceiling's rays differ from the eyes')
    if $B/fovea-bench --scene $SCENE --size 96x108 --frames 2 --warmup 1 --threads 2 --mode foveated --dof weak \
        --ceiling --stereo >"$T/out" 2>"$T/err"; then
        grep -q '^stereo pair (foveated, 2 x 96x108, medians of 2 pairs each, alternated): one eye after the other [0-9.]* ms, fv_pipeline_render_stereo [0-9.]* ms (.*); ceiling (both eyes. rays) [0-9.]* ms' "$T/out" &&
            ok || bad "bench --stereo line: $(cat "$T/out")"
    else
        bad "bench --stereo failed: $(cat "$T/err")"
    fi
    # DoF-driven sampling (issue 15 item 4): fewer rays than the acuity sampler alone where the
    # blur is strong (focus fixed near, everything behind blurred), and the ceiling retraces the
    # frame's own thinned rays (the bench fails if the counts differ)
    for ds in off on; do
        $B/fovea-bench --scene $SCENE --size 160x180 --fov 30 --frames 3 --warmup 1 --threads 2 --mode foveated \
            --dof strong --focus-m 0.3 --dof-sampling $ds --ceiling --counters off --json "$T/ds_$ds.json" \
            >"$T/out" 2>"$T/err" || bad "--dof-sampling $ds bench failed: $(cat "$T/err")"
    done
    n_off=$(sed -n 's/.*"samples_per_frame": \([0-9]*\).*/\1/p' "$T/ds_off.json")
    n_on=$(sed -n 's/.*"samples_per_frame": \([0-9]*\).*/\1/p' "$T/ds_on.json")
    [ -n "$n_on" ] && [ -n "$n_off" ] && [ "$n_on" -lt $((n_off * 3 / 4)) ] && ok ||
        bad "--dof-sampling on: $n_on rays per frame, off: $n_off"
else
    bad "bench failed: $(cat "$T/err")"
fi
# Profiling (issue 7): traces, bench JSON schema, counters, sweeps, kernel benchmarks.
expect_usage "bench bad sweep param" '--sweep: .speed=1. is not P=VALUES' $B/fovea-bench --scene $SCENE --sweep speed=1
expect_usage "bench bad sweep threads" '--sweep threads: 0 is out of range' $B/fovea-bench --scene $SCENE --sweep threads=0..2
expect_usage "bench bad sweep size" '--sweep size: .64. is not WxH' $B/fovea-bench --scene $SCENE --sweep size=64
expect_usage "bench sweep r0 > r1" '--sweep r0: r0 30 must not exceed r1 20' $B/fovea-bench --scene $SCENE --sweep r0=5,30
expect_usage "bench bad counters" '--counters: .maybe. is not one of on, off' $B/fovea-bench --scene $SCENE --counters maybe
expect_usage "bench unknown kernel" "--kernel: .nope. is not a kernel" $B/fovea-bench --kernels --kernel nope
expect_usage "bench calls without kernel" '--calls N needs --kernel NAME' $B/fovea-bench --kernels --calls 3
# the checkers themselves catch what they are for (so the checks below can fail)
printf '{"traceEvents":[{"ph":"M","pid":1,"tid":0,"name":"thread_name","args":{"name":"w"}},{"ph":"B","pid":1,"tid":0,"ts":1,"name":"x"}]}' >"$T/open.json"
# eval_eye (synthetic tracker accuracy): bad flags get one line and exit 2; a small run works
expect_usage "eval_eye bad size" "bad --size.*10x10" $BT/eval_eye --size 10x10
expect_usage "eval_eye bad frames" "bad --frames.*0" $BT/eval_eye --frames 0
expect_usage "eval_eye unknown flag" "unknown option.*--bogus" $BT/eval_eye --bogus
out=$($BT/eval_eye --frames 6 2>&1) && echo "$out" | grep -q "full view .*frames: median" && ok || bad "eval_eye run: $out"

python3 tools/check_trace.py "$T/open.json" 1 >/dev/null && bad "check_trace accepted an unclosed span" || ok
printf '{"scene": "x", "runs": []}' >"$T/schema-bad.json"
python3 tools/check_schema.py docs/bench.schema.json "$T/schema-bad.json" >/dev/null && bad "check_schema accepted a bad file" || ok
# a real trace: matched B/E, one track per worker, stage tracks, tile spans; counters switched
# off (as on a VM without a PMU): reported as unavailable with the reason, the bench succeeds;
# the JSON (with two sweeps) validates against the documented schema
if FOVEA_PERF=off $B/fovea-bench --scene $SCENE --size 96x108 --frames 2 --warmup 1 --threads 2 --dof weak \
    --trace-out "$T/trace.json" --sweep threads=1..2 --sweep pmin=0.1,0.3 --json "$T/p.json" >"$T/out" 2>"$T/err"; then
    ok
    out=$(python3 tools/check_trace.py "$T/trace.json" 2 --stages --tiles) && ok || bad "bench trace: $out"
    out=$(python3 tools/check_schema.py docs/bench.schema.json "$T/p.json") && ok || bad "bench JSON schema: $out"
    grep -q '"available": false, "reason": "switched off (FOVEA_PERF=off)"' "$T/p.json" && ok ||
        bad "counters not reported unavailable in the JSON"
    grep -q 'counters (foveated): unavailable: switched off' "$T/out" && ok || bad "counters not reported unavailable"
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); s=d["sweeps"]; assert [p["threads"] for p in s[0]["points"]]==[1,2] and [p["pmin"] for p in s[1]["points"]]==[0.1,0.3] and all(len(p["runs"])==2 for p in s[0]["points"]) and d["runs"][0]["roofline"]["coc"]["gbps"]>0' "$T/p.json" &&
        ok || bad "sweep points or roofline missing in $(head -c 400 "$T/p.json")"
else
    bad "profiling bench failed: $(cat "$T/err")"
fi
# counters on (whatever this machine has): the bench succeeds either way
FOVEA_PERF= $B/fovea-bench --scene $SCENE --size 64x72 --frames 1 --warmup 0 --mode foveated --json "$T/c.json" \
    >/dev/null 2>"$T/err" && grep -q '"counters": {"available": ' "$T/c.json" && ok || bad "bench with counters: $(cat "$T/err")"
# a one-thread trace has exactly one worker track
if $B/fovea-bench --scene $SCENE --size 64x72 --frames 1 --warmup 0 --threads 1 --mode full --trace-out "$T/t1.json" \
    >/dev/null 2>"$T/err"; then
    out=$(python3 tools/check_trace.py "$T/t1.json" 1 --stages --tiles) && ok || bad "1-thread trace: $out"
else
    bad "1-thread trace bench failed: $(cat "$T/err")"
fi
# the replay's trace, two eyes
if $R --scene $SCENE --frames 2 --size 64x72 --threads 2 --stereo --out "$T/rt" --trace-out "$T/rt.json" --quiet \
    2>"$T/err"; then
    out=$(python3 tools/check_trace.py "$T/rt.json" 2 --stages --tiles) && ok || bad "replay trace: $out"
else
    bad "replay with --trace-out failed: $(cat "$T/err")"
fi
# one kernel timed at production size, and an instruction-count call run
if $B/fovea-bench --kernels --kernel dof_coc_row --kernel-reps 1 --json "$T/k.json" >"$T/out" 2>"$T/err"; then
    out=$(python3 tools/check_schema.py docs/bench.schema.json "$T/k.json") && ok || bad "kernels JSON schema: $out"
    grep -q '"kernel": "dof_coc_row", .*"isa": "c"' "$T/k.json" && ok || bad "kernels JSON: $(cat "$T/k.json")"
else
    bad "--kernels failed: $(cat "$T/err")"
fi
$B/fovea-bench --kernels --kernel pull_row --calls 2 --isa c 2>"$T/err" | grep -q 'pull_row c x 2 calls' && ok ||
    bad "--kernels --calls: $(cat "$T/err")"

# fovea-track: bad eye input gets one line naming the problem, exit 2, and no CSV left behind
K=$B/fovea-track
V=assets/eye_synth.y4m
printf 'YUV4MPEG2 W8 H8 F30:1 Cmono\nFRAME\n' >"$T/trunc.y4m"
head -c 40 /dev/zero >>"$T/trunc.y4m"
printf 'YUV4MPEG2 W16 H16 F30:1 Cmono\nFRAME\n' >"$T/trunc2.y4m"
head -c 256 /dev/zero >>"$T/trunc2.y4m"
printf 'FRAME\n' >>"$T/trunc2.y4m"
head -c 100 /dev/zero >>"$T/trunc2.y4m"
printf 'YUV4MPEG2 W16 H16 F30:1 Cmono\nFRAMX\n' >"$T/corrupt.y4m"
printf 'RIFF garbage\n' >"$T/notyuv.y4m"
printf 'YUV4MPEG2 H16 F30:1\n' >"$T/now.y4m"
printf 'YUV4MPEG2 W16 H16 C420p10\n' >"$T/p10.y4m"
printf 'a.png 1 2 3\n' >"$T/fields.txt"
printf 'a.png 1 x\n' >"$T/label.txt"
printf '# only a comment\n\n' >"$T/empty.txt"
printf 'missing.png 3 4\n' >"$T/missing.txt"
printf 'not a png' >"$T/bad.png"
printf 'bad.png\n' >"$T/badimg.txt"
expect_usage "track no source" 'one of --images LIST, --video FILE or --device DEV is required' $K
expect_usage "track two sources" 'only one of' $K --video $V --images "$T/fields.txt"
# --device: the V4L2 path's errors name the call and the device (no camera on these machines)
expect_usage "track device not v4l2" 'VIDIOC_QUERYCAP on /dev/null: .*not a V4L2 device' $K --device /dev/null --out "$T/k1.csv"
expect_usage "track device missing" 'open on '"$T"'/video9: No such file' $K --device "$T/video9" --out "$T/k1.csv"
expect_usage "track device is a file" 'VIDIOC_QUERYCAP on .*bad.png' $K --device "$T/bad.png" --out "$T/k1.csv"
expect_usage "track bad ctrl" '--ctrl: control .bogus.: expected name=value' $K --device /dev/null --ctrl bogus
expect_usage "track ctrl without device" '--ctrl and --camera-size only apply to --device' $K --video $V --ctrl gain=3
expect_usage "track unknown flag" '--bogus: unknown option' $K --video $V --bogus
expect_usage "track bad bench" '--bench: 0 is out of range' $K --video $V --bench 0
expect_usage "track missing video" 'nope.y4m: No such file' $K --video "$T/nope.y4m" --out "$T/k1.csv"
expect_usage "track truncated y4m" 'trunc.y4m: frame 0 is truncated \(40 of 64 bytes\)' $K --video "$T/trunc.y4m" --out "$T/k1.csv"
expect_usage "track truncated later frame" 'trunc2.y4m: frame 1 is truncated \(100 of 256 bytes\)' $K --video "$T/trunc2.y4m" --out "$T/k1.csv"
expect_usage "track corrupt y4m" 'corrupt.y4m: frame 0: corrupt data \(no FRAME marker\)' $K --video "$T/corrupt.y4m" --out "$T/k1.csv"
expect_usage "track not y4m" 'notyuv.y4m: not a YUV4MPEG2 file' $K --video "$T/notyuv.y4m" --out "$T/k1.csv"
expect_usage "track y4m without W" 'now.y4m: the header lacks W or H' $K --video "$T/now.y4m" --out "$T/k1.csv"
expect_usage "track y4m 10 bit" 'p10.y4m: colour space C420p10 is not supported' $K --video "$T/p10.y4m" --out "$T/k1.csv"
expect_usage "track list fields" 'fields.txt:1: 4 fields, expected PATH \[X Y\]' $K --images "$T/fields.txt" --out "$T/k1.csv"
expect_usage "track list label" 'label.txt:1: label .1 x. is not two numbers' $K --images "$T/label.txt" --out "$T/k1.csv"
expect_usage "track empty list" 'empty.txt: no images listed' $K --images "$T/empty.txt" --out "$T/k1.csv"
expect_usage "track missing image" 'missing.txt:1: missing.png: No such file' $K --images "$T/missing.txt" --out "$T/k1.csv"
expect_usage "track corrupt image" 'badimg.txt:1: bad.png: ' $K --images "$T/badimg.txt" --out "$T/k1.csv"
expect_usage "track list is a directory" '(directory|read error)' $K --images "$T" --out "$T/k1.csv"
[ ! -e "$T/k1.csv" ] && [ ! -e "$T/k1.csv.tmp" ] && ok || bad "fovea-track bad input left $T/k1.csv behind"
if $K --help >"$T/help" 2>&1 && grep -q -- --images "$T/help"; then ok; else bad "fovea-track --help"; fi

# A good run on the bundled synthetic video: one line per frame, PATH_OR_FRAME,X,Y,CONF
if $K --video $V --out "$T/track.csv" --quiet >"$T/out" 2>"$T/err"; then
    hl=$(head -n 1 $V | wc -c)
    w=$(head -n 1 $V | sed 's/.* W\([0-9]*\) .*/\1/'); h=$(head -n 1 $V | sed 's/.* H\([0-9]*\) .*/\1/')
    frames=$(( ($(wc -c <$V) - hl) / (6 + w * h) ))
    rows=$(wc -l <"$T/track.csv")
    [ "$rows" -eq "$frames" ] && ok || bad "track.csv has $rows lines for $frames frames"
    grep -Eqv '^[0-9]+,([0-9.]+,[0-9.]+|,),[0-9.]+$' "$T/track.csv" && bad "track.csv line format: $(grep -Ev '^[0-9]+,([0-9.]+,[0-9.]+|,),[0-9.]+$' "$T/track.csv" | head -1)" || ok
    grep -q 'frames, pupil found in' "$T/out" && ok || bad "track summary: $(cat "$T/out")"
else
    bad "track good run failed: $(cat "$T/err")"
fi
# --mode: a bad value is one line and exit 2; auto (the default) gives the same CSV as no flag, and
# so does headset on this 320x240 video (auto picks headset above a 160 px short side)
expect_usage "track bad mode" "--mode: 'bogus' is not one of auto, headset, crop" $K --video $V --mode bogus --out "$T/k1.csv"
for m in auto headset; do
    if $K --video $V --mode $m --out "$T/track_$m.csv" --quiet >/dev/null 2>"$T/err" && cmp -s "$T/track.csv" "$T/track_$m.csv"; then ok
    else bad "track --mode $m differs from no --mode: $(head -c 300 "$T/err")"; fi
done
if $K --video $V --mode crop --frames 3 --out "$T/track_crop.csv" --quiet >/dev/null 2>"$T/err" &&
    [ "$(wc -l <"$T/track_crop.csv")" -eq 3 ]; then ok; else bad "track --mode crop: $(head -c 300 "$T/err")"; fi
# fovea-replay's own Y4M (C420jpeg, 128x72, 2 frames) reads back
if [ -s "$T/v.y4m" ] && $K --video "$T/v.y4m" --out "$T/v.csv" --quiet >"$T/out" 2>"$T/err"; then
    [ "$(wc -l <"$T/v.csv")" -eq 2 ] && ok || bad "track on the replay's C420jpeg video: $(cat "$T/v.csv")"
else
    bad "track on the replay's C420jpeg video failed: $(cat "$T/err")"
fi
# With labels: the detection rates within 1, 2, 3 and 5 px (labels here: the ground truth)
awk -F, 'NR > 1 && NR <= 6 { printf "f%d.pgm %s %s\n", NR - 2, $7, $8 }' assets/eye_synth.csv >"$T/lab.txt"
i=0
while [ $i -lt 5 ]; do
    # frame i of the Cmono video as a PGM: the header, then the luma bytes
    w=$(head -n 1 $V | sed 's/.* W\([0-9]*\) .*/\1/'); h=$(head -n 1 $V | sed 's/.* H\([0-9]*\) .*/\1/')
    hl=$(head -n 1 $V | wc -c)
    { printf 'P5 %s %s 255\n' "$w" "$h"; tail -c +$((hl + 1 + i * (6 + w * h) + 6)) $V | head -c $((w * h)); } >"$T/f$i.pgm"
    i=$((i + 1))
done
if $K --images "$T/lab.txt" --quiet >"$T/out" 2>"$T/err"; then
    grep -Eq 'all +5 labelled: +<=1px +100\.0% +<=2px +100\.0% +<=3px +100\.0% +<=5px +100\.0%' "$T/out" && ok \
        || bad "track rates on labelled synthetic frames: $(cat "$T/out")"
else
    bad "track labelled run failed: $(cat "$T/err")"
fi
# ---- fovea-headset: start-up faults exit 2 with one line; mid-run faults fall back and go on
HS=$B/fovea-headset
HO="--scene $SCENE --size 64x72 --threads 2"
expect_usage "headset bad shadows" '--shadows: .1. is not one of on, off' $HS $HO --shadows 1
$HS --help 2>&1 | grep -q -- '--shadows on|off' && ok || bad "headset --help lacks --shadows"
expect_usage "headset bad gpio chip" 'gpiod_chip_open_lookup\(nochip\)' $HS $HO --vsync gpio:nochip:3
expect_usage "headset bad gpio line" 'gpio:gpiochip0:x.*LINE must be' $HS $HO --vsync gpio:gpiochip0:x
expect_usage "headset bad gpio edge" 'LINE must be.*EDGE' $HS $HO --vsync gpio:gpiochip0:3:sideways
if [ -e /dev/gpiochip0 ]; then
    expect_usage "headset gpio line out of range" 'line 65535 out of range' $HS $HO --vsync gpio:gpiochip0:65535
fi
expect_usage "headset bad vsync" '--vsync sync:1: want gpio' $HS $HO --vsync sync:1
expect_usage "headset bad timer rate" '--vsync timer:0: HZ' $HS $HO --vsync timer:0
expect_usage "headset missing vsync replay" 'nope.txt: No such file' $HS $HO --vsync replay:"$T/nope.txt"
expect_usage "headset missing camera" '/dev/video99' $HS $HO --camera /dev/video99
expect_usage "headset missing camera replay" 'nope.y4m' $HS $HO --camera replay:"$T/nope.y4m"
expect_usage "headset kms cannot open" 'open\(/dev/dri/card99\)' $HS $HO --display kms:/dev/dri/card99
expect_usage "headset fbdev cannot open" "open\\($T/nofb\\)" $HS $HO --display fbdev:"$T/nofb"
expect_usage "headset png dir cannot be made" '/proc/fovea-no' $HS $HO --display png:/proc/fovea-no/dir
expect_usage "headset bad display" '--display tv: want kms' $HS $HO --display tv
expect_usage "headset unwritable latency csv" '/proc/fovea-no/l.csv' $HS $HO --seconds 5 --latency-csv /proc/fovea-no/l.csv
expect_usage "headset unwritable trace-out" '/proc/fovea-no/p.json' $HS $HO --seconds 5 --trace-out /proc/fovea-no/p.json
expect_usage "headset calibration without camera" '--calibration only applies with --camera' $HS $HO --calibration x
printf 'fovea-calibration 1\ninput pupil\nnorm 320 240 100\nyaw_deg 0 20 0 0 0 0\npitch_deg 0 0 -15 0 0 0\nsamples 1e300\n' >"$T/huge.cal"
expect_usage "headset calibration count out of range" 'huge.cal.*line 6: samples 1e\+300 out of range' $HS $HO --camera replay:assets/eye_synth.y4m --calibration "$T/huge.cal"
# the calibration procedure on a scripted wearer's eye video (tools/gen_eye --calibration): the
# contract line, a file that --calibration then accepts; a wearer blinking through every target and
# a camera that stops: a message naming why, exit 1, no file
GE=$BT/gen_eye
expect_usage "headset calibrate without camera" '--calibrate needs --camera' $HS --calibrate "$T/c.cal"
if $GE --calibration 600 --fps 120 --supersample 1 --out "$T/cal.y4m" --truth "$T/cal.csv" 2>"$T/err" &&
   $HS --calibrate "$T/c.cal" --calibrate-dwell-ms 600 --camera replay:"$T/cal.y4m" --display png:"$T/calpng" \
       --size 160x180 >"$T/out" 2>"$T/err"; then
    grep -Eq '^calibration: 9 points, validation mean 0\.[0-4][0-9] deg, max 0\.[0-9][0-9] deg$' "$T/out" && ok ||
        bad "calibrate summary: $(tail -n 2 "$T/out")"
    [ "$(ls "$T/calpng" | wc -l)" -eq 13 ] && ok || bad "calibrate showed $(ls "$T/calpng" | wc -l) targets, want 13"
    if $HS $HO --seconds 0.5 --camera replay:"$T/cal.y4m" --calibration "$T/c.cal" >"$T/out" 2>"$T/err"; then ok
    else bad "the written calibration was not accepted: $(cat "$T/err")"; fi
else
    bad "calibrate run failed: $(cat "$T/err")"
fi
blinks=
for k in $(seq 0 21); do blinks="$blinks --blink-at $((k * 600 + 310)) --blink-at $((k * 600 + 450))"; done
# shellcheck disable=SC2086
$GE --calibration 600 --fps 120 --supersample 1 --frames 1700 $blinks --out "$T/blink.y4m" --truth "$T/blink.csv"
if $HS --calibrate "$T/b.cal" --calibrate-dwell-ms 600 --camera replay:"$T/blink.y4m" >"$T/out" 2>"$T/err"; then
    bad "calibration through blinks succeeded"
else
    [ "$(wc -l <"$T/err")" -eq 1 ] && grep -q 'calibration failed: only 0 of the 9 grid points had a stable fixation' "$T/err" &&
        [ ! -e "$T/b.cal" ] && [ ! -e "$T/b.cal.tmp" ] && ok || bad "calibration through blinks: $(cat "$T/err")"
fi
head -c $((38 + 6 * 320 * 240 * 3)) "$T/cal.y4m" >"$T/cut.y4m" 2>/dev/null # (about 3 frames' worth)
if $HS --calibrate "$T/s.cal" --calibrate-dwell-ms 600 --camera replay:"$T/cut.y4m" >"$T/out" 2>"$T/err"; then
    bad "calibration on a video that stops succeeded"
else
    grep -q 'the eye camera stopped.*before the procedure ended' "$T/err" && [ ! -e "$T/s.cal" ] && ok ||
        bad "calibration camera stop: $(cat "$T/err")"
fi
printf 'k1 0.1\nk9 1\n' >"$T/bad.lens"
expect_usage "headset bad lens" 'bad.lens:2: unknown key' $HS $HO --lens "$T/bad.lens"
# --lens in replay and bench too (issue 16 item 3): a bad profile is refused; a good one renders with
# reprojection (on by default, and --reproject on is accepted), the same bytes for 1, 2 and 5 threads,
# and differs from the lensless frame and from the lensed frame without reprojection
expect_usage "replay bad lens" 'bad.lens:2: unknown key' $R --scene $SCENE --out "$T/ol" --lens "$T/bad.lens"
expect_usage "bench bad lens" 'bad.lens:2: unknown key' $B/fovea-bench --scene $SCENE --lens "$T/bad.lens"
for th in 1 2 5; do
    $R --scene $SCENE --size 64x72 --frames 3 --stereo --trace assets/gaze_sweep.csv --lens assets/hmd_example.lens --reproject on --threads $th --quiet \
        --out "$T/lens$th" >/dev/null 2>&1 || bad "replay --lens --reproject on run ($th threads)"
done
$R --scene $SCENE --size 64x72 --frames 3 --stereo --trace assets/gaze_sweep.csv --reproject on --threads 2 --quiet --out "$T/nolens" >/dev/null 2>&1
$R --scene $SCENE --size 64x72 --frames 3 --stereo --trace assets/gaze_sweep.csv --lens assets/hmd_example.lens --reproject off --threads 2 --quiet \
    --out "$T/lensoff" >/dev/null 2>&1
f=frame_00002.png
if [ -s "$T/lens1/$f" ] && cmp -s "$T/lens1/$f" "$T/lens2/$f" && cmp -s "$T/lens1/$f" "$T/lens5/$f" &&
    ! cmp -s "$T/lens2/$f" "$T/nolens/$f" && ! cmp -s "$T/lens2/$f" "$T/lensoff/$f"; then ok
else bad "replay --lens --reproject on: frames differ between thread counts, or equal the lensless or unreprojected frame"; fi
$B/fovea-bench --scene $SCENE --size 64x72 --frames 2 --warmup 1 --yaw-rate 30 --lens assets/hmd_example.lens --reproject on \
    --counters off >"$T/out" 2>&1 && awk '/^foveated/ { ok = $3 ~ /^[0-9.]+$/ } END { exit !ok }' "$T/out" && ok ||
    bad "bench --lens --reproject on: no reprojection time: $(tail -n 3 "$T/out")"
expect_usage "headset bad dof-sampling" '--dof-sampling: .1. is not one of on, off' $HS $HO --dof-sampling 1
expect_usage "headset no scene" '--scene FILE is required' $HS --size 64x72

# good runs: the summary's contract lines (DESIGN.md), a latency CSV with one row per refresh
# (--timewarp on, the default) or per frame (--timewarp off)
L1='^fovea-headset: displayed [0-9]+ frames \([0-9.]+ Hz\), rendered [0-9]+ frames \([0-9.]+ Hz\), late [0-9]+$'
L2='motion-to-photon p50 [0-9.]+ ms p99 [0-9.]+ ms; gaze-to-photon p50 [0-9.]+ ms p99 [0-9.]+ ms$'
if $HS $HO --seconds 1 --trace assets/gaze_sweep.csv --latency-csv "$T/lat.csv" >"$T/out" 2>"$T/err"; then
    head -n 1 "$T/out" | grep -Eq "$L1" && ok || bad "headset summary first line: $(head -n 1 "$T/out")"
    grep -Eq "$L2" "$T/out" && ok || bad "headset summary latency line: $(cat "$T/out")"
    grep -q 'timewarp on' "$T/out" && ok || bad "headset timewarp not on by default: $(cat "$T/out")"
    n=$(sed -n 's/^  \([0-9]*\) refreshes in.*/\1/p' "$T/out")
    [ -n "$n" ] && [ "$n" -gt 50 ] && [ "$(($(wc -l <"$T/lat.csv") - 1))" -eq "$n" ] && ok \
        || bad "headset latency csv: $n refreshes, $(wc -l <"$T/lat.csv") lines"
    head -n 1 "$T/lat.csv" | grep -q '^refresh,frame,reused,late,head_t_ms,gaze_t_ms' && ok \
        || bad "headset csv header: $(head -n 1 "$T/lat.csv")"
    # every refresh after the first frame showed one, frame numbers never go back
    awk -F, 'NR > 1 { if ($2 < 0) { if (seen) bad++; next } if (seen && $2 < last) bad++; seen = 1; last = $2 }
             END { exit bad > 0 }' "$T/lat.csv" && ok || bad "headset refreshes without a frame or going back"
else
    bad "headset good run failed: $(cat "$T/err")"
fi
if $HS $HO --seconds 1 --trace assets/gaze_sweep.csv --timewarp off --latency-csv "$T/lat0.csv" >"$T/out" 2>"$T/err"; then
    head -n 1 "$T/out" | grep -Eq "$L1" && ok || bad "headset --timewarp off first line: $(head -n 1 "$T/out")"
    grep -Eq "$L2" "$T/out" && ok || bad "headset --timewarp off latency line: $(cat "$T/out")"
    n=$(sed -n 's/^  \([0-9]*\) frames in.*/\1/p' "$T/out")
    [ -n "$n" ] && [ "$n" -gt 5 ] && [ "$(($(wc -l <"$T/lat0.csv") - 1))" -eq "$n" ] && ok \
        || bad "headset --timewarp off latency csv: $n frames, $(wc -l <"$T/lat0.csv") lines"
    head -n 1 "$T/lat0.csv" | grep -q '^frame,gaze_t_ms,ray_start_ms,done_ms,target_ms,photon_ms,gaze_to_photon_ms' && ok \
        || bad "headset --timewarp off csv header: $(head -n 1 "$T/lat0.csv")"
else
    bad "headset --timewarp off run failed: $(cat "$T/err")"
fi
if $HS $HO --seconds 1 --warp-threads 2 >"$T/out" 2>"$T/err"; then
    head -n 1 "$T/out" | grep -Eq "$L1" && grep -Eq "$L2" "$T/out" && ok || bad "headset --warp-threads 2: $(cat "$T/out")"
else
    bad "headset --warp-threads 2 run failed: $(cat "$T/err")"
fi
expect_usage "headset bad warp threads" '--warp-threads: 3 is out of range' $HS $HO --warp-threads 3
expect_usage "headset bad timewarp" "--timewarp: 'sideways'" $HS $HO --timewarp sideways
# --lens with the timewarp (and reprojection): the contract lines, timewarp on
if $HS $HO --seconds 1 --trace assets/gaze_sweep.csv --lens assets/hmd_example.lens --timewarp on --reproject on --display png:"$T/lpng" \
    >"$T/out" 2>"$T/err"; then
    head -n 1 "$T/out" | grep -Eq "$L1" && grep -Eq "$L2" "$T/out" && grep -q 'timewarp on' "$T/out" && ok ||
        bad "headset --lens --timewarp on: $(cat "$T/out")"
    ls "$T/lpng"/frame_00000.png >/dev/null 2>&1 && ok || bad "headset --lens --timewarp on wrote no frame"
else
    bad "headset --lens --timewarp on failed: $(cat "$T/err")"
fi
# --trace-out: valid trace, one track per worker, the stage tracks and the loop's markers
if $HS $HO --seconds 2 --trace-out "$T/hs.json" >"$T/out" 2>"$T/err"; then
    out=$(python3 tools/check_trace.py "$T/hs.json" 2 --stages) && ok || bad "headset trace: $out"
    for m in 'gaze latch' 'vsync'; do grep -q "\"name\": *\"$m\"" "$T/hs.json" && ok || bad "headset trace lacks $m markers"; done
else
    bad "headset --trace-out failed: $(cat "$T/err")"
fi
if $HS $HO --seconds 1 --camera replay:$V --lens assets/hmd_example.lens --display png:"$T/hpng" >"$T/out" 2>"$T/err"; then
    ls "$T/hpng"/frame_00000.png >/dev/null 2>&1 && ok || bad "headset png display wrote nothing"
    grep -Eq 'camera: [1-9][0-9]* frames tracked$' "$T/out" && ok || bad "headset camera replay: $(cat "$T/out")"
else
    bad "headset camera + png run failed: $(cat "$T/err")"
fi
# mid-run: the eye video breaks off (truncated frame): last good gaze, frames go on
hl=$(head -n 1 $V | wc -c)
head -c $((hl + 30 * (6 + 320 * 240) + 100)) $V >"$T/cut.y4m"
if $HS $HO --seconds 1.5 --camera replay:"$T/cut.y4m" --camera-fps 240 >"$T/out" 2>"$T/err"; then
    grep -q 'camera failed (.*cut.y4m.*); keeping the last good gaze' "$T/err" && ok || bad "headset camera fault: $(cat "$T/err")"
    grep -q 'failed mid-run' "$T/out" && ok || bad "headset camera fault summary: $(cat "$T/out")"
else
    bad "headset run with a camera failing mid-run exited: $(cat "$T/err")"
fi
# mid-run: the vsync line goes silent after 30 edges: predictor, then the timer; frames go on
awk 'BEGIN { for (i = 0; i < 30; i++) printf "%d\n", 5000000000 + i * 11111111 }' >"$T/edges.txt"
if $HS $HO --seconds 1.5 --vsync replay:"$T/edges.txt" --latency-csv "$T/sil.csv" >"$T/out" 2>"$T/err"; then
    grep -q 'state timer' "$T/out" && ok || bad "headset silent vsync: $(cat "$T/out")"
    n=$(grep -c ',timer,' "$T/sil.csv")
    [ "$n" -ge 3 ] && ok || bad "headset stopped presenting when the line went silent: $n frames on the timer"
else
    bad "headset silent vsync run failed: $(cat "$T/err")"
fi
# mid-run: the PNG display's folder vanishes: falls back to none, keeps presenting; SIGINT ends
# the run cleanly with the summary (polls: slow under the sanitizers)
mkdir -p "$T/vanish"
$HS $HO --display png:"$T/vanish/png" >"$T/out" 2>"$T/err" &
hp=$!
i=0
while [ ! -e "$T/vanish/png/frame_00001.png" ] && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
# moved away in one step (rm -rf races with the frames still being written into it)
mv "$T/vanish" "$T/vanished"
rm -rf "$T/vanished"
i=0
while ! grep -q 'continuing without a display' "$T/err" && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
sleep 0.3
kill -INT $hp
wait $hp
rc=$?
[ "$rc" -eq 0 ] && ok || bad "headset SIGINT: exit $rc: $(cat "$T/err")"
grep -q 'display png failed (.*); continuing without a display' "$T/err" && ok || bad "headset display fault: $(cat "$T/err")"
grep -q 'display none' "$T/out" && grep -q 'gaze-to-photon p50' "$T/out" && ok || bad "headset summary after SIGINT: $(cat "$T/out")"
n=$(sed -n 's/^fovea-headset: displayed \([0-9]*\) frames.*/\1/p' "$T/out")
[ -n "$n" ] && [ "$n" -gt 2 ] && ok || bad "headset frames after the display fault: $n"

echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
