"""The planner: numpy points in, a joint path out, through the C core.

    import numpy as np
    from qrtplan import Planner, Point

    planner = Planner(margin_m=0.01, grid_deg=5)       # the core's defaults
    r = planner.plan(points, start=[-90, 0, 0], goal=Point(0.5, 0.2, 0.3))
    if r.ok:
        r.waypoints_deg          # (M, 3) float64, degrees
"""
from __future__ import annotations

import ctypes
import math
import threading
import warnings
from dataclasses import dataclass
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np

from . import _core
from .errors import InvalidInput, QrtError, error_for
from .kinematics import ELBOW, FACING, Arm

__all__ = ["Planner", "PlanResult", "Joints", "Point", "plan", "plan_scene",
           "CapacityWarning", "InputTypeError"]

_KIND_JOINTS, _KIND_XYZ, _KIND_TOOL_TIP = 0, 1, 2
_FACING_CODE = {v: k for k, v in FACING.items() if v != "both"}
_ELBOW_CODE = {v: k for k, v in ELBOW.items() if v != "both"}


class InputTypeError(InvalidInput, TypeError):
    """Input of a type or dtype the planner does not take."""


class CapacityWarning(UserWarning):
    """Points were merged into voxels or dropped: the table was too small."""


@dataclass(frozen=True)
class Joints:
    """A start or goal as joints in degrees (alpha, sigma, eta)."""
    alpha: float
    sigma: float
    eta: float


@dataclass(frozen=True)
class Point:
    """A start or goal as a point in metres for the end effector (aim
    "end_effector") or the tool tip (aim "tool_tip"), with the IK branches
    it may take: facing "any", "front" or "back"; elbow "any", "up" or
    "down" (docs/spec.md section Kinematics)."""
    x: float
    y: float
    z: float
    facing: str = "any"
    elbow: str = "any"
    aim: str = "end_effector"


Target = Union[Joints, Point, Mapping[str, Any], Sequence[float], np.ndarray]


@dataclass
class PlanResult:
    """A plan (docs/spec.md section Plan). status: "ok", "no_path",
    "start_blocked", "goal_blocked", "unreachable" or "capacity"; detail:
    the core's sentence; waypoints_deg: (M, 3) degrees, (0, 3) unless ok;
    cost_deg: the path's joint-space length (None unless ok); clearance_m:
    an ok plan's certified clearance in metres (docs/spec.md section
    Guarantee, Clearance), None when not ok or when no point was given
    (the CLI's null); stats: the CLI's stats without its timings, plus
    "c_seconds" (the C call's wall time)."""
    status: str
    detail: str
    waypoints_deg: np.ndarray
    cost_deg: Optional[float]
    stats: dict
    start_deg: Optional[np.ndarray] = None
    goal_deg: Optional[np.ndarray] = None
    start_ik: Optional[dict] = None
    goal_ik: Optional[dict] = None
    end_clearance_m: Optional[float] = None
    clearance_m: Optional[float] = None

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def to_dict(self) -> dict:
        """The plan as `qrtplan plan` writes it (JSON types), but for
        stats' time_us."""
        d: dict = {"version": 1, "status": self.status, "detail": self.detail}
        if self.ok:
            d["waypoints_deg"] = self.waypoints_deg.tolist()
            d["cost_deg"] = self.cost_deg
            d["clearance_m"] = self.clearance_m  # None: the CLI's null
        for key in ("start_deg", "goal_deg"):
            v = getattr(self, key)
            if v is not None:
                d[key] = v.tolist()
                ik = getattr(self, key[:-4] + "_ik")
                if ik is not None:
                    d[key[:-4] + "_ik"] = dict(ik)
        if self.end_clearance_m is not None:
            d["end_clearance_m"] = self.end_clearance_m
        d["stats"] = {k: v for k, v in self.stats.items() if k != "c_seconds"}
        return d


