"""Palpable from Python: impulse-based, event-driven rigid-body simulation.

    import palpable
    r = palpable.run("scenarios/block_on_ramp_decelerating.json", set={"/parameters/mu": 0.8})
    r.t, r.states["block"], r.summary["reference"]        # numpy arrays and a dict

Scenes are files or dicts (the palpable-scene/1 format); `set` applies the same JSON-pointer
overrides as `palpable run --set`. Bad input raises palpable.InputError (a ValueError) naming the
file and JSON pointer, as the command line does.
"""
import json
import os
import tempfile

import sys

try:
    try:
        import numpy as np
    except ImportError:
        # Another CPython of the same version than the Debian one the module was built with (a
        # pyenv python3 first on PATH, say) has no numpy of its own: Debian's python3-numpy, built
        # for the same ABI, is used from its dist-packages - appended, so the interpreter's own
        # packages still come first. Any other interpreter fails below with a clear message.
        _debian = "/usr/lib/python3/dist-packages"
        if os.path.isdir(_debian) and _debian not in sys.path:
            sys.path.append(_debian)
        import numpy as np
    from ._palpable import InputError, Simulation as _Simulation, __version__, commit
    from . import _palpable
except ImportError as e:  # another interpreter than the one the module was built for
    raise ImportError(
        "palpable: %s. The module is built for one Python (CMake's Python3_EXECUTABLE, the Debian "
        "/usr/bin/python3 by default) and needs its numpy (Debian python3-numpy, installed by "
        "tools/setup); this is %s (Python %d.%d)."
        % (e, sys.executable, sys.version_info[0], sys.version_info[1])) from e

__all__ = ["run", "impact", "sweep", "Simulation", "Result", "InputError", "__version__"]

_COLUMNS = ["x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz"]


def _overrides(set):
    if not set:
        return []
    if isinstance(set, dict):
        return ["%s=%s" % (k, json.dumps(v) if not isinstance(v, str) else v) for k, v in set.items()]
    return list(set)


class _SceneFile:
    """A scene path, or a dict written to a temporary file for the run's duration."""

    def __init__(self, scene):
        self.scene, self.temp = scene, None

    def __enter__(self):
        if isinstance(self.scene, (str, os.PathLike)):
            return os.fspath(self.scene)
        fd, self.temp = tempfile.mkstemp(suffix=".json", prefix="palpable-scene-")
        with os.fdopen(fd, "w") as f:
            json.dump(self.scene, f)
        return self.temp

    def __exit__(self, *exc):
        if self.temp:
            os.unlink(self.temp)


class Result:
    """A run: t (samples), bodies, states[name] (samples x 13), summary (dict), contacts (an array
    of collisions: t, body_a index, body_b index, px, py, pz), events (the events CSV's columns as
    numpy arrays, made on first use), reference (the summary's closed-form figures)."""

    def __init__(self, raw):
        self.t = raw["t"]
        self.bodies = list(raw["bodies"])
        self._states = raw["states"]
        self.states = {name: self._states[:, i, :] for i, name in enumerate(self.bodies)}
        self.summary = raw["summary"]
        self.contacts = raw["contacts"]
        self.reference = self.summary.get("reference")
        self._event_table = raw["events"]
        self._events = None

    @property
    def events(self):
        """Every event row as a dict of numpy arrays, the columns of `palpable run --events`: t,
        kind, body_a, body_b, px..pz (contact point), nx..nz (normal, from b to a), jx..jz
        (impulse on a), approach_speed, energy_change, centre_of_pressure, phases ("slid;stuck",
        "slid;resumed_sliding(dx dy dz)", ...), slip_before_*, slip_after_* (tangential relative
        contact velocity, world frame), normal_impulse_compression, normal_impulse_restitution
        (NaN where a row has none: a mode change, a group's contact)."""
        if self._events is None:
            self._events = self._event_table.columns()
        return self._events

    def events_frame(self):
        """The events as a pandas DataFrame (needs pandas)."""
        import pandas as pd
        return pd.DataFrame(self.events)

    def frame(self):
        """The trace as a pandas DataFrame (one row per body per sample; needs pandas)."""
        import pandas as pd
        n, m = len(self.t), len(self.bodies)
        df = pd.DataFrame(self._states.reshape(n * m, 13), columns=_COLUMNS)
        df.insert(0, "body", np.tile(self.bodies, n))
        df.insert(0, "t", np.repeat(self.t, m))
        return df


def run(scene, set=None, end=None, events=True):
    """Run a scene (path or dict) with overrides; returns a Result. events=False keeps no event
    rows (r.events is then empty; r.contacts is still there): a run whose microcollisions number
    hundreds of thousands keeps ~216 bytes for each otherwise."""
    with _SceneFile(scene) as path:
        return Result(_palpable.run(path, _overrides(set), end, events))


def impact(spec, trajectory=False):
    """Resolve one collision: the spec and the result of `palpable impact`, as dicts. With
    trajectory=True the result also has "trajectory": u(p_z) along the integration, an array of
    rows p_z, p_x, p_y, u_x, u_y, u_z (contact frame; `palpable impact --trajectory`)."""
    return _palpable.impact(spec, trajectory)


def sweep(scene, vary, figure, set=None):
    """Run every combination of `vary` ({pointer: [values]}) and apply `figure` (a callable on the
    Result) to each; returns a list of (values dict, figure value)."""
    import itertools
    keys = list(vary)
    rows = []
    for combo in itertools.product(*(vary[k] for k in keys)):
        overrides = dict(set or {})
        overrides.update(zip(keys, combo))
        rows.append((dict(zip(keys, combo)), figure(run(scene, set=overrides))))
    return rows


class Simulation:
    """A simulation to step: run_until(t), step(t_end), state(body), time."""

    def __init__(self, scene, set=None):
        self._file = _SceneFile(scene)
        path = self._file.__enter__()
        try:
            self._sim = _Simulation(path, _overrides(set))
        finally:
            self._file.__exit__(None, None, None)

    def __getattr__(self, name):
        return getattr(self._sim, name)
