"""teleop: experiments on the teleoperation system from Python (docs/python.md).

Sessions run in-process on a simulated clock, exactly as ``teleop_campaign`` runs them: the
master's cycle (device, controller, safety layer, the two delay channels) against the server's
world. A session's ``summary`` holds the figures of the campaign results table (same names) and
its ``traces`` one numpy array per recorded channel, one row per master cycle.

    import teleop
    r = teleop.run_session(scheme="wave-variables", delay_ms=50, seed=3)
    r.summary["verdict"], r.traces["contact_force_n"].shape

Bad arguments raise ValueError naming the argument, the value and the allowed range.
"""

import itertools
import json
import math
import os
from concurrent.futures import ThreadPoolExecutor

from . import _teleop
from ._teleop import Scene, World, load_scene, read_recording, scheme_labels

__all__ = [
    "Scene", "World", "SessionResult", "load_scene", "run_session", "run_campaign_point",
    "campaign_runs", "sweep", "table", "read_recording", "write_recording", "scheme_labels",
]

# Every argument of run_session that is a campaign axis: (allowed low, high) of the number.
_NUMBER_RANGES = {
    "stiffness_n_per_m": (1.0, 1e6),
    "damping_ns_per_m": (0.0, 1e4),
    "press_depth_m": (0.0, 0.2),
    "tremor_m": (0.0, 0.01),
    "gain": (0.0, 1e5),
    "delay_ms": (0.0, 10000.0),
    "jitter_ms": (0.0, 1000.0),
    "loss": (0.0, 1.0),
    "burst_p_gb": (0.0, 1.0),
    "burst_p_bg": (1e-6, 1.0),
    "max_force_n": (0.0, 1000.0),
    "duration_s": (0.0, 3600.0),
    "homing_s": (0.0, 60.0),
}
_SCRIPTS = ("press-slip", "hold", "line", "circle", "step")
_ENVIRONMENTS = ("sphere", "wall")
_SEED_MAX = 2 ** 53


class SessionResult:
    """One session: ``summary`` (dict, the results table's row by column name), ``traces``
    (dict of numpy arrays, one row per master cycle), ``row`` and ``header`` (the CSV text
    teleop_campaign writes for the same run), ``dropped`` (cycles past the traces' room)."""

    def __init__(self, d):
        self.summary = d["summary"]
        self.traces = d["traces"]
        self.row = d["row"]
        self.header = d["header"]
        self.dropped = d["dropped"]

    def __repr__(self):
        s = self.summary
        return "SessionResult(verdict=%r, scheme=%r, delay_ms=%r, cycles=%d)" % (
            s.get("verdict"), s.get("scheme"), s.get("delay_ms"), len(self.traces["time_s"]))


def _range_error(name, value, allowed):
    return ValueError("%s = %r is outside the allowed range (%s)" % (name, value, allowed))


def _check_number(name, value):
    low, high = _NUMBER_RANGES[name]
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise _range_error(name, value, "a number, %g to %g" % (low, high)) from None
    if not math.isfinite(v) or v < low or v > high:
        raise _range_error(name, value, "%g to %g" % (low, high))
    return v


def _check_choice(name, value, choices):
    if value not in choices:
        raise ValueError("%s = %r is not one of %s" % (name, value, ", ".join(choices)))
    return value


def _session_params(scene, scheme, seed, script, environment, trajectory, numbers):
    """The campaign axes of one session, checked."""
    axes = {"scheme": _check_choice("scheme", scheme, tuple(scheme_labels())),
            "script": _check_choice("script", script, _SCRIPTS)}
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= _SEED_MAX:
        raise _range_error("seed", seed, "an integer, 0 to 2^53")
    axes["seed"] = seed
    if scene is None:
        axes["environment"] = _check_choice("environment", environment, _ENVIRONMENTS)
    if trajectory is not None:
        axes["trajectory"] = os.path.abspath(os.fspath(trajectory))
    for name, value in numbers.items():
        if value is not None:
            axes[name] = _check_number(name, value)
    return axes


def _session_campaign(scene, scheme, seed, script, environment, trajectory, duration_s,
                      homing_s, numbers):
    """The one-run campaign (JSON text, which the campaign loader reads as YAML) of a session."""
    axes = _session_params(scene, scheme, seed, script, environment, trajectory, numbers)
    campaign = {"name": "python-session", "sweeps": [dict(name="session", **axes)]}
    if scene is not None:
        path = scene.file if isinstance(scene, Scene) else os.fspath(scene)
        campaign["model"] = "world"
        campaign["defaults"] = {"scene": os.path.abspath(path)}
        if homing_s is not None:
            campaign["homing_s"] = _check_number("homing_s", homing_s)
    elif homing_s is not None:
        raise ValueError("homing_s = %r applies to a scene (world model) only" % (homing_s,))
    if duration_s is not None:
        campaign["duration_s"] = _check_number("duration_s", duration_s)
    return json.dumps(campaign)


