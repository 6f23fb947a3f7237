"""The cost of a run through Python against the same run from the command line: they alternate,
`repeats` times each, and the medians are compared, in wall time and in CPU time (user + system;
steadier on a shared machine). The command line is timed as the whole `palpable run` process,
Python as the `palpable.run(...)` call in a running interpreter (the trace as numpy arrays and the
summary dict; with --events the event rows too), and as a whole `python3 -c` process (interpreter
and numpy start-up included).

    PYTHONPATH=build/python python3 tools/python/overhead.py build/palpable scenarios/pool_break.json \
        [--set /settings/envelope=1e-6] [--trace] [--events] [--repeats 7]
"""
import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import palpable


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("palpable")
    ap.add_argument("scene")
    ap.add_argument("--trace", action="store_true", help="the command line writes the trace CSV")
    ap.add_argument("--events", action="store_true",
                    help="the command line writes the events CSV; Python keeps the events")
    ap.add_argument("--python-events", action="store_true",
                    help="Python keeps the events (its default) even without --events")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--set", action="append", default=[], help="/json/pointer=value, for both")
    a = ap.parse_args()
    keep = a.events or a.python_events
    with tempfile.TemporaryDirectory() as work:
        measure(a, keep, work)


def measure(a, keep, work):
    cli = [a.palpable, "run", a.scene] + [x for o in a.set for x in ("--set", o)]
    if a.trace:
        cli += ["--trace", os.path.join(work, "t.csv")]
    if a.events:
        cli += ["--events", os.path.join(work, "e.csv")]
    script = "import palpable, sys; palpable.run(sys.argv[1], set=sys.argv[3:], events=sys.argv[2] == '1')"
    whole = [sys.executable, "-c", script, a.scene, "1" if keep else "0"] + a.set
    keys = ("cli", "python_call", "python_process")
    wall = {k: [] for k in keys}
    cpu = {k: [] for k in keys}

    def child_cpu():
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        return r.ru_utime + r.ru_stime

    for _ in range(a.repeats):
        for k in keys:
            t0, c0, p0 = time.perf_counter(), child_cpu(), time.process_time()
            if k == "python_call":
                r = palpable.run(a.scene, set=a.set, events=keep)
                del r
                cpu[k].append(time.process_time() - p0)
            else:
                subprocess.run(cli if k == "cli" else whole, check=True, stdout=subprocess.DEVNULL)
                cpu[k].append(child_cpu() - c0)
            wall[k].append(time.perf_counter() - t0)
    print("command line: %s" % " ".join(cli))
    print("python:       palpable.run(%r, set=%r, events=%r)" % (a.scene, a.set, keep))
    for name, table in (("wall", wall), ("cpu", cpu)):
        med = {k: statistics.median(v) for k, v in table.items()}
        for k in keys:
            print("%-4s %-15s median %.4f s  (%s)" % (name, k, med[k], " ".join("%.4f" % x for x in table[k])))
        print("%-4s python call / command line    = %.4f" % (name, med["python_call"] / med["cli"]))
        print("%-4s python process / command line = %.4f" % (name, med["python_process"] / med["cli"]))


if __name__ == "__main__":
    main()
