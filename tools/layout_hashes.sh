#!/bin/sh
# Behaviour fingerprint for refactors: renders a fixed set of frames (foveated / full, every DoF
# model, stereo, lens, thin-lens reference), tracks the shared eye set and the bundled eye video,
# and lists the bench JSON's keys; prints one "sha256  name" line per output. Run it before and
# after a change that must not alter behaviour and diff the two listings.
#   tools/layout_hashes.sh [BUILD] > hashes.txt      (BUILD defaults to build)
set -eu
B=${1:-build}
SHARED=${SHARED:-../shared}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
R="$B/bin/fovea-replay"
S=assets/range.glb
small="--size 320x360 --quiet --threads 2"
run() { # name, args...
    n=$1; shift
    "$R" --out "$T/$n" $small "$@" >/dev/null
    for f in "$T/$n"/frame_*.png; do sha256sum "$f" | sed "s|$T/||"; done
}
run fov          --scene $S --trace assets/gaze_sweep.csv --frames 4
run full         --scene $S --trace assets/gaze_sweep.csv --frames 2 --full
run stereo       --scene $S --trace assets/gaze_sweep.csv --frames 3 --stereo
run threads1     --scene $S --trace assets/gaze_sweep.csv --frames 3 --threads 1
for m in weier hussain mantiuk konrad liu; do
    run dof-$m   --scene $S --trace assets/gaze_sweep.csv --frames 3 --dof medium --dof-model $m
done
run dof-chroma   --scene $S --frames 2 --dof strong --dof-model liu --chroma on
run dof-full     --scene $S --frames 2 --dof weak --full
run isa-c        --scene $S --trace assets/gaze_sweep.csv --frames 3 --dof medium --isa c
run contrast     --scene $S --frames 2 --contrast-gain 0.5
run reference    --scene $S --frames 1 --reference 4 --dof medium
run refpin       --scene $S --frames 1 --reference 2 --dof none
if [ -d "assets/scenes/FlightHelmet" ]; then
    run helmet   --scene "assets/scenes/FlightHelmet/FlightHelmet.gltf" --frames 2 --dof strong
fi
# tracker CSVs
Tr="$B/bin/fovea-track"
"$Tr" --video assets/eye_synth.y4m --out "$T/track_synth.csv" --quiet >/dev/null
sha256sum "$T/track_synth.csv" | sed "s|$T/||"
"$Tr" --video assets/eye_synth.y4m --out "$T/track_synth_c.csv" --quiet --isa c >/dev/null
sha256sum "$T/track_synth_c.csv" | sed "s|$T/||"
if [ -f "$SHARED/assets/eyes/mrl-dev/pupil.txt" ]; then
    "$Tr" --images "$SHARED/assets/eyes/mrl-dev/pupil.txt" --out "$T/track_mrl.csv" --quiet >/dev/null
    sha256sum "$T/track_mrl.csv" | sed "s|$T/||"
fi
# bench JSON keys (values are times; the keys are the contract)
"$B/bin/fovea-bench" --scene $S --size 160x180 --frames 1 --warmup 0 --mode both --dof weak \
    --json "$T/bench.json" --counters off >/dev/null
python3 - "$T/bench.json" <<'PY'
import json, sys
def keys(o, p=""):
    if isinstance(o, dict):
        for k, v in o.items(): yield from keys(v, p + "/" + k)
    elif isinstance(o, list):
        for v in o[:1]: yield from keys(v, p + "[]")
    else: yield p
print("bench-keys", " ".join(sorted(set(keys(json.load(open(sys.argv[1])))))))
PY
