#!/usr/bin/env python3
"""Judges a stack or pile run from its trace alone (issue 14): how far each body moved, when
everything came to rest, and how many events came after.

  tools/stacks/judge.py TRACE.csv [--events EVENTS.csv] [--rest-tolerance 1e-9] [--json]

TRACE.csv is `palpable run --trace` output (t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz).
Figures, over every dynamic body:
  displacement      largest distance of a centre of mass from where it started [m]
  horizontal        the same in the horizontal plane (x, y) [m]
  turn              largest rotation angle from the starting orientation [rad]
  rest_at           the last sample at which any body was farther than the rest tolerance
                    from its final position [s] (0: never moved)
  still_from        the sample after rest_at: from it on every body is at its final position
                    at every sample [s] (the first sample if no sample is off a final position;
                    a body that moves only before the second sample has rest_at 0 and
                    still_from the second sample)
  events_settling   events (--events) after rest_at and before still_from: the motion ended
                    somewhere in that sampling interval, so these belong to the settling
  events_after_rest events (--events) at or after still_from: while everything was still
  at_rest           true when rest_at is at least 0.5 s before the trace's end
Exit code: 0 at rest, 1 still moving at the end, 2 unreadable input.
"""
import argparse
import csv
import json
import math
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("trace")
    ap.add_argument("--events", help="palpable run --events CSV of the same run")
    ap.add_argument("--rest-tolerance", type=float, default=1e-9,
                    help="distance from the final position that counts as moved [m] [1e-9]")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()
    try:
        rows = list(csv.DictReader(open(args.trace)))
        events = list(csv.DictReader(open(args.events))) if args.events else []
        by_body = {}
        for r in rows:
            q = tuple(float(r[k]) for k in ("qw", "qx", "qy", "qz"))
            by_body.setdefault(r["body"], []).append(
                (float(r["t"]), float(r["x"]), float(r["y"]), float(r["z"]), q))
    except (OSError, KeyError, ValueError) as err:
        print("judge: %s: %s" % (args.trace, err), file=sys.stderr)
        sys.exit(2)
    if not by_body:
        print("judge: %s: no samples" % args.trace, file=sys.stderr)
        sys.exit(2)
    disp = horiz = turn = 0.0
    moved = None  # the last sample at which any body was off its final position (None: none)
    for samples in by_body.values():
        t0, x0, y0, z0, q0 = samples[0]
        for (t, x, y, z, q) in samples:
            disp = max(disp, math.sqrt((x - x0) ** 2 + (y - y0) ** 2 + (z - z0) ** 2))
            horiz = max(horiz, math.hypot(x - x0, y - y0))
            dot = min(1.0, abs(sum(a * b for a, b in zip(q, q0))))
            turn = max(turn, 2.0 * math.acos(dot))
        tf, xf, yf, zf, _ = samples[-1]
        for (t, x, y, z, _) in reversed(samples):
            if math.sqrt((x - xf) ** 2 + (y - yf) ** 2 + (z - zf) ** 2) > args.rest_tolerance:
                moved = t if moved is None else max(moved, t)
                break
    end = max(s[-1][0] for s in by_body.values())
    times = sorted({sample[0] for samples in by_body.values() for sample in samples})
    rest = 0.0 if moved is None else moved
    still = times[0] if moved is None else next((t for t in times if t > moved), end)
    event_times = [float(e["t"]) for e in events]
    settling = sum(1 for t in event_times if moved is not None and moved < t < still)
    after = sum(1 for t in event_times if t >= still)
    at_rest = rest <= end - 0.5
    figures = {"displacement_m": disp, "horizontal_m": horiz, "turn_rad": turn, "rest_at_s": rest,
               "still_from_s": still,
               "events_settling": settling if args.events else None,
               "events_after_rest": after if args.events else None, "at_rest": at_rest,
               "end_s": end, "bodies": len(by_body)}
    if args.json:
        print(json.dumps(figures))
    else:
        print("displacement %.3g m  horizontal %.3g m  turn %.3g rad  rest at %.2f s  "
              "events settling %s  events after rest %s  %s" %
              (disp, horiz, turn, rest, settling if args.events else "-",
               after if args.events else "-", "AT REST" if at_rest else "MOVING"))
    sys.exit(0 if at_rest else 1)


if __name__ == "__main__":
    main()
