"""qrtpland's LCM messages as Foxglove messages (docs/view.md).

`Bridge.feed(channel, data, log_time_ns)` takes one LCM message as it was on
the bus (a bare message or an authenticated_message_t carrying one) and logs
what it shows on the Foxglove channels of a `foxglove.Context`; the sinks of
that context (an MCAP file, a WebSocket server) get them. The message's type
is found from its fingerprint, not from the channel's name, so renamed
channels (`QRT_SCAN_<name>`) work.
"""

from __future__ import annotations

import importlib
import json
import math
import struct
import numpy as np

import foxglove
from foxglove.channels import (
    JointStatesChannel,
    LogChannel,
    PointCloudChannel,
    SceneUpdateChannel,
)
from foxglove.messages import (
    Color,
    CylinderPrimitive,
    JointState,
    JointStates,
    LinePrimitive,
    LinePrimitiveLineType,
    Log,
    LogLevel,
    PackedElementField,
    PackedElementFieldNumericType,
    Point3,
    PointCloud,
    Pose,
    Quaternion,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    Timestamp,
    Vector3,
)

from qrtplan.kinematics import Arm, capsules, forward_points

FRAME = "base"  # the arm's base frame, metres
JOINTS = ("alpha", "sigma", "eta")

# Foxglove topics (docs/view.md has the table)
T_ARM = "/arm"
T_PLAN = "/plan"
T_PLAN_STATUS = "/plan/status"
T_PLAN_LOG = "/plan/log"
T_OBSTACLES = "/obstacles/"  # + sensor_id
T_JOINTS = "/joint_states"
T_JOINT_STATE = "/qrtplan/joint_state"
T_STATUS = "/qrtplan/status"
T_DRIVES = "/drives"
T_VIEW = "/qrtplan/view"
T_REQUEST = "/qrtplan/request"

ARM_COLOR = (0.20, 0.45, 0.85, 1.0)
GHOST_COLOR = (0.55, 0.55, 0.60, 0.25)
PATH_COLOR = (1.0, 0.55, 0.0, 1.0)
PLAN_LEVEL = {"ok": LogLevel.Info, "no_obstacle_data": LogLevel.Warning,
              "stale_obstacle_data": LogLevel.Warning}


def _lcm_types():
    """The lcm-gen classes: qrtplan.lcmtypes in the installed package, else
    the build tree's top-level `qrtplan` (build/lcmtypes/python)."""
    names = ("authenticated_message_t", "daemon_status_t", "joint_state_t",
             "plan_t", "plan_request_t", "range_scan_t", "point_cloud_t")
    out = {}
    for n in names:
        for base in ("qrtplan.lcmtypes", "qrtplan"):
            try:
                mod = importlib.import_module(f"{base}.{n}")
            except ImportError:
                continue
            out[n] = getattr(mod, n)
            break
    return out


TYPES = _lcm_types()
BY_FINGERPRINT = {t._get_packed_fingerprint(): n for n, t in TYPES.items()}


def lcm_type_name(data: bytes) -> str | None:
    """The qrtplan type of an encoded LCM message, None if not one of ours."""
    return BY_FINGERPRINT.get(bytes(data[:8]))


def carried_type(data: bytes) -> str | None:
    """The type of a message, or of the one an authenticated_message_t
    carries, read from the header alone (no decoding of a large scan)."""
    name = lcm_type_name(data)
    if name != "authenticated_message_t":
        return name
    try:
        o = 8
        for _ in range(2):  # channel, sender_id: int32 length incl. NUL
            o += 4 + int.from_bytes(data[o:o + 4], "big")
        o += 8 + 4  # counter, payload_size
        return lcm_type_name(data[o:o + 8])
    except (IndexError, ValueError):
        return None


