#!/usr/bin/env python3
"""Summarises a --trace-out file (Chrome trace-event JSON from fovea-bench / fovea-replay).

usage: tools/trace_summary.py FILE.json

Per track: the spans by name (count, total, median and 99th percentile duration); per worker:
its busy share of the frames' wall time (time inside "pool job" spans over the sum of the
"frame" stage spans): how well the pool keeps the threads fed.
"""
import json
import sys


def pct(v, p):
    v = sorted(v)
    return v[min(len(v) - 1, int(p * (len(v) - 1) + 0.5))] if v else 0.0


def main():
    doc = json.load(open(sys.argv[1]))
    names, open_, spans = {}, {}, {}
    for e in doc["traceEvents"]:
        tid = e["tid"]
        if e["ph"] == "M" and e["name"] == "thread_name":
            names[tid] = e["args"]["name"]
        elif e["ph"] == "B":
            open_.setdefault(tid, []).append(e)
        elif e["ph"] == "E":
            b = open_[tid].pop()
            spans.setdefault(tid, {}).setdefault(b["name"], []).append(e["ts"] - b["ts"])
    frame_us = sum(spans.get(1000, {}).get("frame", []))
    print("%-22s %-12s %8s %11s %10s %10s" % ("track", "span", "count", "total ms", "p50 us", "p99 us"))
    for tid in sorted(spans):
        for n, d in sorted(spans[tid].items()):
            print("%-22s %-12s %8d %11.2f %10.1f %10.1f" % (names.get(tid, tid), n, len(d), sum(d) / 1e3,
                                                            pct(d, 0.5), pct(d, 0.99)))
    if frame_us > 0:
        for tid in sorted(t for t in spans if t < 1000):
            busy = sum(spans[tid].get("pool job", []))
            print("%s: busy %.1f%% of the frames' wall time" % (names.get(tid, tid), 100.0 * busy / frame_us))


main()
