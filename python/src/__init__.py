"""fivebar: dynamics of planar five-bar (5R) mechanisms with load-dependent joint friction.

    import fivebar
    scene = fivebar.load_scene("datasets/scenes/paper.yaml",
                               overrides={"mechanism.links.2.mass": 1.5})
    run = fivebar.simulate(scene)          # dict of NumPy arrays, trajectory.csv columns
    inv = fivebar.inverse(scene, theta, omega, alpha)   # (N, 2) arrays -> M, N, Mf

Bad input raises ValueError with the command line's one-line message; failed numerics raise
fivebar.NumericalError. See docs/python.md.
"""
import os as _os

from . import _core
from ._core import NumericalError, Scene, inverse, simulate

__all__ = ["NumericalError", "Scene", "load_scene", "parse_scene", "simulate", "inverse",
           "identify", "optimize"]
__version__ = "0.1.0"


def load_scene(path, overrides=None):
    """Reads and validates a scene file (YAML).

    overrides: {"dotted.key": value} applied in order like the command line's
    `--set KEY=VALUE` (list elements by 0-based index: "mechanism.links.2.mass").
    Raises ValueError (the command line's message) on bad input.
    """
    return _core.load_scene(_os.fspath(path), overrides)


def parse_scene(text, name="<string>", overrides=None):
    """Parses a scene from YAML text; `name` names it in error messages."""
    return _core.parse_scene(text, name, overrides)


def identify(scene, log, **options):
    """Friction coefficients of `scene` from a torque log (CSV path or dict of arrays).

    Keyword options as `fivebar identify` (method, law, per_joint, loss, loss_scale,
    smooth_sign, estimate_rates, min_rate, sg_window, sg_order, threads, start_from_scene,
    window) plus validate=False. Returns a dict (identification.json's fields, per-sample
    arrays, 'fitted_scene').
    """
    if not isinstance(log, dict):
        log = _os.fspath(log)
    return _core.identify(scene, log, **options)


def optimize(scene, tasks, **options):
    """Energy-optimal rest-to-rest trajectories for a list of tasks.

    `tasks`: a tasks file (path) or a list of task dicts as in that file (name, duration,
    start, goal, torque_limit; docs/formats.md). Keyword options as `fivebar optimize`, with its
    defaults (refinement on; objective total_dissipation when the scene has winding data):
    threads, method, objective, regeneration, end_acceleration, global_search, starts,
    control_points, quadrature_points, singular_margin, refine, validate, plus
    trajectories=True. Returns {task name: dict of summary.csv fields, 'x', 'trajectory',
    'baseline'}.
    """
    if isinstance(tasks, (list, tuple)):
        import json as _json
        # JSON is YAML: the tasks file's own reader checks the dicts
        return _core.optimize_text(scene, _json.dumps({"tasks": list(tasks)}), **options)
    return _core.optimize(scene, _os.fspath(tasks), **options)


identify.__doc__ += "\n" + (_core.identify.__doc__ or "")
optimize.__doc__ += "\n" + (_core.optimize.__doc__ or "")
