"""The arm's kinematics through the C core (include/qrtplan/arm.h).

    >>> from qrtplan.kinematics import Arm, forward_points, capsules
    >>> arm = Arm.default()
    >>> forward_points(arm, [0, 0, 0])[-1]      # the tool tip, metres
    array([0.96, 0.  , 0.  ])

Nothing here computes kinematics in Python: every answer is the core's
(qrt_arm_fk, qrt_arm_tool_tip, qrt_arm_collision_arm, qrt_arm_ik_branches).
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from . import _core
from .errors import InvalidInput, error_for

__all__ = ["Arm", "forward_points", "capsules", "ik", "check_joints"]

FACING = {0: "any", 1: "front", 2: "back", 3: "both"}
ELBOW = {0: "any", 1: "up", 2: "down", 3: "both"}


@dataclass
class Arm:
    """The 3-DoF arm (docs/spec.md section Arm): link lengths and capsule
    radii in metres, joint limits ``[[lo, hi]] * 3`` in degrees (alpha,
    sigma, eta; alpha wraps when its limits are [-180, 180]), and an
    optional tool (length 0: none)."""

    links_m: tuple[float, float, float]
    link_radius_m: tuple[float, float, float]
    limits_deg: tuple[tuple[float, float], ...]
    tool_length_m: float = 0.0
    tool_radius_m: float = 0.0

    @classmethod
    def default(cls) -> "Arm":
        """The core's default arm (qrt_arm_default: Table 1, radii 0.02 m)."""
        a = _core.Arm_c()
        _core.lib.qrtpy_arm_default(ctypes.byref(a))
        return cls._from_c(a)

    @classmethod
    def from_scene(cls, scene: Mapping[str, Any]) -> "Arm":
        """The arm of a scene dict (docs/spec.md section Scene): its "arm"
        object, each key optional with the default arm's value, as the CLI
        reads it. A dict that is itself an arm object (has "links_m",
        "link_radius_m", "limits_deg" or "tool" but no "arm") is read the
        same way."""
        if "arm" in scene:
            spec = scene["arm"]
        elif any(k in scene for k in ("links_m", "link_radius_m", "limits_deg", "tool")):
            spec = scene
        else:
            spec = {}
        if not isinstance(spec, Mapping):
            raise InvalidInput("arm must be an object")
        unknown = set(spec) - {"links_m", "link_radius_m", "limits_deg", "tool"}
        if unknown:
            raise InvalidInput(f"arm: unknown key(s) {sorted(unknown)}")
        arm = cls.default()
        if "links_m" in spec:
            arm.links_m = tuple(_floats(spec["links_m"], 3, "arm.links_m"))
        if "link_radius_m" in spec:
            arm.link_radius_m = tuple(_floats(spec["link_radius_m"], 3,
                                              "arm.link_radius_m"))
        if "limits_deg" in spec:
            lim = spec["limits_deg"]
            if len(lim) != 3:
                raise InvalidInput("arm.limits_deg must be 3 [lo, hi] pairs")
            arm.limits_deg = tuple(tuple(_floats(p, 2, f"arm.limits_deg[{j}]"))
                                   for j, p in enumerate(lim))
        if "tool" in spec:
            tool = spec["tool"]
            if not isinstance(tool, Mapping) or set(tool) != {"length_m", "radius_m"}:
                raise InvalidInput("arm.tool must be an object with length_m and radius_m")
            arm.tool_length_m = float(tool["length_m"])
            arm.tool_radius_m = float(tool["radius_m"])
        arm.validate()
        return arm

    def to_scene(self) -> dict:
        """The scene file's "arm" object for this arm."""
        d = {"links_m": list(self.links_m), "link_radius_m": list(self.link_radius_m),
             "limits_deg": [list(p) for p in self.limits_deg]}
        if self.tool_length_m or self.tool_radius_m:
            d["tool"] = {"length_m": self.tool_length_m, "radius_m": self.tool_radius_m}
        return d

    def validate(self) -> None:
        """Raise InvalidInput unless the core accepts the arm (qrt_arm_validate)."""
        rc = _core.lib.qrtpy_arm_validate(ctypes.byref(self._to_c()))
        if rc != 0:
            raise error_for(rc, f"arm {self}")

    @classmethod
    def _from_c(cls, a: "_core.Arm_c") -> "Arm":
        return cls(links_m=tuple(a.link_m), link_radius_m=tuple(a.link_radius_m),
                   limits_deg=tuple((a.limit_deg[2 * j], a.limit_deg[2 * j + 1])
                                    for j in range(3)),
                   tool_length_m=a.tool_m, tool_radius_m=a.tool_radius_m)

    def _to_c(self) -> "_core.Arm_c":
        a = _core.Arm_c()
        try:
            a.link_m[:] = [float(v) for v in self.links_m]
            a.link_radius_m[:] = [float(v) for v in self.link_radius_m]
            a.limit_deg[:] = [float(v) for p in self.limits_deg for v in p]
            a.tool_m = float(self.tool_length_m)
            a.tool_radius_m = float(self.tool_radius_m)
        except (TypeError, ValueError) as e:
            raise InvalidInput(f"arm {self}: {e}") from None
        return a


