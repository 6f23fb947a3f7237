#!/usr/bin/env python3
"""tools/stacks/judge.py on traces whose answers are known by construction.

A trace sampled every 0.1 s: where the last sample off a body's final position is, and which
events fall before it, inside the sampling interval in which the motion ended (the settling),
and from the first still sample on (after rest). Exit 0 when every check holds.

  judge_test.py SOURCE_DIR
"""
import json
import os
import subprocess
import sys
import tempfile

HEADER = "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n"
EVENTS_HEADER = "t,kind,body_a,body_b\n"


def write_trace(path, positions):
    """positions: {body: [(t, x, y, z), ...]}."""
    with open(path, "w") as f:
        f.write(HEADER)
        for body, samples in positions.items():
            for (t, x, y, z) in samples:
                f.write("%r,%s,%r,%r,%r,1,0,0,0,0,0,0,0,0,0\n" % (t, body, x, y, z))


def write_events(path, times):
    with open(path, "w") as f:
        f.write(EVENTS_HEADER)
        for t in times:
            f.write("%r,collision,a,b\n" % t)


def judge(script, trace, events):
    done = subprocess.run([sys.executable, script, trace, "--events", events, "--json"],
                          stdout=subprocess.PIPE, text=True)
    return done.returncode, json.loads(done.stdout)


def main():
    script = os.path.join(sys.argv[1], "tools", "stacks", "judge.py")
    ok = True

    def check(cond, what):
        nonlocal ok
        print(("ok   " if cond else "FAIL ") + what)
        ok = ok and cond

    times = [round(0.1 * i, 10) for i in range(21)]  # 0 .. 2 s
    with tempfile.TemporaryDirectory() as work:
        trace, events = os.path.join(work, "t.csv"), os.path.join(work, "e.csv")
        # "a" falls 1 cm until 0.5 s and is still from 0.6 s; "b" never moves.
        write_trace(trace, {"a": [(t, 0.0, 0.0, 0.01 * max(0.0, 0.6 - t)) for t in times],
                            "b": [(t, 1.0, 0.0, 0.0) for t in times]})
        # Before the last moving sample, inside the interval the motion ended in, at the first
        # still sample and later.
        write_events(events, [0.3, 0.55, 0.6, 1.5])
        code, f = judge(script, trace, events)
        check(code == 0 and f["at_rest"], "a body still from 0.6 s of 2 s is at rest (exit 0)")
        check(abs(f["rest_at_s"] - 0.5) < 1e-12, "its last moving sample is 0.5 s")
        check(abs(f["still_from_s"] - 0.6) < 1e-12, "it is still from the sample after: 0.6 s")
        check(f["events_settling"] == 1, "one event between them is the settling")
        check(f["events_after_rest"] == 2, "two events at or after 0.6 s are after rest")
        check(abs(f["displacement_m"] - 0.006) < 1e-12, "displacement 6 mm")

        # Nothing moves: still from the first sample, every event after rest.
        write_trace(trace, {"a": [(t, 0.0, 0.0, 0.0) for t in times]})
        write_events(events, [0.0, 1.0])
        code, f = judge(script, trace, events)
        check(code == 0 and f["rest_at_s"] == 0.0 and f["still_from_s"] == 0.0,
              "a body that never moves is still from 0 s")
        check(f["events_settling"] == 0 and f["events_after_rest"] == 2,
              "every event of a scene that never moved is after rest")

        # Off its final position only at the first sample: rest_at 0, still from 0.1 s, and an
        # event between them is the settling (not after rest, as if nothing had moved).
        write_trace(trace, {"a": [(t, 0.0, 0.0, 0.001 if t == 0.0 else 0.0) for t in times]})
        write_events(events, [0.0, 0.05, 0.1, 1.0])
        code, f = judge(script, trace, events)
        check(code == 0 and f["rest_at_s"] == 0.0 and abs(f["still_from_s"] - 0.1) < 1e-12,
              "a body that moves only before the second sample is still from it")
        check(f["events_settling"] == 1 and f["events_after_rest"] == 2,
              "its event at 0.05 s is the settling, those at 0.1 and 1 s after rest")

        # Moving until 1.8 s of 2 s: not at rest (exit 1).
        write_trace(trace, {"a": [(t, 0.0, 0.0, 0.01 * max(0.0, 1.9 - t)) for t in times]})
        code, f = judge(script, trace, events)
        check(code == 1 and not f["at_rest"], "a body moving until 1.8 s of 2 s is MOVING (exit 1)")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
