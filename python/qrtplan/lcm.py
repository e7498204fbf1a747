"""A client of the daemon qrtpland over LCM (docs/daemon.md, docs/security.md).

    from qrtplan.lcm import Client
    with Client(keys=["keys/operator.key", "keys/lidar0.key"]) as c:
        c.publish_points(points, sensor_id="lidar0")        # (N, 3) metres
        plan = c.plan(goal=[30, 40, -20], timeout=5.0)      # plan_t
        q = c.joint_state(timeout=1.0)                      # joint_state_t

publish_points sends a point_cloud_t (points in the sensor's frame, with
its pose; the default pose makes them base-frame points), publish_scan a
range_scan_t. Messages are signed (qrtplan.auth) with the key whose role
the daemon wants for each channel: the operator's for requests, the key
named by the sensor_id for clouds and scans, the joints key for joint
states; without keys they go unsigned (a daemon without --keys). Needs the
PyPI packages lcm and pynacl (`pip install qrtplan[lcm]`).
"""
from __future__ import annotations

import math
import threading
import time
from typing import Any, Callable, Iterable, Optional, Sequence, Union

import lcm as _lcm
import numpy as np

from .lcmtypes import (daemon_status_t, joint_state_t, plan_request_t, plan_t,
                       point_cloud_t, range_scan_t)

__all__ = ["Client", "DEFAULT_URL", "points_to_cloud", "points_to_scan"]

DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"
FACING = {"any": plan_request_t.IK_ANY, "front": plan_request_t.IK_FACING_FRONT,
          "back": plan_request_t.IK_FACING_BACK}
ELBOW = {"any": plan_request_t.IK_ANY, "up": plan_request_t.IK_ELBOW_UP,
         "down": plan_request_t.IK_ELBOW_DOWN}


def points_to_cloud(points: Any, sensor_id: str, utime: Optional[int] = None,
                    position_m: Sequence[float] = (0.0, 0.0, 0.0),
                    orientation: Sequence[float] = (1.0, 0.0, 0.0, 0.0)
                    ) -> point_cloud_t:
    """Points (N, 3 metres) in the sensor's frame as a point_cloud_t from a
    sensor at position_m (base frame) turned by the unit quaternion
    orientation (w, x, y, z: sensor -> base); the default pose makes them
    base-frame points. float32 on the wire (a point moves by up to about
    6e-8 of its distance from the sensor). The daemon checks the pose."""
    from .planner import as_points
    p = as_points(points)
    c = point_cloud_t()
    c.utime = time.time_ns() // 1000 if utime is None else int(utime)
    c.sensor_id = sensor_id
    c.position_m = [float(v) for v in position_m]
    c.orientation = [float(v) for v in orientation]
    if len(c.position_m) != 3 or len(c.orientation) != 4:
        raise ValueError("position_m: 3 numbers; orientation: 4 (w, x, y, z)")
    c.n = len(p)
    f = p.astype(np.float32)
    c.x_m, c.y_m, c.z_m = f[:, 0].tolist(), f[:, 1].tolist(), f[:, 2].tolist()
    return c


def points_to_scan(points: Any, sensor_id: str, utime: Optional[int] = None,
                   max_range_m: float = 100.0) -> range_scan_t:
    """Base-frame points (N, 3 metres) as a range_scan_t from a sensor at
    the base origin with the identity orientation: each point's azimuth,
    elevation and range (float32 on the wire: a point moves by up to about
    1e-7 of its range)."""
    from .planner import as_points
    p = as_points(points)
    r = range_scan_t()
    r.utime = time.time_ns() // 1000 if utime is None else int(utime)
    r.sensor_id = sensor_id
    r.position_m = [0.0, 0.0, 0.0]
    r.orientation = [1.0, 0.0, 0.0, 0.0]
    r.max_range_m = float(max_range_m)
    rho = np.hypot(p[:, 0], p[:, 1])
    r.n = len(p)
    r.azimuth_rad = np.arctan2(p[:, 1], p[:, 0]).astype(np.float32).tolist()
    r.elevation_rad = np.arctan2(p[:, 2], rho).astype(np.float32).tolist()
    r.range_m = np.sqrt(rho * rho + p[:, 2] * p[:, 2]).astype(np.float32).tolist()
    return r


