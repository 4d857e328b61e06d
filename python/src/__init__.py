"""fivebar: dynamics of planar five-bar (5R) mechanisms with load-dependent joint friction.

    import fivebar
    scene = fivebar.load_scene("datasets/scenes/paper.yaml",
                               overrides={"mechanism.links.2.mass": 1.5})
    run = fivebar.simulate(scene, duration=1.0)   # trajectory.csv columns, summary.json
    run.theta1, run.summary.estimated_max_error_rad
    inv = fivebar.inverse(scene, theta, omega, alpha)   # (N, 2) arrays -> M, N, Mf
    fit = fivebar.identify(scene, "log.csv")
    fit.parameters["coulomb"].value, fit.condition_number

Results are dicts whose keys also read as attributes; the fields of the command line's JSON
files are all there. Bad input raises ValueError with the command line's one-line message;
failed numerics raise fivebar.NumericalError; what the command line prints as a warning goes
through warnings.warn with the category fivebar.FivebarWarning. See docs/python.md.
"""
import json as _json
from collections.abc import Mapping as _Mapping
import os as _os
import re as _re
import warnings as _warnings

import numpy as _np

from . import _core
from ._core import NumericalError, Scene

__all__ = ["FivebarWarning", "NumericalError", "Parameters", "Record", "Scene", "load_scene",
           "parse_scene", "simulate", "inverse", "identify", "optimize"]
__version__ = "0.1.0"


class FivebarWarning(UserWarning):
    """What `fivebar` prints as `fivebar: warning: ...`: the run gave a result to read with care
    (a scene value in suspicious units, a parameter the log does not determine, a run check that
    failed, ...). Filter it like any warning: warnings.simplefilter("error", FivebarWarning)."""


class Record(dict):
    """A result: a dict whose keys also read as attributes (run.summary.steps is
    run["summary"]["steps"]). Keys that are not identifiers are read with [...]."""

    __slots__ = ()

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(f"no field '{name}' (fields: {', '.join(self)})") from None

    def __dir__(self):
        return sorted(set(super().__dir__()) | {k for k in self if k.isidentifier()})

    def copy(self):
        return Record(self)

    def to_json(self, **dumps_options):
        """The record as JSON text, in the form of the command line's files: arrays as lists,
        nan as null, a Scene as its YAML text. json.dumps(record) itself refuses the NumPy
        arrays; dumps_options go to json.dumps (indent=2, ...)."""
        return _json.dumps(_jsonable(self), **dumps_options)


class Parameters(list):
    """The estimated parameters in their order, also by name:
    fit.parameters[0] and fit.parameters["coulomb"] are the same Record (name, unit, value, std,
    ci95_low, ci95_high, ...). keys(), items() and `name in parameters` work as for a dict."""

    def __getitem__(self, key):
        if isinstance(key, str):
            for p in self:
                if p["name"] == key:
                    return p
            raise KeyError(f"no parameter '{key}' (parameters: {', '.join(self.keys())})")
        return super().__getitem__(key)

    def __contains__(self, key):
        return key in self.keys() if isinstance(key, str) else super().__contains__(key)

    def keys(self):
        return [p["name"] for p in self]

    def items(self):
        return [(p["name"], p) for p in self]

    def values(self):
        return list(self)

    def get(self, name, default=None):
        return self[name] if name in self else default


def _record(value):
    """dicts as Records (nested too), lists of them as lists, 'parameters' as Parameters."""
    if isinstance(value, dict):
        out = Record((k, _record(v)) for k, v in value.items())
        if isinstance(out.get("parameters"), list):
            dict.__setitem__(out, "parameters", Parameters(out["parameters"]))
        return out
    if isinstance(value, list):
        return [_record(v) for v in value]
    return value