def _floats(v: Any, n: int, what: str) -> list[float]:
    try:
        out = [float(x) for x in v]
    except (TypeError, ValueError):
        raise InvalidInput(f"{what} must be {n} numbers") from None
    if len(out) != n:
        raise InvalidInput(f"{what} must be {n} numbers, not {len(out)}")
    return out


def _joints(q: Any, what: str = "joints_deg") -> np.ndarray:
    a = np.asarray(q, dtype=float) if not isinstance(q, np.ndarray) else q
    if a.shape != (3,) or not np.issubdtype(a.dtype, np.number) or a.dtype.kind == "c":
        raise InvalidInput(f"{what} must be 3 real numbers (alpha, sigma, eta "
                           f"degrees), got shape {np.shape(q)}")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise InvalidInput(f"{what} must be finite, got {a.tolist()}")
    return a


def _dp(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def forward_points(arm: Arm, joints_deg: Sequence[float]) -> np.ndarray:
    """The arm's points for joints in degrees, shape (5, 3), metres: the
    base of link 1 (P0), the shoulder P1, the elbow P2, the end effector Pe
    and the tool tip (Pe again without a tool). Joints outside the limits
    are answered too (check_joints tells)."""
    q = _joints(joints_deg)
    out = np.empty((5, 3))
    rc = _core.lib.qrtpy_forward_points(ctypes.byref(arm._to_c()), _dp(q), _dp(out))
    if rc != 0:
        raise error_for(rc, f"arm {arm}")
    return out


def capsules(arm: Arm, joints_deg: Sequence[float]
             ) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """The three capsules (p0, p1, radius) the planner checks at these
    joints (qrt_arm_collision_arm): links 1 and 2 as they are, link 3 from
    the elbow to the tool tip with the larger of link 3's and the tool's
    radius. A point collides when its distance to a capsule's segment is at
    most radius + the planner's margin_m (docs/spec.md section Collision)."""
    q = _joints(joints_deg)
    p = np.empty((4, 3))
    r = np.empty(3)
    rc = _core.lib.qrtpy_capsules(ctypes.byref(arm._to_c()), _dp(q), _dp(p), _dp(r))
    if rc != 0:
        raise error_for(rc, f"arm {arm}")
    return [(p[i].copy(), p[i + 1].copy(), float(r[i])) for i in range(3)]


def ik(arm: Arm, xyz_m: Sequence[float], alpha_hint_deg: float = 0.0
       ) -> list[tuple[np.ndarray, str, str]]:
    """Every IK solution within the limits for end-effector point xyz_m
    (qrt_arm_ik_branches): (joints_deg, facing, elbow), at most 4."""
    x = _joints(xyz_m, "xyz_m")
    sol = np.empty((4, 3))
    br = (ctypes.c_long * 8)()
    n = ctypes.c_int()
    rc = _core.lib.qrtpy_ik(ctypes.byref(arm._to_c()), _dp(x), float(alpha_hint_deg),
                            _dp(sol), br, ctypes.byref(n))
    if rc != 0:
        raise error_for(rc, f"arm {arm}")
    return [(sol[i].copy(), FACING[br[2 * i]], ELBOW[br[2 * i + 1]])
            for i in range(n.value)]


def check_joints(arm: Arm, joints_deg: Sequence[float]) -> None:
    """Raise LimitsError (or InvalidInput) unless the joints are finite and
    inside the arm's limits (qrt_arm_check_joints)."""
    q = _joints(joints_deg)
    rc = _core.lib.qrtpy_check_joints(ctypes.byref(arm._to_c()), _dp(q))
    if rc != 0:
        raise error_for(rc, f"joints {q.tolist()}")
