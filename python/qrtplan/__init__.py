"""qrtplan: the C core's path planner for the 3-DoF arm, from Python.

    import numpy as np, qrtplan
    r = qrtplan.plan(points, start=[-90, 0, 0], goal=[90, 0, 0])
    r.status, r.waypoints_deg, r.cost_deg

See docs/python.md. Submodules: ``qrtplan.kinematics`` (the arm through the
core), ``qrtplan.lcm`` (a client of the daemon qrtpland),
``qrtplan.lcmtypes`` (the lcm-gen message types).
"""
from __future__ import annotations

import os
from pathlib import Path

# A source checkout (python/ on sys.path): the build tree holds the C layer
# and the generated message types (build/python/qrtplan); an installed
# wheel holds them here.
_build = Path(os.environ.get("QRTPLAN_BUILD_DIR",
                             Path(__file__).resolve().parents[2] / "build"))
if not (Path(__file__).parent / "lcmtypes").is_dir() and \
        (_build / "python" / "qrtplan").is_dir():
    __path__.append(str(_build / "python" / "qrtplan"))  # noqa: F821

from .errors import (AbiError, InvalidInput, LimitsError, QrtError,  # noqa: E402
                     TooBigError)

__version__ = "0.1.0"
__all__ = ["QrtError", "InvalidInput", "LimitsError", "TooBigError", "AbiError",
           "__version__"]

try:
    from .planner import (Joints, PlanResult, Planner, Point,  # noqa: E402,F401
                          plan, plan_scene)
    __all__ += ["Planner", "PlanResult", "Joints", "Point", "plan", "plan_scene"]
except ImportError as _e:  # no numpy yet, or the C layer not built
    _import_error = _e

    _planner_names = ("Planner", "PlanResult", "Joints", "Point", "plan", "plan_scene")


def __getattr__(name):
    """qrtplan.plan_t etc.: the message types, as lcm-gen's top-level
    package has them (code written for build/lcmtypes/python keeps working
    with the installed package)."""
    if name.endswith("_t") and not name.startswith("_"):
        from . import lcmtypes
        try:
            return getattr(lcmtypes, name)
        except AttributeError:
            pass
    if "_import_error" in globals() and name in _planner_names:
        raise ImportError(str(_import_error)) from _import_error
    raise AttributeError(f"module 'qrtplan' has no attribute {name!r}")
