"""The ramp over 4 angles x 4 frictions, with the Python module: a 1 kg cube launched down a ramp
at v0 = 2 m/s (scenarios/block_on_ramp_decelerating.json, angle and friction set per run).

Closed form, with a = g (mu cos(angle) - sin(angle)):
  a > 0: the block stops at t* = v0 / a after d* = v0^2 / (2 a) and stays;
  a < 0: it slides on, accelerating at -a;
  and it leaves the ramp first if d* exceeds the 4.9 m of ramp below it.
Simulated, under both contact models: the stop time (persistent: the instant of the block's
`stick` event; microcollisions: the fit of the reference comparison), the distance slid (the
block's displacement down the slope at the end), or the fitted acceleration.

    PYTHONPATH=build/python python3 tools/python/ramp_study.py
"""
import math
import os
import sys

import numpy as np

import palpable

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RAMP = os.path.join(ROOT, "scenarios", "block_on_ramp_decelerating.json")
G, V0, RAMP_BELOW = 9.81, 2.0, 4.9  # m/s^2, m/s, m of ramp below the block's start
MODELS = ("persistent", "microcollisions")
END = 1.5  # s: how long a block that does not stop on the ramp is run


def closed_form(angle, mu):
    th = math.radians(angle)
    a = G * (mu * math.cos(th) - math.sin(th))
    d_end = V0 * END - 0.5 * a * END * END  # slid by END while it has not stopped
    if a <= 0:
        return {"regime": "accelerates", "acceleration": -a, "d_end": d_end}
    t, d = V0 / a, V0 * V0 / (2 * a)
    return {"regime": "stops" if d < RAMP_BELOW else "leaves the ramp", "t": t, "d": d,
            "d_end": d_end}


def simulate(angle, mu, model, end):
    r = palpable.run(RAMP, end=end, set={"/parameters/angle_deg": angle, "/parameters/mu": mu,
                                         "/settings/contact_model": model})
    th = math.radians(angle)
    down = np.array([math.cos(th), 0.0, -math.sin(th)])
    block = r.states["block"]
    out = {"d": float((block[-1, :3] - block[0, :3]) @ down), "reference": r.reference}
    e = r.events
    stick = (e["kind"] == "stick") & ((e["body_a"] == "block") | (e["body_b"] == "block"))
    if model == "persistent" and stick.any():
        out["t"] = float(e["t"][stick][0])
    elif "stop_time_fit_s" in r.reference:
        out["t"] = r.reference["stop_time_fit_s"]
    if "acceleration_fit" in r.reference:
        out["acceleration"] = r.reference["acceleration_fit"]
    return out


def study(angles=(20, 25, 30, 35), frictions=(0.5, 0.6, 0.7, 0.8)):
    rows = []
    for angle in angles:
        for mu in frictions:
            c = closed_form(angle, mu)
            end = c["t"] + 0.5 if c["regime"] == "stops" else END
            rows.append((angle, mu, c, {m: simulate(angle, mu, m, end) for m in MODELS}))
    return rows


def table(rows):
    lines = ["| angle | μ | closed form | persistent | microcollisions |", "|---|---|---|---|---|"]
    for angle, mu, c, sims in rows:
        if c["regime"] == "stops":
            cells = ["stops at t* = %.6f s after d* = %.6f m" % (c["t"], c["d"])]
            cells += ["%.6f s, %.6f m" % (sims[m]["t"], sims[m]["d"]) for m in MODELS]
        elif c["regime"] == "accelerates":
            cells = ["slides on at %.6f m/s², %.6f m by %g s" % (c["acceleration"], c["d_end"], END)]
            cells += ["%.6f m/s², %.6f m" % (sims[m]["acceleration"], sims[m]["d"]) for m in MODELS]
        else:
            cells = ["would stop after %.3g m, off the ramp; %.6f m by %g s" % (c["d"], c["d_end"], END)]
            cells += ["%.6f m" % sims[m]["d"] for m in MODELS]
        lines.append("| %d° | %.1f | %s |" % (angle, mu, " | ".join(cells)))
    return "\n".join(lines)


if __name__ == "__main__":
    print(table(study()))
    sys.exit(0)