def run_session(params=None, *, scene=None, scheme="position-position", delay_ms=0.0,
                jitter_ms=0.0, loss=0.0, seed=1, script="press-slip", gain=None,
                duration_s=None, homing_s=None, environment="sphere", stiffness_n_per_m=None,
                damping_ns_per_m=None, press_depth_m=None, tremor_m=None, max_force_n=None,
                burst_p_gb=None, burst_p_bg=None, trajectory=None):
    """Runs one in-process session and returns a SessionResult.

    scene: a scene file or a Scene (the world model: robot, deformable bodies); None: the point
    model (the press task of teleop_bench delay on `environment`, sphere or wall). The other
    arguments are the campaign axes of docs/campaigns.md with their units and ranges;
    `max_force_n` and `trajectory` (a replay CSV) choose the device, `script` the operator.
    `params`: a dict of the same arguments (a keyword left at its default takes it). The session runs
    without the GIL, so threads run sessions in parallel.
    """
    args = dict(scene=scene, scheme=scheme, delay_ms=delay_ms, jitter_ms=jitter_ms, loss=loss,
                seed=seed, script=script, gain=gain, duration_s=duration_s, homing_s=homing_s,
                environment=environment, stiffness_n_per_m=stiffness_n_per_m,
                damping_ns_per_m=damping_ns_per_m, press_depth_m=press_depth_m,
                tremor_m=tremor_m, max_force_n=max_force_n, burst_p_gb=burst_p_gb,
                burst_p_bg=burst_p_bg, trajectory=trajectory)
    if params is not None:
        unknown = sorted(set(params) - set(args))
        if unknown:
            raise ValueError("params: unknown key(s) %s (allowed: %s)"
                             % (", ".join(unknown), ", ".join(sorted(args))))
        defaults = run_session.__kwdefaults__
        for key, value in params.items():
            if args[key] == defaults[key]:
                args[key] = value
    numbers = {k: args.pop(k) for k in list(args) if k in _NUMBER_RANGES
               and k not in ("duration_s", "homing_s")}
    text = _session_campaign(args["scene"], args["scheme"], args["seed"], args["script"],
                             args["environment"], args["trajectory"], args["duration_s"],
                             args["homing_s"], numbers)
    return SessionResult(_teleop.run_campaign_text(text, "teleop.run_session", 0))


def sweep(jobs=1, **axes):
    """Runs the Cartesian product of the axes given as lists (the others fixed), as a campaign
    sweep does: the last axis varies fastest. Sessions run on `jobs` threads (they release the
    GIL); the results come back in grid order, the same whatever `jobs` is.

        rs = teleop.sweep(jobs=2, scheme=["tdpa", "wave-variables"], delay_ms=[0, 50, 100])
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or not 1 <= jobs <= 256:
        raise _range_error("jobs", jobs, "an integer, 1 to 256")
    names = [k for k, v in axes.items() if isinstance(v, (list, tuple))]
    fixed = {k: v for k, v in axes.items() if k not in names}
    points = [dict(fixed, **dict(zip(names, values)))
              for values in itertools.product(*(axes[k] for k in names))]
    if jobs == 1:
        return [run_session(**p) for p in points]
    with ThreadPoolExecutor(jobs) as pool:
        return list(pool.map(lambda p: run_session(**p), points))


def table(results):
    """The summaries of several results as columns: {column: numpy array} (numbers as float64
    or int64, text as str arrays), rows in the order of `results`."""
    import numpy as np
    if not results:
        return {}
    columns = {}
    for name in results[0].summary:
        values = [r.summary[name] for r in results]
        if all(isinstance(v, int) for v in values):
            columns[name] = np.array(values, dtype=np.int64)
        elif all(isinstance(v, (int, float)) for v in values):
            columns[name] = np.array(values, dtype=np.float64)
        else:
            columns[name] = np.array([str(v) for v in values])
    return columns


def run_campaign_point(campaign_file, index):
    """Runs run `index` (the run id, from 0) of a campaign file: the row teleop_campaign
    writes for it, as a SessionResult with its traces."""
    return SessionResult(_teleop.run_campaign_file(os.fspath(campaign_file), int(index)))


def campaign_runs(campaign_file):
    """Every run's parameters of a campaign file (dicts, the results table's parameter
    columns), in run-id order."""
    return _teleop.campaign_runs(os.fspath(campaign_file))


def write_recording(path, result, format=""):
    """Writes a session's traces (a SessionResult or its traces dict) as a recording of
    teleop/slave_state and teleop/master_state, one sample of each per cycle: MCAP, or SQLite
    for .db/.sqlite names (`format` "mcap" or "sqlite" forces one). Returns the sample count."""
    traces = result.traces if isinstance(result, SessionResult) else result
    return _teleop.write_recording(os.fspath(path), traces, format)
