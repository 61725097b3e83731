#!/usr/bin/env python3
"""NEON speed-ups without NEON hardware: counts the guest instructions each kernel of
fovea-bench's kernel table runs under qemu-aarch64, C reference against NEON.

usage: tools/kernel_icount.py [--build build-aarch64] [--calls 4] [--kernel NAME] [--json FILE]
                              [--by-function]

How (Debian's qemu-user 7.2 ships no TCG plugins, so no libinsn.so; valgrind is not used):
  1. `fovea-bench --kernels --kernel K --calls N --isa I` sets the kernel's production-sized
     inputs up, makes N calls and prints where the kernel's code is (guest addresses);
  2. the code's extent comes from `aarch64-linux-gnu-nm -S` (symbol sizes, the binary is PIE and
     qemu-user loads it at 0x5500000000) and each function's compilation unit from the DWARF
     address ranges (`readelf --debug-dump=aranges,info`);
  3. qemu-aarch64 runs it twice (N and 3N calls) with `-d in_asm,exec,nochain -dfilter RANGES`: in_asm logs every
     translated block in those ranges with its instructions, exec (with chaining off) every
     execution of such a block; instructions = sum over executions of the block's length.
The ranges are every function of the compilation units (.c files) the kernel's entry points are
in (their static helpers, e.g. reproject's `tap`, and functions instantiated from a template
header such as reproject_tmpl.h) and, for NEON, of the C reference's units too (the NEON kernels
finish odd tails with the C reference); calls into libc / libm or other units are not counted
(the kernels make none). Set-up code in those units cancels out: each count is the difference
between a run of N and one of 3N calls, over 2N. Prints instructions per call and the C / NEON
ratio (a proxy for the speed-up: it ignores latencies, memory and issue width). --by-function
also prints each counted function's share (instructions per call).

Changed 2026-11-28 (kern8): the units were the files `nm -l` names, i.e. where each function is
*declared*; a function instantiated from a template header was then attributed to the header
and left out. For `taa_blend+taa_fill` the C side lost its whole blend (`taa_blend_c`, from
reproject_tmpl.h: 12401 of the C reference's 26598 instructions a tile) while the NEON side
kept `taa_blend_neon` (its entry is in reproject_blend_tmpl.h, counted because it is the entry's
own file): 1.01x was C's fill + taps against NEON's blend + fill. The taa entries counted
fv_taa_tile_run's file, reproject.c, on both sides: it holds fv_taa_project, which the taa_aa
kernels call per pixel (still counted), and the shared tile driver fv_taa_tile_run(_keep) /
fv_taa_tile_setup (plain C, ~170 instructions a tile on both sides, no longer counted: it is the
bench's harness, not the kernels).
"""
import json
import os
import re
import subprocess
import sys
import tempfile

BASE = 0x5500000000  # where qemu-user puts a PIE aarch64 executable
TAA_DRIVER = ("fv_taa_tile_run", "fv_taa_tile_run_keep", "fv_taa_tile_setup")  # the bench's harness: not counted


def arg(name, default):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return default


def kernels(bench):
    # the table's names: from a one-rep timing listing would be slow under qemu; ask the source
    src = open(os.path.join(os.path.dirname(__file__), "..", "tests", "checkasm", "bench.c")).read()
    tab = src[src.index("const checkasm_bench_kernel checkasm_bench_kernels[]"):]
    return re.findall(r'^\s*\{"([a-z0-9_+]+)",', tab, re.M)


def units(bench):
    """[(start, end, compilation unit name)] from the DWARF address ranges."""
    def rd(what):
        return subprocess.run(["aarch64-linux-gnu-readelf", "--debug-dump=" + what] +
                              (["--dwarf-depth=1"] if what == "info" else []) + [bench],
                              capture_output=True, text=True, check=True).stdout
    names, cu = {}, None
    for line in rd("info").splitlines():
        m = re.match(r"\s*Compilation Unit @ offset (0x[0-9a-f]+|\d+):", line)
        if m:
            cu = int(m.group(1), 0)
        elif cu is not None and "DW_AT_name" in line and cu not in names:
            names[cu] = line.split(":")[-1].strip()
    res, cu = [], None
    for line in rd("aranges").splitlines():
        m = re.match(r"\s*Offset into .debug_info:\s+(0x[0-9a-f]+|\d+)", line)
        if m:
            cu = int(m.group(1), 0)
            continue
        m = re.match(r"^\s+([0-9a-f]{16}) ([0-9a-f]{16})\s*$", line)
        if m and cu is not None and int(m.group(2), 16):
            a = int(m.group(1), 16)
            res.append((a, a + int(m.group(2), 16), names.get(cu, "?")))
    return res