class Client:
    """One LCM connection to the daemon. keys: key file paths (or
    qrtplan.auth.Signer objects) to sign with; None sends unsigned. The
    channels are the daemon's defaults. Not thread-safe: handle messages
    from one thread (every wait_* call does)."""

    def __init__(self, url: str = DEFAULT_URL,
                 keys: Optional[Iterable[Union[str, Any]]] = None, *,
                 request_channel: str = "QRT_PLAN_REQUEST", plan_channel: str = "QRT_PLAN",
                 scan_channel: str = "QRT_SCAN", cloud_channel: str = "QRT_CLOUD",
                 joint_channel: str = "QRT_JOINT_STATE", status_channel: str = "QRT_STATUS"):
        self.lc = _lcm.LCM(url)
        self.channels = dict(request=request_channel, plan=plan_channel, scan=scan_channel,
                             cloud=cloud_channel, joints=joint_channel,
                             status=status_channel)
        self._publisher: Any = self.lc
        if keys is not None:
            from .auth import SignedPublisher, Signer
            signers = [k if isinstance(k, Signer) else Signer(str(k)) for k in keys]
            self._publisher = SignedPublisher(self.lc, signers, request_channel,
                                              scan_channel, joint_channel,
                                              cloud_channel=cloud_channel)
        self._plans: list[plan_t] = []
        self._joints: Optional[joint_state_t] = None
        self._status: Optional[daemon_status_t] = None
        self._joint_callbacks: list[Callable[[joint_state_t], None]] = []
        self._last_id = 0
        self._id_lock = threading.Lock()
        self._subs = [
            self.lc.subscribe(plan_channel, self._on_plan),
            self.lc.subscribe(joint_channel, self._on_joints),
            self.lc.subscribe(status_channel, self._on_status)]

    # --- incoming -------------------------------------------------------
    def _on_plan(self, channel: str, data: bytes) -> None:
        self._plans.append(plan_t.decode(data))
        del self._plans[:-256]

    def _on_joints(self, channel: str, data: bytes) -> None:
        try:
            self._joints = joint_state_t.decode(data)
        except ValueError:  # a signed one: the daemon's own are not
            return
        for cb in self._joint_callbacks:
            cb(self._joints)

    def _on_status(self, channel: str, data: bytes) -> None:
        self._status = daemon_status_t.decode(data)

    def handle(self, timeout_s: float = 0.0) -> bool:
        """Handle at most one incoming message, waiting up to timeout_s."""
        return self.lc.handle_timeout(max(0, int(timeout_s * 1000))) > 0

    def _wait(self, done: Callable[[], Any], timeout_s: float, what: str) -> Any:
        end = time.monotonic() + timeout_s
        while True:
            got = done()
            if got is not None:
                return got
            left = end - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no {what} within {timeout_s:g} s")
            self.lc.handle_timeout(max(1, min(50, int(left * 1000))))

    # --- outgoing -------------------------------------------------------
    def publish(self, channel: str, msg: Any) -> None:
        """Publish an lcm message (or encoded bytes), signed when keys were given."""
        self._publisher.publish(channel, msg if isinstance(msg, (bytes, bytearray))
                                else msg.encode())

    def publish_scan(self, scan: range_scan_t) -> None:
        """Publish a range_scan_t on the scan channel (signed with the key
        named by its sensor_id)."""
        self.publish(self.channels["scan"], scan)

    def publish_cloud(self, cloud: point_cloud_t) -> None:
        """Publish a point_cloud_t on the cloud channel (signed with the key
        named by its sensor_id)."""
        self.publish(self.channels["cloud"], cloud)

    def publish_points(self, points: Any, sensor_id: str = "points",
                       utime: Optional[int] = None, *,
                       position_m: Sequence[float] = (0.0, 0.0, 0.0),
                       orientation: Sequence[float] = (1.0, 0.0, 0.0, 0.0)
                       ) -> point_cloud_t:
        """Publish points in the sensor's frame with its pose as a cloud
        from sensor_id (points_to_cloud); with the default pose, base-frame
        points. Returns the message sent."""
        cloud = points_to_cloud(points, sensor_id, utime, position_m, orientation)
        self.publish_cloud(cloud)
        return cloud

    def request_plan(self, goal: Sequence[float], *, xyz: bool = False,
                     start: Optional[Sequence[float]] = None, facing: str = "any",
                     elbow: str = "any", request_id: Optional[int] = None) -> int:
        """Ask for a plan to goal: joints in degrees, or (xyz=True) an
        end-effector point in metres with an IK branch (facing, elbow).
        start: joints in degrees, or None for the measured joint state.
        Returns the request id the plans will echo."""
        if facing not in FACING or elbow not in ELBOW:
            raise ValueError("facing: any, front or back; elbow: any, up or down")
        if not xyz and (facing != "any" or elbow != "any"):
            raise ValueError("facing and elbow apply to xyz goals only")
        vals = [float(v) for v in goal]
        if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
            raise ValueError(f"goal must be 3 finite numbers, got {goal!r}")
        r = plan_request_t()
        r.utime = time.time_ns() // 1000
        with self._id_lock:
            if request_id is None:
                request_id = max(self._last_id + 1, r.utime // 1000)
            self._last_id = request_id
        r.request_id = int(request_id)
        r.goal_kind = plan_request_t.GOAL_XYZ if xyz else plan_request_t.GOAL_JOINTS
        r.goal = vals
        r.has_start = start is not None
        r.start_deg = [float(v) for v in start] if start is not None else [0.0] * 3
        r.ik_facing, r.ik_elbow = FACING[facing], ELBOW[elbow]
        self.publish(self.channels["request"], r)
        return r.request_id

    def wait_plan(self, request_id: Optional[int] = None, timeout: float = 5.0) -> plan_t:
        """The next plan for request_id (None: any plan arriving from now),
        or TimeoutError."""
        seen = len(self._plans) if request_id is None else 0

        def find():
            for p in self._plans[seen:]:
                if request_id is None or p.request_id == request_id:
                    return p
            return None
        return self._wait(find, timeout, f"plan for request {request_id}")

    def plan(self, goal: Sequence[float], timeout: float = 5.0, **kw: Any) -> plan_t:
        """request_plan, then wait_plan for it."""
        return self.wait_plan(self.request_plan(goal, **kw), timeout)

    def joint_state(self, timeout: float = 1.0) -> joint_state_t:
        """The latest joint state, waiting for one if none has come yet."""
        return self._wait(lambda: self._joints, timeout, "joint state")

    def on_joint_state(self, callback: Callable[[joint_state_t], None]) -> None:
        """Call callback with every joint state handled from now on."""
        self._joint_callbacks.append(callback)

    def status(self, timeout: float = 2.0) -> daemon_status_t:
        """The next daemon_status_t."""
        self._status = None
        return self._wait(lambda: self._status, timeout, "daemon status")

    def close(self) -> None:
        for s in self._subs:
            self.lc.unsubscribe(s)
        self._subs = []

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