def _dp(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def as_points(points: Any, check_finite: bool = True) -> np.ndarray:
    """points as a C-contiguous (N, 3) float64 array, checked: float64 is
    used as given (no copy when contiguous); float32 and integer arrays are
    converted (exactly); other dtypes raise InputTypeError; a shape other
    than (N, 3) (an empty list is (0, 3)), NaN or infinity InvalidInput.
    check_finite False leaves NaN and infinity to the core, which refuses
    them too (Planner.plan: one pass over the points instead of two)."""
    a = points if isinstance(points, np.ndarray) else np.asarray(points)
    if a.dtype.kind not in "fiu" or a.dtype.itemsize > 8:
        raise InputTypeError(f"points must be float or integer numbers (x, y, z "
                             f"metres), not dtype {a.dtype}")
    if a.ndim == 1 and a.size == 0:
        a = a.reshape(0, 3)
    if a.ndim != 2 or a.shape[1] != 3:
        raise InvalidInput(f"points must be an (N, 3) array of x, y, z metres, "
                           f"got shape {a.shape}")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if check_finite:
        _check_finite(a)
    return a


def _check_finite(a: np.ndarray) -> None:
    if a.size and not np.isfinite(a).all():
        i = int(np.flatnonzero(~np.isfinite(a).all(axis=1))[0])
        raise InvalidInput(f"points must be finite: row {i} is {a[i].tolist()} "
                           f"(the core: {_core.err_text(-1)})")


def _three(v: Any, what: str) -> list[float]:
    if type(v) in (list, tuple) and len(v) == 3 and \
            all(type(x) in (int, float) for x in v):  # the common case, fast
        out = [float(x) for x in v]
        if math.isfinite(out[0] + out[1] + out[2]):
            return out
    a = v if isinstance(v, np.ndarray) else np.asarray(v)
    if a.dtype.kind not in "fiu":
        raise InputTypeError(f"{what} must be 3 real numbers, not dtype {a.dtype}")
    if a.shape != (3,):
        raise InvalidInput(f"{what} must be 3 numbers, got shape {a.shape}")
    out = [float(x) for x in a]
    if not all(math.isfinite(x) for x in out):
        raise InvalidInput(f"{what} must be finite, got {out} "
                           f"(the core: {_core.err_text(-1)})")
    return out


def _target(t: Target, what: str) -> "_core.Target_c":
    c = _core.Target_c()
    if isinstance(t, Joints):
        c.kind, c.value[:] = _KIND_JOINTS, _three([t.alpha, t.sigma, t.eta], what)
        return c
    if isinstance(t, Point):
        t = {"xyz_m": [t.x, t.y, t.z], "ik": {"facing": t.facing, "elbow": t.elbow},
             "aim": t.aim}
    if isinstance(t, Mapping):
        unknown = set(t) - {"joints_deg", "xyz_m", "ik", "aim"}
        if unknown or ("joints_deg" in t) == ("xyz_m" in t):
            raise InvalidInput(f"{what} must have joints_deg or xyz_m (and for "
                               f"xyz_m optionally ik, aim), got keys {sorted(t)}")
        if "joints_deg" in t:
            if "ik" in t or "aim" in t:
                raise InvalidInput(f"{what}.ik and .aim apply only to xyz_m")
            c.kind, c.value[:] = _KIND_JOINTS, _three(t["joints_deg"], what + ".joints_deg")
            return c
        aim = t.get("aim", "end_effector")
        if aim not in ("end_effector", "tool_tip"):
            raise InvalidInput(f'{what}.aim is {aim!r}; valid: "end_effector", "tool_tip"')
        ik = t.get("ik", {})
        if not isinstance(ik, Mapping) or set(ik) - {"facing", "elbow"}:
            raise InvalidInput(f"{what}.ik must be an object with facing and/or elbow")
        facing, elbow = ik.get("facing", "any"), ik.get("elbow", "any")
        if facing not in _FACING_CODE or elbow not in _ELBOW_CODE:
            raise InvalidInput(f"{what}.ik: facing one of any, front, back; elbow "
                               f"one of any, up, down (got {facing!r}, {elbow!r})")
        c.kind = _KIND_TOOL_TIP if aim == "tool_tip" else _KIND_XYZ
        c.value[:] = _three(t["xyz_m"], what + ".xyz_m")
        c.facing, c.elbow = _FACING_CODE[facing], _ELBOW_CODE[elbow]
        return c
    if isinstance(t, (str, bytes)):
        raise InputTypeError(f"{what} must be joints in degrees, Joints, Point or a "
                             f"scene target dict, not {type(t).__name__}")
    c.kind, c.value[:] = _KIND_JOINTS, _three(t, what + " (joints, degrees)")
    return c


class Planner:
    """A planner with its own state (the core's struct qrt_planner, ~15.7
    MB in the host profile, allocated once here and freed by close() or
    garbage collection).

    arm: an Arm, a scene's "arm" dict, or None for the default arm.
    margin_m, cspace_margin_deg, grid_deg, use_astar, simplify,
    sample_draws: the core's parameters (None: the core's defaults, as a
    scene file that omits them; sample_draws 0: no sampled fallback, as
    `qrtplan plan --sample-draws 0`). whole_mask: build the whole C-space mask before every plan
    (`qrtplan plan --whole-mask`) instead of only the nodes the plan reads
    (the default; the same plan). Raises InvalidInput, TooBigError or
    AbiError with the core's text when the core refuses the settings.
    """

    def __init__(self, arm: Union[Arm, Mapping[str, Any], None] = None, *,
                 margin_m: Optional[float] = None,
                 cspace_margin_deg: Optional[float] = None,
                 grid_deg: Optional[float] = None, use_astar: bool = True,
                 simplify: bool = True, sample_draws: Optional[int] = None,
                 whole_mask: bool = False):
        self._h = None
        if arm is None:
            arm = Arm.default()
        elif isinstance(arm, Mapping):
            arm = Arm.from_scene({"arm": arm})
        elif not isinstance(arm, Arm):
            raise InputTypeError(f"arm must be an Arm, a dict or None, not "
                                 f"{type(arm).__name__}")
        self.arm = arm
        p = _core.Params_c()
        _core.lib.qrtpy_params_default(ctypes.byref(p))
        p.arm = arm._to_c()
        for name, v in (("margin_m", margin_m), ("cspace_margin_deg", cspace_margin_deg),
                        ("grid_deg", grid_deg)):
            if v is not None:
                if isinstance(v, bool) or not isinstance(v, (int, float, np.integer,
                                                            np.floating)):
                    raise InputTypeError(f"{name} must be a number, not {type(v).__name__}")
                setattr(p, name, float(v))
        p.use_astar, p.simplify = int(bool(use_astar)), int(bool(simplify))
        if sample_draws is not None:
            if isinstance(sample_draws, bool) or not isinstance(sample_draws,
                                                                (int, np.integer)):
                raise InputTypeError(f"sample_draws must be an int, not "
                                     f"{type(sample_draws).__name__}")
            if not 0 <= sample_draws <= 1000000:
                raise InvalidInput(f"sample_draws {sample_draws} is not in 0 .. 1000000")
            p.sample_draws = int(sample_draws)
        self.margin_m, self.cspace_margin_deg = p.margin_m, p.cspace_margin_deg
        self.grid_deg, self.whole_mask = p.grid_deg, bool(whole_mask)
        rc = ctypes.c_int()
        msg = ctypes.create_string_buffer(512)
        h = _core.lib.qrtpy_planner_new(ctypes.byref(p), ctypes.byref(rc), msg, 512)
        if not h:
            # the CLI's sentences (src/cli/main.c, prepare)
            extra = msg.value.decode() or {
                -1: "invalid arm, margins or grid_deg (alpha wraps only with a grid "
                    "that divides 360)",
                -3: "coarser grid_deg or narrower limits"}.get(rc.value, "")
            raise error_for(rc.value, f"Planner(arm={arm}, margin_m={p.margin_m}, "
                            f"cspace_margin_deg={p.cspace_margin_deg}, "
                            f"grid_deg={p.grid_deg})", extra)
        self._h = h
        self._lock = threading.Lock()
        self._wp = np.empty((_core.MAX_WAYPOINTS, 3))
        self._res = _core.Result_c()
        self._res_ref = ctypes.byref(self._res)
        self._wp_ptr = self._wp.ctypes.data

    def close(self) -> None:
        """Free the planner's state now (it is freed with the object anyway)."""
        h, self._h = self._h, None
        if h:
            _core.lib.qrtpy_planner_free(h)

    def __del__(self):
        self.close()

    def __enter__(self) -> "Planner":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def plan(self, points: Any, start: Target, goal: Target) -> PlanResult:
        """Plan from start to goal around points, as `qrtplan plan` does.

        points: (N, 3) metres in the base frame (see as_points for dtypes);
        they replace the last call's. start, goal: joints in degrees (a
        sequence of 3, or Joints), a Point, or a scene target dict
        ({"joints_deg": ...} or {"xyz_m": ..., "ik": ..., "aim": ...}).
        Raises InvalidInput / LimitsError with the core's text for bad
        input; a plan that finds no path is a result, not an error. Warns
        CapacityWarning when points had to be merged or were dropped.
        """
        if not self._h:
            raise QrtError("Planner is closed")
        pts = as_points(points, check_finite=False)
        s, g = _target(start, "start"), _target(goal, "goal")
        r, wp = self._res, self._wp
        with self._lock:
            rc = _core.lib.qrtpy_plan(self._h, pts.ctypes.data, pts.shape[0],
                                      ctypes.byref(s), ctypes.byref(g),
                                      self.whole_mask, self._res_ref, self._wp_ptr)
            if rc != 0:
                if rc == -1:
                    _check_finite(pts)  # the points' row, when it was them
                raise error_for(rc, "plan", f"start {_show(s)}, goal {_show(g)}")
            return self._result(r, wp)

    @staticmethod
    def _result(r, wp) -> PlanResult:
        status = _STATUS.get(r.status) or _core.lib.qrt_plan_status_name(r.status).decode()
        ok = status == "ok"
        stats = {"points": r.points, "points_ignored": r.points_ignored,
                 "points_dropped": r.points_dropped, "voxel_m": r.voxel_m,
                 "cells_blocked": r.cells_blocked, "nodes_expanded": r.nodes_expanded,
                 "sampled_nodes": r.sampled_nodes}
        if ok:
            stats["lattice_cost_deg"] = r.lattice_cost_deg
        stats.update(lattice_path_nodes=r.lattice_path_nodes, start_node=r.start_node,
                     goal_node=r.goal_node, c_seconds=r.c_seconds)
        if r.points_dropped > 0:
            warnings.warn(f"{r.points_dropped} obstacle points dropped (the table "
                          f"holds {_core.MAX_POINTS}, merged at {r.voxel_m} m)",
                          CapacityWarning, stacklevel=3)
        elif r.voxel_m > 0:
            warnings.warn(f"more points than the table holds exactly "
                          f"({_core.MAX_POINTS}): merged into {r.voxel_m} m voxels",
                          CapacityWarning, stacklevel=3)
        res = PlanResult(status=status, detail=r.detail.decode(),
                         waypoints_deg=wp[:r.n_waypoints].copy() if ok
                         else np.empty((0, 3)),
                         cost_deg=r.cost_deg if ok else None, stats=stats,
                         clearance_m=r.clearance_m if r.has_clearance else None)
        if status not in ("unreachable", "capacity"):
            res.start_deg = np.array(r.start_deg[:])
            res.start_ik = _ik(r.start_facing, r.start_elbow)
            if status != "start_blocked":
                res.goal_deg = np.array(r.goal_deg[:])
                res.goal_ik = _ik(r.goal_facing, r.goal_elbow)
        if r.end_measured:
            res.end_clearance_m = r.end_clearance_m
        return res

    def clearance(self, joints_deg: Sequence[float], points: Any) -> float:
        """The arm's clearance at joints from points, with this planner's
        arm and margin (qrt_planner_clearance; <= 0: collides)."""
        if not self._h:
            raise QrtError("Planner is closed")
        q = np.ascontiguousarray(_three(joints_deg, "joints_deg"), dtype=np.float64)
        pts = as_points(points)
        return float(_core.lib.qrtpy_clearance(self._h, _dp(q), _dp(pts), pts.shape[0]))


_STATUS = {k: _core.lib.qrt_plan_status_name(k).decode() for k in range(6)}


def _ik(facing: int, elbow: int) -> Optional[dict]:
    if facing == 0 and elbow == 0:
        return None
    return {"facing": FACING[facing], "elbow": ELBOW[elbow]}


def _show(t) -> str:
    kind = {0: "joints_deg", 1: "xyz_m", 2: "tool tip xyz_m"}.get(t.kind, "?")
    return f"{kind} {list(t.value)}"


def plan(points: Any, start: Target, goal: Target, **params: Any) -> PlanResult:
    """One plan with a planner made for it: Planner(**params).plan(...)."""
    with Planner(**params) as p:
        return p.plan(points, start, goal)


_SCENE_KEYS = {"version", "name", "arm", "margin_m", "cspace_margin_deg", "grid_deg",
               "points", "points_file", "start", "goal"}


def plan_scene(scene: Mapping[str, Any], **options: Any) -> PlanResult:
    """Plan a scene dict (docs/spec.md section Scene) with inline points,
    as `qrtplan plan scene.json` does; options: use_astar, simplify,
    sample_draws, whole_mask. points_file is not read here: load the points and use
    Planner.plan."""
    unknown = set(scene) - _SCENE_KEYS
    if unknown:
        raise InvalidInput(f"scene: unknown key(s) {sorted(unknown)}")
    if "points_file" in scene:
        raise InvalidInput("scene: points_file is not read by plan_scene; load the "
                           "points and call Planner.plan")
    arm = Arm.from_scene(scene)
    with Planner(arm, margin_m=scene.get("margin_m"),
                 cspace_margin_deg=scene.get("cspace_margin_deg"),
                 grid_deg=scene.get("grid_deg"), **options) as p:
        return p.plan(scene.get("points", []), scene["start"], scene["goal"])
