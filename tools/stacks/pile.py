#!/usr/bin/env python3
"""Writes a pile scene (issue 14's stacks, issue 15's piles figure) as JSON on stdout.

N bodies (spheres of radius 0.025 m with rolling resistance 0.001 m, or random convex hulls
of 12 points in a 0.05 m cube), 0.1 kg each, placed on a 0.06 m grid in layers above a floor,
jittered by up to 5 mm and thrown with a random horizontal velocity up to 0.2 m/s, then dropped
into a square bin (a floor and four halfspace walls at +-W). Friction 0.5, restitution 0.3.
The random draws are fixed by --seed, so a scene is reproduced by its command line.

  tools/stacks/pile.py 100 sphere 10 > pile100s.json
  build/tools/palpable run pile100s.json --summary-json pile100s.summary.json

A layer holds at most as many bodies per row as fit inside the bin (so a pile of 100 or 200
is stacked in layers instead of placed through the walls), and a hull's points lie in the
0.05 m cube about its grid point (its centre of mass placed accordingly), so that no two
bodies overlap; piles of up to 64 bodies are placed as the first version of this script
placed them.
"""
import argparse
import json
import math
import random


def hull_centre_of_mass(points):
    """The centre of mass of the convex hull of `points` (uniform density): the hull's facets by
    brute force (every triple whose plane has all points on one side; a dozen random points have
    no four coplanar), then its volume in tetrahedra from an inner point."""
    def sub(a, b):
        return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]

    def cross(a, b):
        return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]

    def dot(a, b):
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]

    inner = [sum(p[k] for p in points) / len(points) for k in range(3)]
    volume, moment = 0.0, [0.0, 0.0, 0.0]
    m = len(points)
    for i in range(m):
        for j in range(i + 1, m):
            for k in range(j + 1, m):
                a, b, c = points[i], points[j], points[k]
                normal = cross(sub(b, a), sub(c, a))
                sides = [dot(normal, sub(q, a)) for q in points]
                scale = 1e-12 * max(abs(x) for x in sides)
                if not (all(x <= scale for x in sides) or all(x >= -scale for x in sides)):
                    continue
                v = abs(dot(normal, sub(inner, a))) / 6.0  # the tetrahedron (inner, a, b, c)
                volume += v
                for axis in range(3):
                    moment[axis] += v * (inner[axis] + a[axis] + b[axis] + c[axis]) / 4.0
    return [x / volume for x in moment]


def pile(n, kind, end_time, seed=7, half_width=0.3):
    # A generator of its own: the module's shared one, seeded here, was drawn from by every
    # thread at once when pile-cost ran seeds side by side (--jobs 2), so those piles were not
    # their seeds' (the 100-hull pile "of seed 2" ran to 10 s, the seed's own stops at 0.76 s).
    # The same draws as random.seed(seed) made: a pile of one seed is unchanged.
    rng = random.Random(seed)
    W = half_width
    pitch = 0.06
    bodies = [{"name": "floor", "motion": "fixed",
               "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}}]
    for i, (nx, ny) in enumerate([(1, 0), (-1, 0), (0, 1), (0, -1)]):
        bodies.append({"name": "wall%d" % i, "motion": "fixed",
                       "shape": {"type": "halfspace", "normal": [-nx, -ny, 0], "offset": -W}})
    # Bodies per row: sqrt(n) rounded up, at most what keeps a jittered body 5 mm off the walls
    # (extent 0.025 m, jitter 0.005 m).
    fit = int(math.floor((2 * (W - 0.025 - 0.005 - 0.005)) / pitch)) + 1
    side = min(int(math.ceil(n ** 0.5)), fit)
    for i in range(n):
        x = ((i % side) - (side - 1) / 2) * pitch
        y = (((i // side) % side) - (side - 1) / 2) * pitch
        z = 0.05 + pitch * (i // (side * side)) + 0.1
        x += rng.uniform(-0.005, 0.005)
        y += rng.uniform(-0.005, 0.005)
        if kind == "sphere":
            shape = {"type": "sphere", "radius": 0.025}
        else:
            pts = [[rng.uniform(-0.025, 0.025) for _ in range(3)] for _ in range(12)]
            shape = {"type": "convex", "vertices": pts}
            if n > 64:
                # The hull's points lie in the 0.05 m cube about the grid point, so that no two
                # hulls overlap: the scene's position is where the hull's centre of mass goes
                # (scenarios/README.md), up to 0.035 m from the cube's centre. (Placed at the
                # grid point, two hulls of the 200-hull pile of seed 1 overlapped.)
                c = hull_centre_of_mass(pts)
                x, y, z = x + c[0], y + c[1], z + c[2]
        bodies.append({"name": "p%d" % i, "mass": 0.1, "shape": shape, "position": [x, y, z],
                       "velocity": [rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), 0]})
    material = {"default": {"friction": 0.5, "restitution": 0.3}}
    if kind == "sphere":
        material["default"]["rolling_resistance"] = 0.001
    return {"format": "palpable-scene/1", "name": "pile", "gravity": [0, 0, -9.81],
            "end_time": float(end_time), "output": {"interval": 0.05}, "materials": material,
            "bodies": bodies}


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("count", type=int, help="number of bodies in the pile")
    parser.add_argument("kind", choices=["sphere", "hull"], help="spheres or convex hulls")
    parser.add_argument("end_time", type=float, help="simulated time [s]")
    parser.add_argument("--seed", type=int, default=7, help="random seed (default 7)")
    parser.add_argument("--half-width", type=float, default=0.3,
                        help="the bin's half width W [m] (default 0.3)")
    args = parser.parse_args()
    print(json.dumps(pile(args.count, args.kind, args.end_time, args.seed, args.half_width)))


if __name__ == "__main__":
    main()
