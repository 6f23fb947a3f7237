#!/usr/bin/env python3
"""Writes the paper's experiment scenes (scenarios/*.json) whose geometry is easier to compute
than to type: pool break, chain of balls, balls in a dish, bowling, coins. Run from the repository
root: python3 scenarios/generate_scenes.py. The JSON files are committed; this script only
documents and reproduces how they were made."""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def compact(obj, indent=0):
    """JSON with short numeric arrays on one line."""
    pad = "  " * indent
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = [f'{pad}  {json.dumps(k)}: {compact(v, indent + 1)}' for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + f"\n{pad}}}"
    if isinstance(obj, list):
        if all(not isinstance(x, (dict, list)) for x in obj) or \
           all(isinstance(x, list) and all(not isinstance(y, (dict, list)) for y in x) for x in obj) and len(obj) <= 4:
            return json.dumps(obj)
        items = [f"{pad}  {compact(v, indent + 1)}" for v in obj]
        return "[\n" + ",\n".join(items) + f"\n{pad}]"
    if isinstance(obj, float):
        return repr(obj)
    return json.dumps(obj)


def write(name, scene):
    with open(os.path.join(HERE, name), "w") as f:
        f.write(compact(scene) + "\n")


def r17(x):
    return float(f"{x:.17g}")


G = [0, 0, -9.81]


def chain_of_balls():
    # Eight steel balls (12.5 mm radius) touching in a line on a table, struck at one end by a
    # ninth at 1 m/s. Paper: 2.5 s virtual, 7.3 s real on 1995 hardware.
    r, m = 0.0125, 0.0642
    gap = 0.5e-4
    bodies = [{"name": "table", "motion": "fixed",
               "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}}]
    z = r17(r + gap)
    bodies.append({"name": "striker", "mass": m, "shape": {"type": "sphere", "radius": r},
                   "position": [-0.2, 0, z], "velocity": [1.0, 0, 0],
                   "angular_velocity": [0, r17(1.0 / r), 0]})
    for i in range(8):
        bodies.append({"name": f"ball{i}", "mass": m, "shape": {"type": "sphere", "radius": r},
                       "position": [r17(i * (2 * r + gap)), 0, z]})
    write("chain_of_balls.json", {
        "format": "palpable-scene/1", "name": "chain_of_balls",
        "description": "Eight steel balls (r = 12.5 mm, 64.2 g) touching in a line on a table, struck at one end by a ninth rolling at 1 m/s. The momentum passes down the chain (e = 0.95 between balls) and the far ball leaves. Mirtich & Canny: 2.5 s virtual, 7.3 s real in 1995.",
        "gravity": G, "end_time": 2.5, "output": {"interval": 0.01},
        "settings": {"envelope": 1e-4},
        "materials": {"default": {"friction": 0.1, "restitution": 0.95},
                      "pairs": [{"bodies": ["table", "*"], "friction": 0.2, "restitution": 0.3}]},
        "bodies": bodies})


def pool_break():
    # Regulation 9 ft table: playing surface 2.54 m x 1.27 m; balls 57.15 mm, 170 g. The rack's
    # balls are 0.1 mm apart (inside each other's envelopes, as in the paper); cue ball at 8 m/s.
    r, m = 0.028575, 0.17
    length, width = 2.54, 1.27
    gap = 1e-4 * 0.5
    cushion_h, cushion_w = 0.0363, 0.05  # nose height ~ 0.635 ball diameter
    z = r17(r + gap)
    parts = []
    for sx in (-1, 1):  # end cushions
        parts.append({"shape": {"type": "box", "half_extents": [cushion_w / 2, width / 2 + cushion_w, cushion_h / 2]},
                      "position": [r17(sx * (length / 2 + cushion_w / 2)), 0, r17(cushion_h / 2)]})
    for sy in (-1, 1):  # side cushions
        parts.append({"shape": {"type": "box", "half_extents": [length / 2 + cushion_w, cushion_w / 2, cushion_h / 2]},
                      "position": [0, r17(sy * (width / 2 + cushion_w / 2)), r17(cushion_h / 2)]})
    bodies = [{"name": "cloth", "motion": "fixed",
               "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}},
              {"name": "cushions", "motion": "fixed", "shape": {"type": "compound", "parts": parts}}]
    bodies.append({"name": "cue", "mass": m, "shape": {"type": "sphere", "radius": r},
                   "position": [-0.635, 0, z], "velocity": [8.0, 0, 0],
                   "angular_velocity": [0, r17(8.0 / r), 0]})
    d = 2 * r + 1e-4  # centre spacing: 0.1 mm apart
    k = 0
    for row in range(5):
        for j in range(row + 1):
            x = 0.635 + row * d * math.sqrt(3) / 2
            y = (j - row / 2) * d
            k += 1
            bodies.append({"name": f"ball{k}", "mass": m, "shape": {"type": "sphere", "radius": r},
                           "position": [r17(x), r17(y), z]})
    write("pool_break.json", {
        "format": "palpable-scene/1", "name": "pool_break",
        "description": "A break on a regulation 9 ft table (2.54 x 1.27 m; balls 57.15 mm, 170 g): 15 racked balls 0.1 mm apart (inside each other's envelopes, as in the paper) and a cue ball rolling at 8 m/s. The cloth is a fixed halfspace, the cushions a fixed compound of four boxes. Ball-ball e = 0.93, mu = 0.05; ball-cloth mu = 0.2, e = 0.5; ball-cushion mu = 0.15, e = 0.75. Mirtich & Canny: 3.0 s virtual, 95 s real in 1995.",
        "gravity": G, "end_time": 3.0, "output": {"interval": 0.01},
        "settings": {"envelope": 1e-4},
        "materials": {"default": {"friction": 0.05, "restitution": 0.93},
                      "pairs": [{"bodies": ["cloth", "*"], "friction": 0.2, "restitution": 0.5},
                                {"bodies": ["cushions", "*"], "friction": 0.15, "restitution": 0.75}]},
        "bodies": bodies})


def balls_in_dish():
    # A concave dish: a flat 16-gon bottom (apothem 8 cm) and 16 walls tilted at 25 degrees, each
    # the convex hull of its trapezoidal top face (exactly its sector, so that no piece pokes
    # above its neighbour's surface at the concave creases) and that face moved 2 cm inward.
    n_sides, bottom_r, slope = 16, 0.08, math.radians(25)
    wall_len, wall_t = 0.2, 0.02
    half = math.pi / n_sides
    parts = [{"shape": {"type": "prism", "radius": r17(bottom_r / math.cos(half)),
                        "half_height": wall_t / 2, "sides": n_sides},
              "position": [0, 0, -wall_t / 2],
              "orientation": [r17(math.cos(half / 2)), 0, 0, r17(math.sin(half / 2))]}]
    r_out = bottom_r + wall_len * math.cos(slope)
    z_out = wall_len * math.sin(slope)
    for i in range(n_sides):
        phi = 2 * math.pi * i / n_sides
        top = []
        for radius, z in ((bottom_r, 0.0), (r_out, z_out)):
            for side in (-1, 1):
                a = phi + side * half
                top.append((radius / math.cos(half) * math.cos(a), radius / math.cos(half) * math.sin(a), z))
        # Inward-up normal of the wall's top face.
        n = (-math.sin(slope) * math.cos(phi), -math.sin(slope) * math.sin(phi), math.cos(slope))
        points = top + [(x - wall_t * n[0], y - wall_t * n[1], z - wall_t * n[2]) for x, y, z in top]
        parts.append({"shape": {"type": "convex", "vertices": [[r17(c) for c in p] for p in points]}})
    bodies = [{"name": "dish", "motion": "fixed", "shape": {"type": "compound", "parts": parts}}]
    r, m = 0.02, 0.0335  # 40 mm glass marbles... heavy ones
    positions = [(0.0, 0.0, 0.15), (0.09, 0.0, 0.25), (-0.06, 0.07, 0.3), (0.03, -0.1, 0.35),
                 (-0.1, -0.05, 0.4), (0.05, 0.09, 0.45)]
    for i, p in enumerate(positions):
        bodies.append({"name": f"ball{i}", "mass": m, "shape": {"type": "sphere", "radius": r},
                       "position": list(p), "velocity": [0, 0, 0]})
    write("balls_in_dish.json", {
        "format": "palpable-scene/1", "name": "balls_in_dish",
        "description": "Six balls (r = 20 mm) dropped into a concave dish built from 17 convex pieces (a flat 16-gon bottom and 16 walls tilted at 25 degrees); they bounce, roll and come to rest at the bottom (rolling and spinning resistance 0.1 mm, a rolling-resistance coefficient d / r = 0.005: without them a ball rolling or spinning in a dish never stops). Mirtich & Canny: 7.8 s virtual, 95 s real in 1995.",
        "gravity": G, "end_time": 7.8, "output": {"interval": 0.01},
        "settings": {"envelope": 1e-4},
        "materials": {"default": {"friction": 0.3, "restitution": 0.5, "rolling_resistance": 1e-4, "spinning_resistance": 1e-4}},
        "bodies": bodies})


def coins():
    # Five US quarters (r = 12.13 mm, 1.75 mm thick, 5.67 g; 32-gon prisms) dropped from 6-20 cm
    # with tilts, spins about their axes and sideways speeds onto a table. They bounce on their
    # rims, rock, land flat and spin down: the spin about the normal is taken out by torsional
    # friction over the face (impulse/contact_torque.hpp). Paper: 3.6 s virtual, 50 s real.
    r, half_t, m, sides = 0.01213, 0.000875, 0.00567, 32
    drops = [  # position, tilt about x [deg], tilt about y [deg], spin about own axis, velocity
        ((0.00, 0.00, 0.06), 20.0, 0.0, 15.0, (0.10, 0.0, 0.0)),
        ((0.06, 0.02, 0.09), -35.0, 10.0, -25.0, (-0.05, 0.05, 0.0)),
        ((-0.05, 0.05, 0.12), 5.0, -50.0, 40.0, (0.0, -0.10, 0.0)),
        ((0.03, -0.06, 0.16), 60.0, 0.0, 10.0, (0.05, 0.05, 0.0)),
        ((-0.04, -0.04, 0.20), 0.0, 0.0, 30.0, (0.0, 0.0, 0.0)),
    ]
    bodies = [{"name": "table", "motion": "fixed",
               "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}}]
    for i, (p, ax, ay, spin, v) in enumerate(drops):
        # q = q_y * q_x; the coin's axis is its modelling z.
        cx, sx = math.cos(math.radians(ax) / 2), math.sin(math.radians(ax) / 2)
        cy, sy = math.cos(math.radians(ay) / 2), math.sin(math.radians(ay) / 2)
        q = (cy * cx, cy * sx, sy * cx, -sy * sx)
        # World direction of the coin's axis: R(q) e_z.
        w, x, y, z = q
        axis = (2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y))
        bodies.append({"name": f"coin{i}", "mass": m,
                       "shape": {"type": "prism", "radius": r, "half_height": half_t, "sides": sides},
                       "position": list(p), "orientation": [r17(c) for c in q],
                       "velocity": list(v), "angular_velocity": [r17(spin * a) for a in axis]})
    write("coins.json", {
        "format": "palpable-scene/1", "name": "coins",
        "description": "Five coins (US quarters: r = 12.13 mm, 1.75 mm thick, 5.67 g, as 32-gon prisms) dropped from 6 to 20 cm with tilts, spins of 10 to 40 rad/s about their axes and sideways speeds onto a table (coin-table mu = 0.3, e = 0.5). They bounce on their rims, rock, land flat, slide and spin down to rest: the spin about the normal is taken out by torsional friction over the face. Mirtich & Canny: 3.6 s virtual, 50 s real in 1995.",
        "plot": "tumble",
        "gravity": G, "end_time": 3.6, "output": {"interval": 0.01},
        "settings": {"envelope": 1e-4},
        "materials": {"default": {"friction": 0.3, "restitution": 0.5}},
        "bodies": bodies})


def bowling():
    # A 60 ft lane (18.29 m from the foul line to the head pin), ten pins 12 in apart, each the
    # convex hull of rings through the regulation pin profile (15 in tall, 4.766 in at the belly,
    # 2.03 in at the base; 1.53 kg), and a 7 kg ball (8.5 in) rolling at 8 m/s into the 1-3
    # pocket. Envelope 1 mm, as in the paper.
    profile = [(0.0, 0.0254), (0.03, 0.043), (0.076, 0.058), (0.114, 0.0605), (0.16, 0.055),
               (0.2, 0.042), (0.25, 0.0235), (0.29, 0.027), (0.33, 0.032), (0.36, 0.025),
               (0.381, 0.008)]
    ring = 12
    # The hull of rings of aligned regular 12-gons is the polygonal solid of revolution of the
    # profile's convex chain (the neck is filled in). Its cross-section area is proportional to
    # r^2 at every height, so the centroid follows from the circular frusta of that chain.
    chain = []
    for z, radius in profile:  # upper convex chain in the (z, r) half-plane
        while len(chain) >= 2:
            (z0, r0), (z1, r1) = chain[-2], chain[-1]
            if (z1 - z0) * (radius - r0) - (r1 - r0) * (z - z0) >= 0:  # not a right turn
                chain.pop()
            else:
                break
        chain.append((z, radius))
    points = []
    for z, radius in chain:
        for k in range(ring):
            a = 2 * math.pi * k / ring
            points.append([r17(radius * math.cos(a)), r17(radius * math.sin(a)), r17(z)])
    vol = 0.0
    moment = 0.0
    for (z0, r0), (z1, r1) in zip(chain, chain[1:]):
        h = z1 - z0
        v = math.pi * h / 3 * (r0 * r0 + r0 * r1 + r1 * r1)
        zc = z0 + h * (r0 * r0 + 2 * r0 * r1 + 3 * r1 * r1) / (4 * (r0 * r0 + r0 * r1 + r1 * r1))
        vol += v
        moment += v * zc
    z_com = moment / vol
    envelope = 1e-3
    head_x = 18.29
    spacing = 0.3048
    bodies = [{"name": "lane", "motion": "fixed",
               "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}}]
    # The pin deck's kickbacks (side walls, inner faces 0.8 m from the lane's centre line) and the
    # pit cushion behind it (inner face 21.3 m from the foul line), fixed boxes.
    wall_half = [1.9, 0.05, 0.4]
    for side, y in (("left", -0.85), ("right", 0.85)):
        bodies.append({"name": f"kickback_{side}", "motion": "fixed",
                       "shape": {"type": "box", "half_extents": wall_half},
                       "position": [19.6, y, 0.4]})
    bodies.append({"name": "pit_cushion", "motion": "fixed",
                   "shape": {"type": "box", "half_extents": [0.05, 0.9, 0.4]},
                   "position": [21.35, 0.0, 0.4]})
    pin = 0
    for row in range(4):
        for j in range(row + 1):
            pin += 1
            x = head_x + row * spacing * math.sqrt(3) / 2
            y = (j - row / 2) * spacing
            bodies.append({"name": f"pin{pin}", "mass": 1.53,
                           "shape": {"type": "convex", "vertices": points},
                           "position": [r17(x), r17(y), r17(z_com + envelope / 2)]})
    r_ball = 0.108
    bodies.append({"name": "ball", "mass": 7.0, "shape": {"type": "sphere", "radius": r_ball},
                   "position": [0.0, 0.06, r17(r_ball + envelope / 2)],
                   "velocity": [8.0, 0, 0], "angular_velocity": [0, r17(8.0 / r_ball), 0]})
    write("bowling.json", {
        "format": "palpable-scene/1", "name": "bowling",
        "description": "A 7 kg ball (r = 108 mm) rolling at 8 m/s down a 60 ft lane into the 1-3 pocket of ten pins (each the convex hull of rings through the regulation profile, 1.53 kg, 12 in apart). Envelope 1 mm, as in the paper. Ball-lane mu = 0.04 (oiled), pin-lane mu = 0.2, ball-pin e = 0.7, pin-pin e = 0.6. Kickbacks (side walls 0.8 m from the centre line) and a pit cushion 21.3 m from the foul line keep everything on the deck. Mirtich & Canny: 5.0 s virtual, 167 s real in 1995.",
        "gravity": G, "end_time": 5.0, "output": {"interval": 0.01},
        "settings": {"envelope": envelope},
        "materials": {"default": {"friction": 0.2, "restitution": 0.6},
                      "pairs": [{"bodies": ["ball", "lane"], "friction": 0.04, "restitution": 0.3},
                                {"bodies": ["lane", "*"], "friction": 0.2, "restitution": 0.3},
                                {"bodies": ["ball", "*"], "friction": 0.1, "restitution": 0.7}]},
        "bodies": bodies})



if __name__ == "__main__":
    chain_of_balls()
    pool_break()
    balls_in_dish()
    coins()
    bowling()
