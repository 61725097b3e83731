#!/usr/bin/env python3
"""Checks a Chrome trace-event JSON written by --trace-out (platform/proftrace.c).

usage: check_trace.py FILE.json WORKERS [--stages] [--tiles]
Fails (exit 1, one line naming the problem) unless: the file is valid JSON with a traceEvents
list; every "B" is closed by an "E" on the same track (tid) in stack order, with non-decreasing
timestamps per track; there is a named track ("thread_name") for each of the WORKERS worker
threads (tid 0 .. WORKERS-1) and no other worker track; with --stages, named tracks with spans
for the pipeline stages frame, trace and reconstruct; with --tiles, "tile" spans on worker tracks.
"""
import json
import sys


def fail(msg):
    print("check_trace: " + msg)
    sys.exit(1)


def main():
    if len(sys.argv) < 3:
        fail("usage: check_trace.py FILE.json WORKERS [--stages] [--tiles]")
    path, workers = sys.argv[1], int(sys.argv[2])
    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, ValueError) as e:
        fail("%s: not valid JSON: %s" % (path, e))
    ev = doc.get("traceEvents") if isinstance(doc, dict) else None
    if not isinstance(ev, list) or not ev:
        fail("no traceEvents list")
    names, stacks, last_ts, spans = {}, {}, {}, {}
    for i, e in enumerate(ev):
        ph, tid = e.get("ph"), e.get("tid")
        if not isinstance(tid, int) or e.get("pid") != 1:
            fail("event %d: bad pid/tid" % i)
        if ph == "M":
            if e.get("name") == "thread_name":
                names[tid] = e["args"]["name"]
            continue
        ts = e.get("ts")
        if not isinstance(ts, (int, float)):
            fail("event %d: no ts" % i)
        if ts < last_ts.get(tid, float("-inf")):
            fail("event %d: time goes back on track %d" % (i, tid))
        last_ts[tid] = ts
        st = stacks.setdefault(tid, [])
        if ph == "B":
            if not isinstance(e.get("name"), str):
                fail("event %d: B without a name" % i)
            st.append(e)
            spans.setdefault(tid, set()).add(e["name"])
        elif ph == "E":
            if not st:
                fail("event %d: E without an open B on track %d" % (i, tid))
            st.pop()
        elif ph in ("i", "X"):
            pass
        else:
            fail("event %d: unknown phase %r" % (i, ph))
    for tid, st in stacks.items():
        if st:
            fail("track %d: %d B events never closed (first %r)" % (tid, len(st), st[0]["name"]))
    wtracks = sorted(t for t in names if t < 1000)
    if wtracks != list(range(workers)):
        fail("worker tracks %s, want 0..%d" % (wtracks, workers - 1))
    if any(t >= 1000 and t < 2000 and t not in names for t in stacks):
        fail("a stage track without a name")
    if "--stages" in sys.argv:
        got = {names.get(t) for t in spans if 1000 <= t < 2000}
        for s in ("frame", "trace", "reconstruct"):
            if "stage " + s not in got:
                fail("no spans on the track 'stage %s' (have %s)" % (s, sorted(x for x in got if x)))
    if "--tiles" in sys.argv:
        if not any("tile" in spans.get(t, ()) for t in range(workers)):
            fail("no 'tile' spans on the worker tracks")
    print("check_trace: ok, %d events, %d tracks" % (len(ev), len(names)))


main()
