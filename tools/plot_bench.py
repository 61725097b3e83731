#!/usr/bin/env python3
"""Turns fovea-bench JSON into PNG charts with gnuplot (Debian package gnuplot-nox).

usage: tools/plot_bench.py OUT_DIR FILE.json...

Each FILE is a scene bench (fovea-bench --json) or a kernel bench (--kernels --json). Writes:
  stages.png    per-stage time, stacked, foveated vs full, for every scene run and threads point
  scaling.png   per-stage scaling efficiency t(1) / (n t(n)) against threads (--sweep threads=...)
  sweep-P.png   per-stage time against each other swept parameter P (pmin, size, r0, r1)
  roofline.png  fraction of the measured copy bandwidth per post-processing stage
  kernels.png   kernel speed-ups against the C reference per ISA (and, from
                tools/kernel_icount.py --json, NEON's instruction ratio under qemu)
Charts whose data is absent are skipped. Prints the files written.
"""
import json
import os
import subprocess
import sys

STAGES = ["trace", "reproject", "reconstruct", "coc", "dof_filter", "combine"]
ROOF = ["reproject", "reconstruct", "coc", "dof_filter", "combine"]


def gnuplot(script):
    subprocess.run(["gnuplot"], input=script.encode(), check=True)


def block(name, rows):
    return "$%s << EOD\n%s\nEOD\n" % (name, "\n".join(" ".join(str(x) for x in r) for r in rows))


def num(v):
    return 0.0 if v is None else v


def scene_name(d):
    """The scene's name, and the JSON file's when it differs (two runs of one scene)."""
    n = os.path.splitext(os.path.basename(d["scene"]))[0]
    f = d.get("_file", n)
    return n if f.lower() in n.lower() else "%s [%s]" % (n, f)


def head(out, w=1000, h=560):
    return 'set terminal pngcairo noenhanced size %d,%d font ",10"\nset output "%s"\nset grid ytics\nset key outside right\n' % (
        w, h, out)


def stages_chart(scenes, out):
    rows, seen = [], set()
    for d in scenes:
        pts = [(d["threads"], d["runs"])]
        for sw in d.get("sweeps", []):
            if sw["param"] == "threads":
                pts += [(p["threads"], p["runs"]) for p in sw["points"]]
        for t, runs in pts:
            for r in runs:
                label = '"%s %s %dt"' % (scene_name(d), r["mode"], t)
                if label in seen:
                    continue
                seen.add(label)
                rows.append([label] + [num(r["stages_ms"][s]) for s in STAGES])
    if not rows:
        return None
    s = head(out) + block("d", rows)
    s += ('set style data histograms\nset style histogram rowstacked\nset style fill solid 0.8 border -1\n'
          'set boxwidth 0.7\nset ylabel "ms per frame (one eye)"\nset xtics rotate by -30\n'
          'set title "Per-stage time, foveated vs full (means over the timed frames)"\n')
    s += "plot " + ", ".join('$d using %d%s title "%s"' % (i + 2, ":xtic(1)" if i == 0 else "", st)
                             for i, st in enumerate(STAGES)) + "\n"
    gnuplot(s)
    return out


def scaling_chart(scenes, out):
    series = []
    for d in scenes:
        for sw in d.get("sweeps", []):
            if sw["param"] != "threads" or len(sw["points"]) < 2:
                continue
            p0 = sw["points"][0]
            for mi, r0 in enumerate(p0["runs"]):
                for st in STAGES + ["total"]:
                    a = r0["total_ms"] if st == "total" else r0["stages_ms"][st]
                    if not a:
                        continue
                    rows = []
                    for p in sw["points"]:
                        r = p["runs"][mi]
                        b = r["total_ms"] if st == "total" else r["stages_ms"][st]
                        if b:
                            rows.append([p["threads"], a * p0["threads"] / (b * p["threads"])])
                    if st in ("trace", "reconstruct", "dof_filter", "total"):
                        series.append(("%s %s %s" % (scene_name(d), r0["mode"], st), rows))
    if not series:
        return None
    s = head(out) + "".join(block("s%d" % i, rows) for i, (_, rows) in enumerate(series))
    s += ('set xlabel "threads"\nset ylabel "scaling efficiency t(1) / (n t(n))"\nset yrange [0:1.2]\n'
          'set xtics 1\nset title "Thread scaling per stage"\n')
    s += "plot " + ", ".join('$s%d using 1:2 with linespoints title "%s"' % (i, n) for i, (n, _) in enumerate(series))
    gnuplot(s + "\n")
    return out


