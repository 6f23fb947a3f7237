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
    regimes = [c["regime"] for _, _, c, _ in rows]
    assert regimes.count("stops") >= 8 and "accelerates" in regimes
    for _, _, c, sims in rows:
        p, m = sims["persistent"], sims["microcollisions"]
        if c["regime"] == "stops":
            # Persistent: the stick event at t* to rounding, and the block stays where it stopped.
            assert p["t"] == pytest.approx(c["t"], abs=1e-9)
            assert p["d"] == pytest.approx(c["d"], abs=1e-9)
            # Microcollisions: within half a flight, and the rest position within the envelope's
            # scale.
            assert m["t"] == pytest.approx(c["t"], abs=2e-2)
            assert m["d"] == pytest.approx(c["d"], abs=2e-3)
        elif c["regime"] == "accelerates":
            assert p["acceleration"] == pytest.approx(c["acceleration"], abs=1e-6)
            assert p["d"] == pytest.approx(c["d_end"], abs=1e-9)
        else:
            assert p["d"] == pytest.approx(c["d_end"], abs=1e-9)
    # The README shows this table, as made here.
    with open(os.path.join(ROOT, "README.md")) as f:
        readme = f.read()
    shown = readme.split("<!-- ramp-study:begin -->\n")[1].split("<!-- ramp-study:end -->")[0]
    assert shown == study.table(rows) + "\n"


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


POOL = os.path.join(ROOT, "scenarios", "pool_break.json")


def test_events_carry_each_collisions_phases_slips_and_normal_impulses():
    # The phases are a lone collision's integration (a group's records carry none). Under the
    # microcollision model the rack's sticking collisions are lone; under the persistent model
    # they strike held balls, as groups.
    r = palpable.run(POOL, set={"/settings/contact_model": "microcollisions"}, end=0.5)
    e = r.events
    n = len(e["t"])
    assert n > 10 and all(len(column) == n for column in e.values())
    collided = (e["kind"] == "collision") | (e["kind"] == "microcollision")
    detail = collided & (e["phases"] != "group")
    assert detail.sum() > 10
    phases = set(w.split("(")[0] for p in e["phases"][detail] for w in p.split(";"))
    assert {"slid", "stuck"} <= phases
    # Normal impulse = compression + restitution, both >= 0; slips are tangential.
    p_n = e["jx"] * e["nx"] + e["jy"] * e["ny"] + e["jz"] * e["nz"]
    total = e["normal_impulse_compression"] + e["normal_impulse_restitution"]
    assert np.allclose(total[detail], p_n[detail], rtol=1e-9, atol=1e-15)
    assert np.all(e["normal_impulse_compression"][detail] >= 0)
    before = np.stack([e["slip_before_x"], e["slip_before_y"], e["slip_before_z"]], axis=1)
    normal = np.stack([e["nx"], e["ny"], e["nz"]], axis=1)
    assert np.all(np.abs((before * normal).sum(axis=1)[detail]) <= 1e-9)
    stuck = detail & np.array([p.endswith("stuck") for p in e["phases"]])
    after = np.stack([e["slip_after_x"], e["slip_after_y"], e["slip_after_z"]], axis=1)
    assert stuck.sum() > 0
    assert np.all(np.linalg.norm(after[stuck], axis=1)
                  <= 1e-6 * (np.linalg.norm(before[stuck], axis=1) + e["approach_speed"][stuck]))
    # The contacts array is the collisions of the events table.
    assert len(r.contacts) == collided.sum()


def test_events_and_the_trace_as_pandas_data_frames():
    pd = pytest.importorskip("pandas")
    r = palpable.run(RAMP, set={"/settings/contact_model": "persistent"})
    events = r.events_frame()
    assert isinstance(events, pd.DataFrame)
    assert "stick" in set(events["kind"])
    stop = events[events["kind"] == "stick"]["t"].iloc[0]
    assert stop == pytest.approx(r.reference["stop_time_closed_form_s"], abs=1e-9)
    trace = r.frame()
    assert list(trace.columns[:3]) == ["t", "body", "x"]
    assert len(trace) == len(r.t) * len(r.bodies)


def test_impact_trajectory_is_u_of_p_z_from_u0_to_u_final():
    spec = {"K": [[2.5, 0, -1.5], [0, 4, 0], [-1.5, 0, 2.5]], "u0": [0.5, 0, -1],
            "friction": 0.5, "restitution": 0.5, "law": "stronge"}
    out = palpable.impact(spec, trajectory=True)
    path = out["trajectory"]
    assert path.shape[1] == 6
    assert list(path[0]) == [0, 0, 0, 0.5, 0, -1]
    assert np.all(np.diff(path[:, 0]) >= 0)
    assert path[-1, 0] == pytest.approx(out["impulse"][2], rel=1e-15)
    assert list(path[-1, 3:]) == pytest.approx(out["u_final"], rel=1e-12, abs=1e-15)
    assert "trajectory" not in palpable.impact(spec)


def test_state_of_an_unknown_body_is_a_key_error():
    sim = palpable.Simulation(RAMP)
    with pytest.raises(KeyError, match="no body named"):
        sim.state("nothing")


def test_a_run_may_keep_no_events():
    r = palpable.run(RAMP, events=False)
    assert len(r.events["t"]) == 0 and len(r.contacts) > 0
    assert r.events["phases"].shape == (0,)