def _ts(utime_us: int) -> Timestamp:
    return Timestamp(sec=int(utime_us // 1_000_000),
                     nsec=int(utime_us % 1_000_000) * 1000)


def _color(c) -> Color:
    return Color(r=c[0], g=c[1], b=c[2], a=c[3])


def _quat_from_z(d):
    """The rotation (x, y, z, w) taking the z axis to the direction d."""
    d = d / np.linalg.norm(d)
    c = float(d[2])
    if c < -1 + 1e-9:
        return (1.0, 0.0, 0.0, 0.0)
    axis = np.array([-d[1], d[0], 0.0])  # z x d
    w = 1.0 + c
    q = np.array([axis[0], axis[1], axis[2], w])
    q /= np.linalg.norm(q)
    return tuple(float(v) for v in q)


def capsule_primitives(caps, color):
    """Cylinders and end spheres drawing capsules [(p0, p1, radius)]."""
    cyl, sph = [], []
    for p0, p1, r in caps:
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        d = p1 - p0
        n = float(np.linalg.norm(d))
        if n > 1e-9:
            x, y, z, w = _quat_from_z(d)
            mid = (p0 + p1) / 2
            cyl.append(CylinderPrimitive(
                pose=Pose(position=Vector3(x=mid[0], y=mid[1], z=mid[2]),
                          orientation=Quaternion(x=x, y=y, z=z, w=w)),
                size=Vector3(x=2 * r, y=2 * r, z=n), bottom_scale=1.0,
                top_scale=1.0, color=_color(color)))
        for p in (p0, p1):
            sph.append(SpherePrimitive(
                pose=Pose(position=Vector3(x=p[0], y=p[1], z=p[2]),
                          orientation=Quaternion(x=0, y=0, z=0, w=1)),
                size=Vector3(x=2 * r, y=2 * r, z=2 * r), color=_color(color)))
    return cyl, sph


def wrap180(a):
    return (np.asarray(a, float) + 180.0) % 360.0 - 180.0


def path_samples(waypoints_deg, step_deg=2.0):
    """Joint configurations along a path, alpha taking the short way across
    +-180 between waypoints as the drives do."""
    w = np.asarray(waypoints_deg, float).reshape(-1, 3)
    if len(w) < 2:
        return w
    out = [w[0]]
    for a, b in zip(w[:-1], w[1:]):
        d = b - a
        d[0] = wrap180(d[0])
        k = max(1, int(math.ceil(np.abs(d).max() / step_deg)))
        for i in range(1, k + 1):
            out.append(a + d * (i / k))
    return np.array(out)


class _Scan:
    """A range_scan_t read straight into numpy arrays: lcm-gen's decode
    makes Python floats of every return (12 ms for 10^5 here)."""
    __slots__ = ("utime", "sensor_id", "position_m", "orientation",
                 "max_range_m", "n", "azimuth_rad", "elevation_rad",
                 "range_m")


def decode_scan(data: bytes) -> _Scan:
    """An encoded range_scan_t (lcm/range_scan_t.lcm, big-endian) as _Scan;
    ValueError if it is truncated or not one."""
    if lcm_type_name(data) != "range_scan_t":
        raise ValueError("not a range_scan_t")
    m = _Scan()
    o = 8
    (m.utime, k) = struct.unpack_from(">qi", data, o)
    o += 12
    if k < 1 or o + k > len(data):
        raise ValueError("bad sensor_id")
    m.sensor_id = bytes(data[o:o + k - 1]).decode("utf-8", "replace")
    o += k
    v = struct.unpack_from(">7dfi", data, o)
    o += 7 * 8 + 4 + 4
    m.position_m, m.orientation, m.max_range_m, m.n = v[0:3], v[3:7], v[7], v[8]
    if m.n < 0 or o + 12 * m.n > len(data):
        raise ValueError("truncated range_scan_t")
    a = np.frombuffer(data, ">f4", 3 * m.n, o).astype(np.float32)
    m.azimuth_rad, m.elevation_rad, m.range_m = (a[:m.n], a[m.n:2 * m.n],
                                                 a[2 * m.n:])
    return m


class _Cloud:
    __slots__ = ("utime", "sensor_id", "position_m", "orientation", "n",
                 "x_m", "y_m", "z_m")


def decode_cloud(data: bytes) -> _Cloud:
    """An encoded point_cloud_t (lcm/point_cloud_t.lcm) as _Cloud, its
    coordinates numpy arrays; ValueError if truncated or not one."""
    if lcm_type_name(data) != "point_cloud_t":
        raise ValueError("not a point_cloud_t")
    m = _Cloud()
    m.utime, k = struct.unpack_from(">qi", data, 8)
    o = 20
    if k < 1 or o + k > len(data):
        raise ValueError("bad sensor_id")
    m.sensor_id = bytes(data[o:o + k - 1]).decode("utf-8", "replace")
    o += k
    v = struct.unpack_from(">7di", data, o)
    o += 7 * 8 + 4
    m.position_m, m.orientation, m.n = v[0:3], v[3:7], v[7]
    if m.n < 0 or o + 12 * m.n > len(data):
        raise ValueError("truncated point_cloud_t")
    a = np.frombuffer(data, ">f4", 3 * m.n, o).astype(np.float32)
    m.x_m, m.y_m, m.z_m = a[:m.n], a[m.n:2 * m.n], a[2 * m.n:]
    return m


FAST = {"range_scan_t": decode_scan, "point_cloud_t": decode_cloud}
CLOUDS = tuple(FAST)  # the messages only the newest of which is shown


def scan_points(scan) -> np.ndarray:
    """A range_scan_t's returns in the base frame (N x 3, metres); returns
    at or beyond max_range_m, non-positive or not finite are left out."""
    n = scan.n  # float32 as sent: for the picture, not for the planner
    az = np.asarray(scan.azimuth_rad, np.float32)[:n]
    el = np.asarray(scan.elevation_rad, np.float32)[:n]
    r = np.asarray(scan.range_m, np.float32)[:n]
    ok = np.isfinite(r) & np.isfinite(az) & np.isfinite(el) & (r > 0) & (
        r < scan.max_range_m)
    az, el, r = az[ok], el[ok], r[ok]
    ce = np.cos(el)
    p = np.stack([r * ce * np.cos(az), r * ce * np.sin(az), r * np.sin(el)],
                 axis=1)
    return to_base(p, scan.position_m, scan.orientation)


def cloud_points(cloud) -> np.ndarray:
    """A point_cloud_t's points in the base frame (N x 3, metres); points
    with a coordinate not finite are left out."""
    n = cloud.n
    p = np.stack([np.asarray(v, np.float32)[:n]
                  for v in (cloud.x_m, cloud.y_m, cloud.z_m)], axis=1)
    p = p[np.isfinite(p).all(axis=1)]
    return to_base(p, cloud.position_m, cloud.orientation)


def to_base(p, position, orientation) -> np.ndarray:
    """Sensor-frame points (N x 3) in the base frame: turned by the unit
    quaternion orientation (w, x, y, z), then moved to position."""
    w, x, y, z = orientation
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return p @ R.T.astype(np.float32) + np.asarray(position, np.float32)


def plan_summary(m) -> str:
    """What /plan/log says of a plan_t: its status and detail, then an ok
    plan's certified clearance and the mask's blocked-cell count (-1: the
    whole mask was not built, as with qrtpland's default --mask as-read)."""
    extra = []
    if m.status == "ok":
        extra.append("no obstacle point" if m.clearance_m >= 1e9 else
                     f"clearance {m.clearance_m * 1000:.1f} mm")
    extra.append("blocked cells not counted (whole mask not built)"
                 if m.cells_blocked < 0 else
                 f"{m.cells_blocked} blocked cells")
    return (f"request {m.request_id}: {m.status}: {m.detail} "
            f"[{'; '.join(extra)}]")


def _json_channel(topic, name, ctx):
    """A JSON channel whose schema is named qrtplan.<name> (the fields are
    the LCM message's, docs/daemon.md; plus "channel", the LCM channel)."""
    schema = foxglove.Schema(
        name="qrtplan." + name, encoding="jsonschema",
        data=json.dumps({"type": "object", "title": "qrtplan." + name})
        .encode())
    return foxglove.Channel(topic, schema=schema, message_encoding="json",
                            context=ctx)


def _plain(msg) -> dict:
    """An LCM message's fields as a JSON-able dict."""
    out = {}
    for k in msg.__slots__:
        v = getattr(msg, k)
        if isinstance(v, (bytes, bytearray)):
            continue
        if isinstance(v, (list, tuple)):
            v = [list(x) if isinstance(x, (list, tuple)) else x for x in v]
        out[k] = v
    return out


class Bridge:
    """Logs qrtpland's messages onto Foxglove channels of `context`."""

    def __init__(self, context: foxglove.Context | None = None,
                 arm: Arm | None = None, ghosts: int = 12):
        self.ctx = context or foxglove.Context()
        self.arm = arm or Arm.default()
        self.ghosts = ghosts
        c = self.ctx
        self.ch_arm = SceneUpdateChannel(T_ARM, context=c)
        self.ch_plan = SceneUpdateChannel(T_PLAN, context=c)
        self.ch_plan_log = LogChannel(T_PLAN_LOG, context=c)
        self.ch_joints = JointStatesChannel(T_JOINTS, context=c)
        self.ch_plan_status = _json_channel(T_PLAN_STATUS, "plan_t", c)
        self.ch_joint_state = _json_channel(T_JOINT_STATE, "joint_state_t",
                                            c)
        self.ch_status = _json_channel(T_STATUS, "daemon_status_t", c)
        self.ch_drives = _json_channel(T_DRIVES, "drives", c)
        self.ch_view = _json_channel(T_VIEW, "view_counts", c)
        self.ch_request = _json_channel(T_REQUEST, "plan_request_t", c)
        self.ch_clouds: dict[str, PointCloudChannel] = {}
        self.counts: dict[str, int] = {}
        self.last_drive = None
        self.last_can = None
        self.last_plan_key = None

    # -- intake -------------------------------------------------------------
    def feed(self, channel: str, data: bytes, log_time_ns: int) -> str | None:
        """Shows one LCM message; returns its type name (None: not ours)."""
        name = lcm_type_name(data)
        if name == "authenticated_message_t":
            # a trusted sender's input: shown as sent, its MAC not checked
            # here (the bridge holds no keys; qrtpland checks it)
            try:
                env = TYPES[name].decode(data)
            except Exception:
                self._count("undecodable")
                return None
            data = bytes(env.payload)
            name = lcm_type_name(data)
        if name is None:
            self._count("not_qrtplan")
            return None
        try:
            msg = FAST[name](data) if name in FAST else \
                TYPES[name].decode(data)
        except Exception:
            self._count("undecodable")
            return None
        getattr(self, "_" + name)(channel, msg, log_time_ns)
        self._count(name)
        return name

    def _count(self, k):
        self.counts[k] = self.counts.get(k, 0) + 1

    # -- the messages -------------------------------------------------------
    def _arm_entity(self, eid, joints, color, utime):
        cyl, sph = capsule_primitives(capsules(self.arm, list(joints)), color)
        return SceneEntity(timestamp=_ts(utime), frame_id=FRAME, id=eid,
                           cylinders=cyl, spheres=sph)

    def _joint_state_t(self, channel, m, t):
        q = [float(v) for v in m.joints_deg]
        self.ch_arm.log(SceneUpdate(entities=[
            self._arm_entity("arm", q, ARM_COLOR, m.utime)]), log_time=t)
        self.ch_joints.log(JointStates(timestamp=_ts(m.utime), joints=[
            JointState(name=n, position=math.radians(v))
            for n, v in zip(JOINTS, q)]), log_time=t)
        self.ch_joint_state.log({"utime": m.utime, "channel": channel,
                                 "joints_deg": q, "moving": bool(m.moving),
                                 "drive_state": m.drive_state}, log_time=t)
        if m.drive_state != self.last_drive:
            self.last_drive = m.drive_state
            self._drives(m.utime, t)

    def _drives(self, utime, t):
        self.ch_drives.log({"utime": utime, "drive_state": self.last_drive,
                            "can_state": self.last_can}, log_time=t)

    def _plan_t(self, channel, m, t):
        d = _plain(m)
        d["channel"] = channel
        self.ch_plan_status.log(d, log_time=t)
        ents, drawn = [], set()
        if m.status == "ok" and m.n_waypoints > 0:
            drawn = {"tool_path", "ghosts"}
            w = np.array(m.waypoints_deg, float).reshape(-1, 3)
            tip = np.array([forward_points(self.arm, list(q))[-1]
                            for q in path_samples(w)])
            ents.append(SceneEntity(
                timestamp=_ts(m.utime), frame_id=FRAME, id="tool_path",
                lines=[LinePrimitive(
                    type=LinePrimitiveLineType.LineStrip, thickness=0.01,
                    points=[Point3(x=p[0], y=p[1], z=p[2]) for p in tip],
                    color=_color(PATH_COLOR))]))
            pick = w if len(w) <= self.ghosts else w[np.linspace(
                0, len(w) - 1, self.ghosts).round().astype(int)]
            cyl, sph = [], []
            for q in pick:
                c, s = capsule_primitives(capsules(self.arm, list(q)),
                                          GHOST_COLOR)
                cyl += c
                sph += s
            ents.append(SceneEntity(timestamp=_ts(m.utime), frame_id=FRAME,
                                    id="ghosts", cylinders=cyl, spheres=sph))
        # an empty path where there is none: the old one is withdrawn
        for eid in ("tool_path", "ghosts"):
            if eid not in drawn:
                ents.append(SceneEntity(timestamp=_ts(m.utime),
                                        frame_id=FRAME, id=eid))
        self.ch_plan.log(SceneUpdate(entities=ents), log_time=t)
        key = (m.request_id, m.status)
        if key != self.last_plan_key:  # a log line when the status changes
            self.last_plan_key = key
            self.ch_plan_log.log(Log(
                timestamp=_ts(m.utime), level=PLAN_LEVEL.get(
                    m.status, LogLevel.Warning),
                name="qrtpland", message=plan_summary(m)), log_time=t)

    def _range_scan_t(self, channel, m, t):
        self._cloud(m, scan_points(m), t)

    def _point_cloud_t(self, channel, m, t):
        self._cloud(m, cloud_points(m), t)

    def _cloud(self, m, p, t):
        p = p.astype("<f4")
        sid = m.sensor_id or "scan"
        ch = self.ch_clouds.get(sid)
        if ch is None:
            ch = self.ch_clouds[sid] = PointCloudChannel(
                T_OBSTACLES + sid, context=self.ctx)
        ch.log(PointCloud(
            timestamp=_ts(m.utime), frame_id=FRAME,
            pose=Pose(position=Vector3(x=0, y=0, z=0),
                      orientation=Quaternion(x=0, y=0, z=0, w=1)),
            point_stride=12, fields=[
                PackedElementField(name=n, offset=4 * i,
                                   type=PackedElementFieldNumericType.Float32)
                for i, n in enumerate("xyz")],
            data=p.tobytes()), log_time=t)

    def _plan_request_t(self, channel, m, t):
        d = _plain(m)
        d["channel"] = channel
        self.ch_request.log(d, log_time=t)

    def _daemon_status_t(self, channel, m, t):
        d = _plain(m)
        d["channel"] = channel
        self.ch_status.log(d, log_time=t)
        if m.can_state != self.last_can:
            self.last_can = m.can_state
            self._drives(m.utime, t)

    def _authenticated_message_t(self, channel, m, t):  # nested envelope
        self._count("nested_envelope")

    def log_counts(self, log_time_ns, extra=None):
        d = {"received": dict(self.counts)}
        if extra:
            d.update(extra)
        self.ch_view.log(d, log_time=log_time_ns)