def sweep_charts(scenes, outdir):
    outs = []
    for d in scenes:
        for sw in d.get("sweeps", []):
            if sw["param"] == "threads":
                continue
            rows = []
            for p in sw["points"]:
                x = p["width"] * p["height"] / 1e6 if sw["param"] == "size" else float(p["value"])
                r = p["runs"][0]
                rows.append([x] + [num(r["stages_ms"][st]) for st in STAGES] + [num(r["total_ms"])])
            out = os.path.join(outdir, "sweep-%s.png" % sw["param"])
            xl = {"size": "megapixels per eye", "pmin": "p_min", "r0": "r0 (deg)", "r1": "r1 (deg)"}[sw["param"]]
            s = head(out) + block("d", rows)
            s += 'set xlabel "%s"\nset ylabel "ms per frame"\nset title "%s, %s: time against %s"\n' % (
                xl, scene_name(d), sw["points"][0]["runs"][0]["mode"], sw["param"])
            s += "plot " + ", ".join('$d using 1:%d with linespoints title "%s"' % (i + 2, st)
                                     for i, st in enumerate(STAGES + ["total"])) + "\n"
            gnuplot(s)
            outs.append(out)
    return outs


def roofline_chart(scenes, out):
    rows = []
    for d in scenes:
        for r in d["runs"]:
            rows.append(['"%s %s %dt"' % (scene_name(d), r["mode"], d["threads"])] +
                        [num((r["roofline"].get(st) or {}).get("fraction")) for st in ROOF])
    if not rows:
        return None
    s = head(out) + block("d", rows)
    s += ('set style data histograms\nset style histogram clustered gap 1\nset style fill solid 0.8 border -1\n'
          'set ylabel "fraction of measured copy bandwidth"\nset xtics rotate by -20\n'
          'set title "Memory roofline: compulsory bytes / stage time over memcpy bandwidth"\n')
    s += "plot " + ", ".join('$d using %d%s title "%s"' % (i + 2, ":xtic(1)" if i == 0 else "", st)
                             for i, st in enumerate(ROOF)) + "\n"
    gnuplot(s)
    return out


def kernels_chart(kern, out):
    isas, names, sp = [], [], {}
    for k in kern:
        for r in k.get("kernel_icount", {}).get("results", []):
            if r["ratio"]:
                if "neon (insn ratio, qemu)" not in isas:
                    isas.append("neon (insn ratio, qemu)")
                sp[(r["kernel"], "neon (insn ratio, qemu)")] = r["ratio"]
        for r in k.get("kernels_bench", {}).get("results", []):
            if r["isa"] not in isas:
                isas.append(r["isa"])
            if r["kernel"] not in names:
                names.append(r["kernel"])
            sp[(r["kernel"], r["isa"])] = r["speedup"]
    if not names:
        return None
    rows = [['"%s"' % n] + [sp.get((n, i), 0) for i in isas] for n in names]
    s = head(out) + block("d", rows)
    s += ('set style data histograms\nset style histogram clustered gap 1\nset style fill solid 0.8 border -1\n'
          'set ylabel "speed-up over the C reference"\nset xtics rotate by -30\nset logscale y 2\nset yrange [0.5:*]\n'
          'set title "Hand-vectorised kernels at production sizes (median of back-to-back runs)"\n')
    s += "plot " + ", ".join('$d using %d%s title "%s"' % (i + 2, ":xtic(1)" if i == 0 else "", isa)
                             for i, isa in enumerate(isas)) + "\n"
    gnuplot(s)
    return out


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(2)
    outdir = sys.argv[1]
    os.makedirs(outdir, exist_ok=True)
    scenes, kern = [], []
    for p in sys.argv[2:]:
        with open(p) as f:
            d = json.load(f)
        d["_file"] = os.path.splitext(os.path.basename(p))[0]
        (kern if "kernels_bench" in d or "kernel_icount" in d else scenes).append(d)
    outs = [stages_chart(scenes, os.path.join(outdir, "stages.png")),
            scaling_chart(scenes, os.path.join(outdir, "scaling.png")),
            roofline_chart(scenes, os.path.join(outdir, "roofline.png")),
            kernels_chart(kern, os.path.join(outdir, "kernels.png"))] + sweep_charts(scenes, outdir)
    for o in outs:
        if o:
            print(o)


main()