def _jsonable(value):
    """value with NumPy arrays and numbers as lists and Python numbers, nan and inf as None
    (null, as the command line writes a number that is not determined), a Scene as its YAML."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, _np.ndarray)):
        return [_jsonable(v) for v in value]
    if isinstance(value, _np.generic):
        value = value.item()
    if isinstance(value, float) and not _np.isfinite(value):
        return None
    if isinstance(value, Scene):
        return value.to_yaml()
    return value


def _warn(messages, stacklevel=3):
    for message in messages:
        _warnings.warn(message, FivebarWarning, stacklevel=stacklevel)


def _floats(value):
    """`value` as a float64 array (lists, tuples, int and float32 arrays converted); a value
    NumPy cannot convert is passed on as it is, for the error naming the argument."""
    if value is None:
        return None
    try:
        return _np.asarray(value, dtype=_np.float64)
    except (TypeError, ValueError):
        return value


def _plain(value):
    """NumPy scalars and arrays as Python numbers and lists (for json.dumps)."""
    return value.tolist() if hasattr(value, "tolist") else str(value)


def _override_values(overrides):
    """{"dotted.key": value} with NumPy scalars and arrays (0-d included) as Python numbers and
    lists; other values are passed on as they are, for the error naming the key."""
    if not isinstance(overrides, dict):
        return overrides
    return {k: v.tolist() if isinstance(v, (_np.ndarray, _np.generic)) else v
            for k, v in overrides.items()}


def _log_columns(log):
    """A torque log given as {column: array} or as a NumPy structured array (np.genfromtxt(...,
    names=True)): each column a 1-D float64 array."""
    if isinstance(log, _np.ndarray):
        if not log.dtype.names:
            raise ValueError("log: (argument): expected a CSV path, a dict of arrays or a "
                             f"structured array with named columns, got an array of {log.dtype}")
        log = {name: log[name] for name in log.dtype.names}
    columns = {}
    for name, values in log.items():
        array = _floats(values)
        if not isinstance(array, _np.ndarray) or array.ndim != 1:
            shape = array.shape if isinstance(array, _np.ndarray) else type(values).__name__
            raise ValueError(f"log: {name}: (argument): expected a 1-D array of numbers, "
                             f"got {shape}")
        columns[name] = array
    return columns


def load_scene(path, overrides=None):
    """Reads and validates a scene file (YAML).

    overrides: {"dotted.key": value} applied in order like the command line's
    `--set KEY=VALUE` (list elements by 0-based index: "mechanism.links.2.mass").
    Raises ValueError (the command line's message) on bad input; likely unit mistakes come as
    FivebarWarning.
    """
    scene = _core.load_scene(_os.fspath(path), _override_values(overrides))
    _warn(scene.warnings)
    return scene


def parse_scene(text, name="<string>", overrides=None):
    """Parses a scene from YAML text, or builds it from a dict of the same structure
    ({"mechanism": {"ground_length": 0.29, "links": [...]}, ...}); `name` names it in error
    messages. Checked as a scene file is (ValueError with the command line's message)."""
    if isinstance(text, dict):
        text = _json.dumps(text, default=_plain)  # JSON is YAML: one parser, every check
        try:
            scene = _core.parse_scene(text, name, _override_values(overrides))
        except ValueError as e:  # the line numbers of that one-line text mean nothing here
            raise ValueError(_re.sub(r" \(line \d+\)", "", str(e))) from None
    else:
        scene = _core.parse_scene(text, name, _override_values(overrides))
    _warn(scene.warnings)
    return scene


def _scene_replace(self, overrides=None, /, **keys):
    """A copy of the scene with some values changed, checked as a scene file is.

    scene.replace({"simulation.duration": 1.0, "mechanism.links.2.mass": 1.5}) or, with "__"
    for ".", scene.replace(simulation__duration=1.0). The scene itself is not changed.
    """
    merged = dict(overrides or {})
    merged.update((k.replace("__", "."), v) for k, v in keys.items())
    scene = self._replace(_override_values(merged))
    _warn(scene.warnings)
    return scene


Scene.replace = _scene_replace
Scene.with_ = _scene_replace


def simulate(scene, overrides=None, *, twin=False, **simulation):
    """Forward simulation of `scene`, as `fivebar simulate` (error estimate included).

    Keywords change the scene's `simulation.*` keys for this run: simulate(scene,
    duration=1.0, rtol=1e-9); `overrides` ({"dotted.key": value}) changes any key.
    twin=True also runs the frictionless twin ('frictionless', summary.frictionless).
    Returns a Record: one float64 array per trajectory.csv column (t, theta1..theta4, ...,
    E_diss, W_in, W_ext; a four-bar scene's: theta1..theta3, M1, N1..N4, ...), 'mode'
    (N, joints) int joint modes (+1/-1 slip, 0 at rest, 2 stuck) and
    'summary' (every field of summary.json). A run whose own checks fail has
    summary.status 'failed' and warns (FivebarWarning); a run that fails raises
    fivebar.NumericalError.
    """
    if overrides or simulation:
        merged = dict(overrides or {})
        merged.update(("simulation." + k, v) for k, v in simulation.items())
        scene = scene.replace(merged)
    run = _record(_core.simulate(scene, twin))
    summary = run["summary"]
    _warn([f"{scene.path}: {s['message']}" for s in (summary, summary.get("frictionless"))
           if s and s.get("status") != "ok" and "message" in s])
    return run


def inverse(scene, theta, omega, alpha, t=None, threads=0):
    """Friction-aware inverse dynamics of N states.

    theta, omega, alpha: (N, 2) arrays of cranks 1 and 2 (anything np.asarray converts to
    float64: lists, int or float32 arrays); t: (N,) times, needed when loads.M3 or loads.F
    depend on t. Returns a Record {'M': (N, 2) driving torques [N m], 'N': (N, 5) joint
    reaction magnitudes [N], 'Mf': (N, 5) friction torques [N m]} (joints O, B, C, D, D0).
    A four-bar scene takes the crank's theta, omega, alpha as (N,) or (N, 1) arrays and returns
    'M' (N, 1), 'N' and 'Mf' (N, 4) (joints O, B, C, D0); a crank at rest is held as
    `fivebar inverse` holds it (docs/hold.md). Runs with the GIL released, on `threads` threads
    (0: all cores) when N is large.
    """
    return Record(_core.inverse(scene, _floats(theta), _floats(omega), _floats(alpha),
                                _floats(t), threads))


def identify(scene, log, **options):
    """Friction coefficients of `scene` from a torque log: a CSV path, a dict of arrays or a
    NumPy structured array (np.genfromtxt(path, delimiter=",", names=True, skip_header=k), k
    the '#' lines above the header).

    Keyword options as `fivebar identify` (method, law, per_joint, loss, loss_scale,
    smooth_sign, estimate_rates, min_rate, sg_window, sg_order, threads, start_from_scene,
    window) plus validate=False. Returns a Record with every field of identification.json
    (parameters also by name: fit.parameters["coulomb"].std), the covariance, the per-sample
    arrays and 'fitted_scene'. Its warnings also go through warnings.warn (FivebarWarning), and
    so does a fit its own checks reject (status 'failed', status_reason).
    """
    if isinstance(log, (_Mapping, _np.ndarray)):
        log = _log_columns(log)
    else:
        log = _os.fspath(log)
    fit = _record(_core.identify(scene, log, **options))
    _warn(fit["warnings"])
    # a fit its own checks reject (the command line exits 3): status 'failed' and a warning
    if fit.get("status") != "ok":
        _warn([f"the fit should not be used: {fit.get('status_reason', '')}"])
    return fit


def optimize(scene, tasks, **options):
    """Energy-optimal rest-to-rest trajectories for a list of tasks.

    `tasks`: a tasks file (path) or a list of task dicts as in that file (name, duration,
    start, goal, torque_limit; docs/formats.md). Keyword options as `fivebar optimize`, with its
    defaults (refinement on; objective total_dissipation when the scene has winding data):
    threads, method, objective, regeneration, end_acceleration, global_search, starts,
    control_points, quadrature_points, singular_margin, refine, validate, plus
    trajectories=True. Returns a Record {task name: Record of summary.csv fields, 'x',
    'trajectory', 'baseline'} (best.reach_right.trajectory.M1; task names that are not
    identifiers with [...]).
    """
    if isinstance(tasks, (list, tuple)):
        import json as _json
        # JSON is YAML: the tasks file's own reader checks the dicts (NumPy numbers as floats)
        text = _json.dumps({"tasks": list(tasks)}, default=float)
        return _record(_core.optimize_text(scene, text, **options))
    return _record(_core.optimize(scene, _os.fspath(tasks), **options))


identify.__doc__ += "\n" + (_core.identify.__doc__ or "")
optimize.__doc__ += "\n" + (_core.optimize.__doc__ or "")
