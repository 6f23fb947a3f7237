#!/usr/bin/env python3
"""Writes a scene restarted from a trace sample: SCENE with each dynamic body placed at its state
at time T of TRACE (position, orientation, velocity and angular velocity), everything else as SCENE
has it, end_time included, as JSON on stdout or in OUT (written whole, or not at all).

  tools/stacks/restart.py SCENE TRACE T [-o OUT]

TRACE is `palpable run SCENE --trace TRACE` output (t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz);
its sample at T (within 1e-9 s) is taken, every dynamic body of SCENE must be in it. What a trace
does not hold is not restored: which contacts were held and in which modes, and the pairs'
counters. A restarted run meets its touching bodies afresh at t = 0 (their collisions and holds),
so from there it takes its own path: it reproduces a behaviour that lasts (a cycle, a storm), not
the original run event for event. (Seed 23 of the 50-hull piles, restarted at 6.95 s, cycled
again within 0.3 s, and could then be cut down to the three hulls that keep the cycle going:
README, "Why seeds 23 and 24 ...".)

Exit status: 0 written; 2 bad input (a missing or malformed file, no sample at T, a body missing
from the sample), the file named.
"""
import argparse
import csv
import json
import math
import os
import sys
import tempfile

STATE = {"position": ("x", "y", "z"), "orientation": ("qw", "qx", "qy", "qz"),
         "velocity": ("vx", "vy", "vz"), "angular_velocity": ("wx", "wy", "wz")}


def fail(message):
    print(f"restart.py: {message}", file=sys.stderr)
    sys.exit(2)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("trace")
    ap.add_argument("t", type=float, help="the trace's sample time [s]")
    ap.add_argument("-o", "--output", help="write here instead of stdout")
    args = ap.parse_args()
    if not math.isfinite(args.t):
        fail(f"T must be a finite time, got {args.t}")
    try:
        with open(args.scene) as f:
            scene = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{args.scene}: cannot read the scene: {e}")
    if not isinstance(scene, dict) or not isinstance(scene.get("bodies"), list):
        fail(f"{args.scene}: /bodies: expected an array of bodies")
    sample = {}
    try:
        with open(args.trace, newline="") as f:
            for row in csv.DictReader(f):
                if abs(float(row["t"]) - args.t) <= 1e-9:
                    sample[row["body"]] = row
    except KeyError as e:
        fail(f"{args.trace}: not a palpable trace: no column {e} (expected "
             "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz)")
    except (OSError, ValueError, TypeError) as e:
        fail(f"{args.trace}: cannot read the trace: {e}")
    if not sample:
        fail(f"{args.trace}: no sample at t = {args.t:g} s")
    for i, body in enumerate(scene["bodies"]):
        if not isinstance(body, dict):
            fail(f"{args.scene}: /bodies/{i}: expected an object")
        if body.get("motion", "dynamic") != "dynamic":
            continue
        name = body.get("name")
        row = sample.get(name)
        if row is None:
            fail(f"{args.trace}: body {name!r} (/bodies/{i} of {args.scene}) is not in the sample "
                 f"at t = {args.t:g} s")
        try:
            for key, columns in STATE.items():
                body[key] = [float(row[c]) for c in columns]
        except (KeyError, TypeError, ValueError) as e:
            fail(f"{args.trace}: body {name!r} at t = {args.t:g} s: bad or missing column ({e})")
    text = json.dumps(scene, indent=1) + "\n"
    if not args.output:
        sys.stdout.write(text)
        return
    directory = os.path.dirname(os.path.abspath(args.output))
    try:
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=".restart-")
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, args.output)
    except OSError as e:
        fail(f"{args.output}: cannot write: {e}")


if __name__ == "__main__":
    main()
