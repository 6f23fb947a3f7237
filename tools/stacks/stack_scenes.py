#!/usr/bin/env python3
"""Writes the stack scenes of issue 14 as palpable scene files (palpable-scene/1).

Towers of 2, 5, 10 and 20 boxes, pyramids of 3, 4 and 6 rows (0.1 m cubes, 1 kg, mu 0.5,
e 0.5), each started touching, 0.2 mm apart and 1 mm apart; a 1 kg and a 5 kg plank bridging two
cubes; a cube on a cube on a 15 degree ramp; a 0.5 kg box on a 1 kg block launched at 1 m/s
(mu 1 between them, 0.3 on the floor). Touching boxes are placed at exactly h/2 + i h: the loader
accepts placements that touch to within rounding.

  tools/stacks/stack_scenes.py --out DIR [--end-time 10]
  for f in DIR/*.json; do build/palpable run $f --trace ${f%.json}.csv --events ${f%.json}.events.csv; done
  tools/stacks/judge.py DIR/tower10_touch.csv --events DIR/tower10_touch.events.csv
"""
import argparse
import json
import math
import os
import sys


def scene(name, bodies, end, mu=0.5, e=0.5):
    return {"format": "palpable-scene/1", "name": name, "gravity": [0, 0, -9.81],
            "end_time": end, "output": {"interval": 0.01},
            "materials": {"default": {"friction": mu, "restitution": e}}, "bodies": bodies}


FLOOR = {"name": "floor", "motion": "fixed",
         "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}}


def box(name, half, pos, mass=1.0, q=None, v=None):
    b = {"name": name, "mass": mass, "shape": {"type": "box", "half_extents": list(half)},
         "position": list(pos)}
    if q:
        b["orientation"] = q
    if v:
        b["velocity"] = v
    return b


def scenes(end):
    out = {}
    h = 0.1
    cube = (h / 2, h / 2, h / 2)
    for gap, tag in ((0.0, "touch"), (2e-4, "g02"), (1e-3, "g1")):
        for n in (2, 5, 10, 20):
            bodies = [FLOOR] + [box("box%d" % i, cube, (0, 0, h / 2 + i * (h + gap)))
                                for i in range(n)]
            out["tower%d_%s" % (n, tag)] = scene("tower%d_%s" % (n, tag), bodies, end)
        for rows in (3, 4, 6):
            bodies = [FLOOR]
            for r in range(rows):
                k = rows - r
                for j in range(k):
                    x = (j - (k - 1) / 2) * (h + gap)
                    bodies.append(box("b%d_%d" % (r, j), cube, (x, 0, h / 2 + r * (h + gap))))
            out["pyramid%d_%s" % (rows, tag)] = scene("pyramid%d_%s" % (rows, tag), bodies, end)
    for m in (1, 5):
        bodies = [FLOOR, box("c1", cube, (-0.3, 0, h / 2)), box("c2", cube, (0.3, 0, h / 2)),
                  box("plank", (0.4, 0.05, 0.01), (0, 0, h + 0.01), mass=float(m))]
        out["plank%d" % m] = scene("plank%d" % m, bodies, end)
    a = math.radians(15)
    n = (-math.sin(a), 0, math.cos(a))
    q = [math.cos(a / 2), 0, -math.sin(a / 2), 0]
    bodies = [{"name": "ramp", "motion": "fixed",
               "shape": {"type": "halfspace", "normal": list(n), "offset": 0}},
              box("c1", cube, tuple(c * h / 2 for c in n), q=q),
              box("c2", cube, tuple(c * 1.5 * h for c in n), q=q)]
    out["ramp_stack"] = scene("ramp_stack", bodies, end)
    bodies = [FLOOR, box("block", (0.1, 0.1, 0.05), (0, 0, 0.05), mass=1.0, v=[1, 0, 0]),
              box("box", cube, (0, 0, 0.15), mass=0.5, v=[1, 0, 0])]
    s = scene("carried", bodies, min(end, 2.0), mu=1.0)
    s["materials"]["pairs"] = [{"bodies": ["floor", "block"], "friction": 0.3, "restitution": 0.5}]
    out["carried"] = s
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="directory to write the scene files into")
    ap.add_argument("--end-time", type=float, default=10.0, help="simulated seconds [10]")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    made = scenes(args.end_time)
    for name, s in made.items():
        with open(os.path.join(args.out, name + ".json"), "w") as f:
            json.dump(s, f, indent=1)
    print("%d scenes in %s" % (len(made), args.out), file=sys.stderr)


if __name__ == "__main__":
    main()
