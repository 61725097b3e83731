#!/usr/bin/env python3
"""NEON speed-ups without NEON hardware: counts the guest instructions each kernel of
fovea-bench's kernel table runs under qemu-aarch64, C reference against NEON.

usage: tools/kernel_icount.py [--build build-aarch64] [--calls 4] [--kernel NAME] [--json FILE]

How (Debian's qemu-user 7.2 ships no TCG plugins, so no libinsn.so; valgrind is not used):
  1. `fovea-bench --kernels --kernel K --calls N --isa I` sets the kernel's production-sized
     inputs up, makes N calls and prints where the kernel's code is (guest addresses);
  2. the code's extent comes from `aarch64-linux-gnu-nm -S` (symbol sizes, the binary is PIE and
     qemu-user loads it at 0x5500000000); the taa entry also counts fv_taa_tile_run;
  3. qemu-aarch64 runs it again with `-d in_asm,exec,nochain -dfilter RANGES`: in_asm logs every
     translated block in those ranges with its instructions, exec (with chaining off) every
     execution of such a block; instructions = sum over executions of the block's length.
Only instructions inside the kernel's own functions count (calls into libm or other helpers
are not; the kernels make none). The set-up is outside the ranges, so it costs nothing in the
log. Prints instructions per call and the C / NEON ratio (a proxy for the speed-up: it ignores
latencies, memory and issue width).
"""
import json
import os
import re
import subprocess
import sys
import tempfile

BASE = 0x5500000000  # where qemu-user puts a PIE aarch64 executable


def arg(name, default):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return default


def kernels(bench):
    # the table's names: from a one-rep timing listing would be slow under qemu; ask the source
    src = open(os.path.join(os.path.dirname(__file__), "..", "core", "kbench.c")).read()
    tab = src[src.index("const fv_kbench_kernel fv_kbench_kernels[]"):]
    return re.findall(r'^\s*\{"([a-z0-9_+]+)",', tab, re.M)


def symbols(bench):
    syms = []
    out = subprocess.run(["aarch64-linux-gnu-nm", "-S", "--defined-only", bench], capture_output=True,
                         text=True, check=True).stdout
    for line in out.splitlines():
        p = line.split()
        if len(p) == 4 and p[2] in "tTwW":
            syms.append((int(p[0], 16), int(p[1], 16), p[3]))
    return syms


def count(bench, kernel, isa, calls, syms):
    r = subprocess.run(["qemu-aarch64", bench, "--kernels", "--kernel", kernel, "--calls", str(calls), "--isa", isa],
                       capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(r.stderr.strip())
    addrs = [int(a, 16) for a in re.findall(r"0x[0-9a-f]+", r.stdout.split("code at")[1])]
    ranges, fnames = [], []
    for a in addrs:
        for s, n, name in syms:
            if s + BASE == a:
                ranges.append((a, n))
                fnames.append(name)
    if kernel.startswith("taa"):
        for s, n, name in syms:
            if name == "fv_taa_tile_run":
                ranges.append((s + BASE, n))
                fnames.append(name)
    if not ranges:
        raise RuntimeError("no symbol at %s" % addrs)
    with tempfile.TemporaryDirectory() as d:
        log = os.path.join(d, "q.log")
        dfilter = ",".join("0x%x+0x%x" % (a, n) for a, n in ranges)
        subprocess.run(["qemu-aarch64", "-d", "in_asm,exec,nochain", "-dfilter", dfilter, "-D", log, bench,
                        "--kernels", "--kernel", kernel, "--calls", str(calls), "--isa", isa],
                       capture_output=True, check=True)
        tb, cur, total = {}, None, 0
        with open(log, errors="replace") as f:
            for line in f:
                if line.startswith("IN:"):
                    cur = None
                    continue
                m = re.match(r"^0x([0-9a-f]+):\s", line)
                if m:
                    pc = int(m.group(1), 16)
                    if cur is None:
                        cur = pc
                        tb[cur] = 0
                    tb[cur] += 1
                    continue
                if not line.strip():
                    cur = None
                    continue
                m = re.match(r"^Trace \d+: \S+ \[[0-9a-f]+/([0-9a-f]+)/", line)
                if m:
                    total += tb.get(int(m.group(1), 16), 0)
    return total / calls, fnames


def main():
    build = arg("--build", "build-aarch64")
    calls = int(arg("--calls", "4"))
    only = arg("--kernel", None)
    bench = os.path.join(build, "bin", "fovea-bench")
    syms = symbols(bench)
    res = []
    print("%-20s %14s %14s %8s   (instructions per call, qemu-aarch64, %d calls)" % ("kernel", "c", "neon", "c/neon",
                                                                                     calls))
    for k in kernels(bench):
        if only and k != only:
            continue
        c, cf = count(bench, k, "c", calls, syms)
        n, nf = count(bench, k, "neon", calls, syms)
        same = cf == nf  # no NEON version: the C one twice
        print("%-20s %14.0f %14s %8s   %s" % (k, c, "-" if same else "%.0f" % n, "-" if same else "%.2fx" % (c / n),
                                            " ".join(nf)))
        res.append({"kernel": k, "c_insns_per_call": c, "neon_insns_per_call": None if same else n,
                    "ratio": None if same else c / n})
    if "--json" in sys.argv:
        with open(arg("--json", None), "w") as f:
            json.dump({"kernel_icount": {"calls": calls, "results": res}}, f, indent=1)


main()
