#!/bin/sh
# Runs fovea's test binaries (cmocka: tests/test_*, tests/checkasm/checkasm) and the command-line
# tests, then prints one summary line
# "tests: N passed, N failed". Env: BUILD (build dir), SHARED (../shared), RUNNER (e.g.
# qemu-aarch64 for the cross leg). --core: only the core's test binaries (no app/CLI tests).
set -u
BUILD=${BUILD:-build}
export SHARED=${SHARED:-../shared}
RUNNER=${RUNNER:-}
core_only=0
[ "${1:-}" = "--core" ] && core_only=1
pass=0 fail=0 failed_names=
log=$(mktemp)
for t in "$BUILD"/tests/test_* "$BUILD"/tests/checkasm/checkasm; do
    [ -x "$t" ] || continue
    name=$(basename "$t")
    echo "== $name"
    # shellcheck disable=SC2086
    $RUNNER "$t" >"$log" 2>&1
    rc=$?
    cat "$log"
    p=$(sed -n 's/.*\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -n 1)
    f=$(sed -n 's/.*\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -n 1)
    p=${p:-0} f=${f:-0}
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "!! $name exited with status $rc without a cmocka failure count (crash?)"
        f=1
    fi
    pass=$((pass + p)) fail=$((fail + f))
    [ "$f" -ne 0 ] && failed_names="$failed_names $name"
done
rm -f "$log"
if [ "$core_only" -eq 0 ]; then
    echo "== cli"
    out=$(BUILD="$BUILD" sh tests/cli.sh 2>&1)
    echo "$out"
    p=$(echo "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p')
    f=$(echo "$out" | sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p')
    [ -z "$p" ] && { p=0; f=1; }
    pass=$((pass + p)) fail=$((fail + f))
    [ "$f" -ne 0 ] && failed_names="$failed_names cli"
fi
[ -n "$failed_names" ] && echo "failing:$failed_names"
echo "tests: $pass passed, $fail failed"
[ "$fail" -eq 0 ] && [ "$pass" -gt 0 ]
