"""The Python module, as a user runs it (pytest; part of tools/run-tests)."""
import json
import math
import os

import numpy as np
import pytest

import palpable

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RAMP = os.path.join(ROOT, "scenarios", "block_on_ramp_decelerating.json")


def test_version():
    assert palpable.__version__.count(".") == 2


def test_run_a_file_with_overrides_gives_arrays_and_the_closed_form():
    r = palpable.run(RAMP, set={"/parameters/mu": 0.8, "/settings/contact_model": "persistent"})
    block = r.states["block"]
    assert block.shape == (len(r.t), 13)
    a = 9.81 * (math.sin(math.radians(30)) - 0.8 * math.cos(math.radians(30)))
    assert r.reference["acceleration_closed_form"] == pytest.approx(a, rel=1e-12)
    assert abs(r.reference["stop_time_error_s"]) < 1e-9
    # The trace is the CLI's: speed along the slope decreases linearly until the stop.
    v = block[:, 7:10]
    assert np.all(np.diff(np.linalg.norm(v, axis=1)[:50]) <= 0)


def test_run_a_dict_and_the_errors_name_the_pointer():
    import json
    with open(RAMP) as f:
        scene = json.load(f)
    scene["bodies"][1]["mass"] = -1
    with pytest.raises(palpable.InputError, match=r"/bodies/1/mass"):
        palpable.run(scene)
    with pytest.raises(ValueError, match=r"--set /settings/envelope"):
        palpable.run(RAMP, set=["/settings/envelope=1e999"])


def test_simulation_steps_and_runs_on():
    sim = palpable.Simulation(RAMP, set={"/settings/contact_model": "persistent"})
    kind, t, collided = sim.step(3.0)
    assert t >= 0.0
    sim.run_until(1.0)
    assert sim.time == pytest.approx(1.0)
    x1 = sim.state("block")["x"]
    sim.run_until(2.5)  # stopped at 1.919 s: at rest afterwards
    x2 = sim.state("block")["x"]
    sim.run_until(3.0)
    assert sim.state("block")["x"] == x2
    assert x1 != x2


def test_impact_is_the_command_line_impact():
    spec = {"K": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "u0": [1, 0, -1], "friction": 0.5,
            "restitution": 0.5, "law": "poisson"}
    out = palpable.impact(spec)
    assert out["status"] == "ok"
    assert out["u_final"][2] == pytest.approx(0.5, rel=1e-9)


def test_sweep_with_a_figure():
    rows = palpable.sweep(RAMP, {"/parameters/mu": [0.8, 0.9]},
                          lambda r: r.reference["stop_time_closed_form_s"],
                          set={"/settings/contact_model": "persistent"})
    assert [v["/parameters/mu"] for v, _ in rows] == [0.8, 0.9]
    assert rows[0][1] > rows[1][1]  # more friction stops sooner


def test_the_ramp_study_runs_and_is_exact_under_the_persistent_model():
    import importlib.util
    spec = importlib.util.spec_from_file_location(
        "ramp_study", os.path.join(ROOT, "tools", "python", "ramp_study.py"))
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    rows = study.study()
    assert len(rows) == 16
    stopped = [f["persistent"] for _, _, f in rows if "premise_failed" not in f["persistent"]]
    assert len(stopped) >= 10
    assert all(abs(p["stop_time_error_s"]) < 1e-9 for p in stopped)
    print(study.table(rows))


def test_the_readme_quick_start_runs_as_written(capsys, monkeypatch):
    with open(os.path.join(ROOT, "README.md")) as f:
        text = f.read()
    start = text.index("```python\nimport math, palpable")
    code = text[start + len("```python\n"):text.index("```\n", start + 10)]
    monkeypatch.chdir(ROOT)
    exec(compile(code, "README quick start", "exec"), {})
    out = capsys.readouterr().out
    difference = float(out.split("closed form:")[1].split()[0])
    assert difference < 1e-12


def test_impact_of_a_value_json_cannot_carry_or_nested_too_deep_is_an_input_error():
    # Through the command line's JSON reader: NaN is not JSON, and its depth limit holds here too.
    with pytest.raises(palpable.InputError, match=r"^spec: not valid JSON"):
        palpable.impact({"K": float("nan")})
    deep = json.loads("[" * 600 + "]" * 600)
    with pytest.raises(palpable.InputError, match=r"^spec: nested deeper than 256 levels"):
        palpable.impact({"K": deep})
