"""The ramp over 4 angles x 4 frictions, with the Python module: the block launched down at 2 m/s
stops at t* = v0 / (g (mu cos - sin)); the table gives t* and the measured stop-time error under
both contact models (persistent: exact; microcollisions: within half a flight), or why a
combination has no stop (the block slides off the ramp first).

    PYTHONPATH=build/python python3 tools/python/ramp_study.py
"""
import os
import sys

import palpable

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RAMP = os.path.join(ROOT, "scenarios", "block_on_ramp_decelerating.json")


def study(angles=(20, 25, 30, 35), frictions=(0.5, 0.6, 0.7, 0.8)):
    rows = []
    for angle in angles:
        for mu in frictions:
            figures = {}
            for model in ("persistent", "microcollisions"):
                r = palpable.run(RAMP, set={"/parameters/angle_deg": angle, "/parameters/mu": mu,
                                            "/settings/contact_model": model})
                figures[model] = r.reference
            rows.append((angle, mu, figures))
    return rows


def table(rows):
    lines = ["| angle | μ | t* [s] | error, persistent [s] | error, microcollisions [s] |",
             "|---|---|---|---|---|"]
    for angle, mu, f in rows:
        p, m = f["persistent"], f["microcollisions"]
        if "premise_failed" in p:
            lines.append("| %d° | %.1f | — | %s | |" % (angle, mu, p["premise_failed"]))
            continue
        lines.append("| %d° | %.1f | %.6f | %.2g | %.2g |" % (
            angle, mu, p["stop_time_closed_form_s"], p["stop_time_error_s"], m["stop_time_error_s"]))
    return "\n".join(lines)


if __name__ == "__main__":
    print(table(study()))
    sys.exit(0)
