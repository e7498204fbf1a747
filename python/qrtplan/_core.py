"""The ctypes layer over src/python/qrtpy.c (the C core's flat shim).

Loads ``_qrtcore.so`` from the package directory (an installed wheel) or,
for a source checkout, from the build tree (``build/python/qrtplan``, or
``$QRTPLAN_BUILD_DIR/python/qrtplan``); ``$QRTPLAN_CORE_LIB`` names the
library outright. The records below mirror the shim's structs, whose sizes
the library reports and this module checks at import.
"""
from __future__ import annotations

import ctypes
import os
from pathlib import Path

__all__ = ["lib", "Arm_c", "Params_c", "Target_c", "Result_c",
           "MAX_WAYPOINTS", "MAX_POINTS", "err_text"]

_D3 = ctypes.c_double * 3


class Arm_c(ctypes.Structure):
    _fields_ = [("link_m", _D3), ("link_radius_m", _D3),
                ("limit_deg", ctypes.c_double * 6), ("tool_m", ctypes.c_double),
                ("tool_radius_m", ctypes.c_double)]


class Params_c(ctypes.Structure):
    _fields_ = [("arm", Arm_c), ("margin_m", ctypes.c_double),
                ("cspace_margin_deg", ctypes.c_double),
                ("grid_deg", ctypes.c_double), ("use_astar", ctypes.c_long),
                ("simplify", ctypes.c_long), ("sample_draws", ctypes.c_long)]


class Target_c(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_long), ("value", _D3),
                ("facing", ctypes.c_long), ("elbow", ctypes.c_long)]


_L = ctypes.c_long
_F = ctypes.c_double


class Result_c(ctypes.Structure):
    _fields_ = [("status", _L), ("n_waypoints", _L), ("cost_deg", _F),
                ("lattice_cost_deg", _F), ("start_deg", _D3), ("goal_deg", _D3),
                ("start_facing", _L), ("start_elbow", _L), ("goal_facing", _L),
                ("goal_elbow", _L), ("start_node", _L), ("goal_node", _L),
                ("lattice_path_nodes", _L), ("nodes_expanded", _L),
                ("sampled_nodes", _L),
                ("cells_blocked", _L), ("points", _L), ("points_ignored", _L),
                ("points_dropped", _L), ("voxel_m", _F), ("end_free", _L),
                ("end_measured", _L), ("end_clearance_m", _F),
                ("has_clearance", _L), ("clearance_m", _F), ("c_seconds", _F), ("detail", ctypes.c_char * 256)]


def _find() -> str:
    env = os.environ.get("QRTPLAN_CORE_LIB")
    if env:
        return env
    here = Path(__file__).resolve().parent
    candidates = [here / "_qrtcore.so"]
    build = os.environ.get("QRTPLAN_BUILD_DIR")
    root = here.parents[1]
    candidates.append(Path(build) / "python" / "qrtplan" / "_qrtcore.so" if build
                      else root / "build" / "python" / "qrtplan" / "_qrtcore.so")
    for c in candidates:
        if c.is_file():
            return str(c)
    raise ImportError("qrtplan: the C core (_qrtcore.so) is not built: "
                      "`pip install .` the repository, or `make` it and set "
                      f"QRTPLAN_BUILD_DIR (looked in {', '.join(map(str, candidates))})")


lib = ctypes.CDLL(_find())

_P = ctypes.POINTER
_vp = ctypes.c_void_p
_dp = _P(ctypes.c_double)
for name, res, args in [
    ("qrtpy_layout", None, [_P(ctypes.c_long)]),
    ("qrtpy_params_default", None, [_P(Params_c)]),
    ("qrtpy_planner_new", _vp, [_P(Params_c), _P(ctypes.c_int), ctypes.c_char_p,
                                ctypes.c_size_t]),
    ("qrtpy_planner_free", None, [_vp]),
    # the arrays by address (ndarray.ctypes.data): cheaper than data_as
    ("qrtpy_plan", ctypes.c_int, [_vp, _vp, ctypes.c_long, _P(Target_c),
                                  _P(Target_c), ctypes.c_int, _P(Result_c), _vp]),
    ("qrtpy_arm_default", ctypes.c_int, [_P(Arm_c)]),
    ("qrtpy_arm_validate", ctypes.c_int, [_P(Arm_c)]),
    ("qrtpy_forward_points", ctypes.c_int, [_P(Arm_c), _dp, _dp]),
    ("qrtpy_capsules", ctypes.c_int, [_P(Arm_c), _dp, _dp, _dp]),
    ("qrtpy_ik", ctypes.c_int, [_P(Arm_c), _dp, ctypes.c_double, _dp,
                                _P(ctypes.c_long), _P(ctypes.c_int)]),
    ("qrtpy_check_joints", ctypes.c_int, [_P(Arm_c), _dp]),
    ("qrtpy_clearance", ctypes.c_double, [_vp, _dp, _dp, ctypes.c_long]),
    ("qrt_err_name", ctypes.c_char_p, [ctypes.c_int]),
    ("qrt_plan_status_name", ctypes.c_char_p, [ctypes.c_int]),
]:
    f = getattr(lib, name)
    f.restype = res
    f.argtypes = args

_layout = (ctypes.c_long * 6)()
lib.qrtpy_layout(_layout)
_want = [ctypes.sizeof(t) for t in (Arm_c, Params_c, Target_c, Result_c)]
if list(_layout[:4]) != _want:
    raise ImportError(f"qrtplan: {lib._name} lays its records out as {list(_layout[:4])} "
                      f"bytes, this module as {_want}: a library of another version")
MAX_WAYPOINTS = int(_layout[4])
MAX_POINTS = int(_layout[5])


def err_text(rc: int) -> str:
    """The core's text for an error code (qrt_err_name)."""
    return lib.qrt_err_name(rc).decode()