def symbols(bench):
    """(address, size, name, compilation unit) of every function in the binary."""
    us = units(bench)
    syms = []
    out = subprocess.run(["aarch64-linux-gnu-nm", "-S", "--defined-only", bench], capture_output=True,
                         text=True, check=True).stdout
    for line in out.splitlines():
        q = line.split()
        if len(q) == 4 and q[2] in "tTwW":
            a = int(q[0], 16)
            src = next((u for s, e, u in us if s <= a < e), "")
            syms.append((a, int(q[1], 16), q[3], src))
    return syms


def run_logged(bench, kernel, isa, calls, dfilter):
    """Instructions executed inside the dfilter ranges by one run: {block address: count}."""
    with tempfile.TemporaryDirectory() as d:
        log = os.path.join(d, "q.log")
        subprocess.run(["qemu-aarch64", "-d", "in_asm,exec,nochain", "-dfilter", dfilter, "-D", log, bench,
                        "--kernels", "--kernel", kernel, "--calls", str(calls), "--isa", isa],
                       capture_output=True, check=True)
        tb, cur, total = {}, None, {}
        with open(log, errors="replace") as f:
            for line in f:
                if line.startswith("IN:"):
                    cur = None
                    continue
                m = re.match(r"^0x([0-9a-f]+):\s", line)
                if m:
                    if cur is None:
                        cur = int(m.group(1), 16)
                        tb[cur] = 0
                    tb[cur] += 1
                    continue
                if not line.strip():
                    cur = None
                    continue
                m = re.match(r"^Trace \d+: \S+ \[[0-9a-f]+/([0-9a-f]+)/", line)
                if m:
                    a = int(m.group(1), 16)
                    total[a] = total.get(a, 0) + tb.get(a, 0)
    return total


def code_addrs(bench, kernel, isa):
    r = subprocess.run(["qemu-aarch64", bench, "--kernels", "--kernel", kernel, "--calls", "1", "--isa", isa],
                       capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(r.stderr.strip())
    return [int(a, 16) for a in re.findall(r"0x[0-9a-f]+", r.stdout.split("code at")[1])]


def count(bench, kernel, isa, calls, syms):
    """Instructions per call: every function of the compilation units of the kernel's code (its
    static helpers) and, for an ISA version, of the C reference's (its tails) are counted; the
    set-up's share cancels between a run of `calls` and one of 3 `calls` calls."""
    files, names = set(), []
    for a in code_addrs(bench, kernel, isa) + (code_addrs(bench, kernel, "c") if isa != "c" else []):
        for s, n, name, src in syms:
            if s + BASE == a:
                files.add(src)
                names.append(name)
    if not files:
        raise RuntimeError("no symbol at the kernel's address")
    if kernel.startswith("taa"):  # the kernels call fv_taa_project (reproject.c); the tile driver there is not theirs
        files |= {src for s, n, name, src in syms if name == "fv_taa_project"}
    sel = [(s, n, name, src) for s, n, name, src in syms if src in files and n > 0 and name not in TAA_DRIVER]
    dfilter = ",".join("0x%x+0x%x" % (s + BASE, n) for s, n, name, src in sel)
    i1 = run_logged(bench, kernel, isa, calls, dfilter)
    i3 = run_logged(bench, kernel, isa, 3 * calls, dfilter)
    per = {}
    for a in set(i1) | set(i3):
        f = next(("%s (%s)" % (name, src) for s, n, name, src in sel if s + BASE <= a < s + BASE + n), "?")
        per[f] = per.get(f, 0) + (i3.get(a, 0) - i1.get(a, 0)) / (2 * calls)
    return sum(per.values()), names[:1], per


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
        c, cf, cp = count(bench, k, "c", calls, syms)
        n, nf, np_ = count(bench, k, "neon", calls, syms)
        same = cf == nf  # no NEON version: the C one twice
        print("%-20s %14.0f %14s %8s   %s" % (k, c, "-" if same else "%.0f" % n, "-" if same else "%.2fx" % (c / n),
                                            " ".join(nf)))
        if "--by-function" in sys.argv:
            for isa, per in (("c", cp), ("neon", np_)):
                for f, v in sorted(per.items(), key=lambda kv: -kv[1]):
                    if round(v):
                        print("    %-5s %12.0f  %s" % (isa, v, f))
        res.append({"kernel": k, "c_insns_per_call": c, "neon_insns_per_call": None if same else n,
                    "ratio": None if same else c / n})
    if "--json" in sys.argv:
        with open(arg("--json", None), "w") as f:
            json.dump({"kernel_icount": {"calls": calls, "results": res}}, f, indent=1)


main()
