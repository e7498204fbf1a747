"""qrtplan-view (docs/view.md): a daemon session recorded live to MCAP and,
from lcm-logger's log of the same session, with --from-log; both read back
with the `mcap` reader: the expected topics and schemas, as many messages as
were on the bus (every joint state, plan and status), each topic's log times
increasing, the joint states and plans equal to the bus's, the tool path
ending at the plan's goal; and make demo's session.mcap against the joints
the closed loop traced (skipped when make demo has not run)."""
import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import lcm

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))  # the package's source
from qrtplan.kinematics import Arm, forward_points  # noqa: E402
from qrtplan.view import bridge, recording  # noqa: E402

DAEMON = Path(os.environ.get("QRTPLAND_BIN", ROOT / "build" / "bin" /
                             "qrtpland"))
T = bridge.TYPES  # the lcm-gen classes the bridge decodes with
PORT = 7350 + os.getpid() % 40  # the daemon tests use 7700..8700
PY = sys.executable
ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(
    p for p in (str(ROOT / "python"), os.environ.get("PYTHONPATH")) if p))

TOPICS = {  # topic -> schema
    "/arm": "foxglove.SceneUpdate",
    "/plan": "foxglove.SceneUpdate",
    "/plan/log": "foxglove.Log",
    "/joint_states": "foxglove.JointStates",
    "/obstacles/s0": "foxglove.PointCloud",
    "/plan/status": "qrtplan.plan_t",
    "/qrtplan/joint_state": "qrtplan.joint_state_t",
    "/qrtplan/status": "qrtplan.daemon_status_t",
    "/qrtplan/request": "qrtplan.plan_request_t",
    "/drives": "qrtplan.drives",
    "/qrtplan/view": "qrtplan.view_counts",
}


def _stop(p):
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
        try:
            p.wait(20)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def now_us():
    return time.time_ns() // 1000


def scan_from_points(points, position=(0.0, 0.0, 0.0)):
    """A scan of sensor s0 at `position`, identity orientation, whose
    returns hit the given base-frame points."""
    p = np.asarray(points, float).reshape(-1, 3) - np.asarray(position)
    r = np.linalg.norm(p, axis=1)
    m = T["range_scan_t"]()
    m.utime, m.sensor_id, m.max_range_m = now_us(), "s0", 5.0
    m.position_m, m.orientation = list(position), [1.0, 0.0, 0.0, 0.0]
    m.n = len(p)
    m.azimuth_rad = np.arctan2(p[:, 1], p[:, 0]).tolist()
    m.elevation_rad = np.arcsin(p[:, 2] / r).tolist()
    m.range_m = r.tolist()
    return m


def request(goal, start):
    r = T["plan_request_t"]()
    r.utime, r.request_id, r.goal_kind, r.goal = now_us(), 1, 0, list(goal)
    r.has_start, r.start_deg = True, list(start)
    return r


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """A 4 s session: the bridge and lcm-logger listen from before the
    daemon starts until after it stopped; this test is the sensor (a scan
    of the Table 4 sphere every 0.1 s), the operator (one request) and the
    drives (joint states at 20 Hz, moving along alpha)."""
    tmp = tmp_path_factory.mktemp("view")
    url = f"udpm://239.255.76.67:{PORT}?ttl=0&recv_buf_size=4194304"
    view = subprocess.Popen(
        [PY, "-m", "qrtplan.view", "--lcm-url", url, "--mcap",
         str(tmp / "live.mcap")], env=ENV, stderr=subprocess.PIPE, text=True)
    logger = subprocess.Popen(["lcm-logger", f"--lcm-url={url}", "-q",
                               str(tmp / "session.lcmlog")])
    lc = lcm.LCM(url)
    bus = {"QRT_PLAN": [], "QRT_STATUS": [], "QRT_JOINT_STATE": []}
    for ch in bus:
        lc.subscribe(ch, lambda c, d: bus[c].append(d))
    time.sleep(2.0)  # both subscribed
    daemon = subprocess.Popen([str(DAEMON), "--lcm-url", url],
                              stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    with open(ROOT / "scenes" / "table4_one_sphere.json") as f:
        pts = np.asarray(json.load(f)["points"], float)
    t0 = time.time()
    k = 0
    asked = False
    while time.time() - t0 < 4.0:
        js = T["joint_state_t"]()
        js.utime = now_us()
        js.joints_deg = [-100.0 + 2.0 * k, 0.0, 0.0]
        js.moving = k > 10
        js.drive_state = "external" if k < 40 else "operation_enabled"
        lc.publish("QRT_JOINT_STATE", js.encode())
        if k % 2 == 0:
            lc.publish("QRT_SCAN", scan_from_points(pts).encode())
        if not asked and time.time() - t0 > 1.0:
            lc.publish("QRT_PLAN_REQUEST", request([100, 0, 0], [-100, 0, 0]).encode())
            asked = True
        k += 1
        end = t0 + 0.05 * k
        while time.time() < end:
            lc.handle_timeout(5)
    daemon.send_signal(signal.SIGTERM)
    daemon.wait(15)
    end = time.time() + 1.0
    while time.time() < end:
        lc.handle_timeout(20)
    _stop(view)
    _stop(logger)
    err = view.stderr.read()
    assert view.returncode == 0, err
    conv = subprocess.run(
        [PY, "-m", "qrtplan.view", "--from-log", str(tmp / "session.lcmlog"),
         "--mcap", str(tmp / "from_log.mcap")], env=ENV, capture_output=True,
        text=True, timeout=120)
    assert conv.returncode == 0, conv.stderr
    return {"bus": bus, "scans": (k + 1) // 2,
            "live": recording.read(tmp / "live.mcap"),
            "from_log": recording.read(tmp / "from_log.mcap")}


@pytest.mark.parametrize("kind", ["live", "from_log"])
def test_topics_counts_and_times(session, kind):
    rec, bus = session[kind], session["bus"]
    for topic, schema in TOPICS.items():
        assert rec.schemas.get(topic) == schema, (topic, rec.schemas)
    n_js = len(bus["QRT_JOINT_STATE"])
    assert n_js >= 60
    for t in ("/arm", "/joint_states", "/qrtplan/joint_state"):
        assert rec.count(t) == n_js, t
    assert len(bus["QRT_PLAN"]) >= 5
    assert rec.count("/plan") == rec.count("/plan/status") == len(
        bus["QRT_PLAN"])
    assert rec.count("/qrtplan/status") == len(bus["QRT_STATUS"]) >= 2
    assert 1 <= rec.count("/obstacles/s0") <= session["scans"]
    if kind == "from_log":  # nothing is skipped when converting
        assert rec.count("/obstacles/s0") == session["scans"]
    # the drive state changed once, the CAN state ("off") was seen once
    assert [d["drive_state"] for d in rec.values("/drives")][-1] == \
        "operation_enabled"
    for topic, msgs in rec.messages.items():
        t = [lt for lt, _ in msgs]
        assert all(b >= a for a, b in zip(t, t[1:])), topic
        assert len(set(t)) == len(t) or topic.startswith("/drives"), topic


@pytest.mark.parametrize("kind", ["live", "from_log"])
def test_contents_match_the_bus(session, kind):
    rec, bus = session[kind], session["bus"]
    want = [T["joint_state_t"].decode(d) for d in bus["QRT_JOINT_STATE"]]
    got = rec.values("/qrtplan/joint_state")
    assert [(g["utime"], g["joints_deg"], g["drive_state"]) for g in got] == \
        [(w.utime, list(w.joints_deg), w.drive_state) for w in want]
    for g, js in zip(rec.values("/joint_states"), want):
        assert [j.name for j in g.joints] == ["alpha", "sigma", "eta"]
        assert np.allclose([j.position for j in g.joints],
                           np.radians(js.joints_deg))
    plans = [T["plan_t"].decode(d) for d in bus["QRT_PLAN"]]
    got = rec.values("/plan/status")
    assert [(g["utime"], g["status"], g["n_waypoints"], g["clearance_m"],
             g["cells_blocked"]) for g in got] == \
        [(p.utime, p.status, p.n_waypoints, p.clearance_m, p.cells_blocked)
         for p in plans]
    ok = [i for i, p in enumerate(plans) if p.status == "ok"]
    assert ok, [p.status for p in plans]
    # the daemon's default as-read mask: never whole, never counted; an ok
    # plan's clearance certified, at least the margin (the sphere is there)
    assert {p.cells_blocked for p in plans} == {-1}
    assert all(0.01 <= plans[i].clearance_m < 1e9 for i in ok)
    # /plan/log: one line per status change, with the clearance for ok
    lines = [g.message for g in rec.values("/plan/log")]
    first_ok = plans[ok[0]]
    assert bridge.plan_summary(first_ok) in lines, lines
    assert f"clearance {first_ok.clearance_m * 1000:.1f} mm" in \
        bridge.plan_summary(first_ok)
    assert all("blocked cells not counted" in x for x in lines), lines
    arm = Arm.default()
    for i in ok:
        scene = rec.values("/plan")[i]
        ents = {e.id: e for e in scene.entities}
        line = ents["tool_path"].lines[0].points
        w = np.array(plans[i].waypoints_deg)
        for end, q in ((line[0], w[0]), (line[-1], w[-1])):
            assert np.allclose([end.x, end.y, end.z],
                               forward_points(arm, list(q))[-1], atol=1e-9)
        # alpha the short way across +-180, as the drives move
        a = np.degrees(np.arctan2([p.y for p in line], [p.x for p in line]))
        swept = np.abs(bridge.wrap180(np.diff(a))).sum()
        assert swept == pytest.approx(
            np.abs(bridge.wrap180(np.diff(w[:, 0]))).sum(), abs=1e-6)
        n_ghosts = min(len(w), 12)
        assert len(ents["ghosts"].cylinders) == 3 * n_ghosts
    # the arm drawn at the joints of each joint state
    for scene, js in zip(rec.values("/arm"), want):
        c = scene.entities[0].cylinders
        assert len(c) == 3
        tip = forward_points(arm, list(js.joints_deg))[3]
        far = c[2].pose.position  # link 3's middle, half its length on
        assert np.linalg.norm(np.array([far.x, far.y, far.z]) - tip) == \
            pytest.approx(c[2].size.z / 2, abs=1e-9)


def test_scan_points_round_trip():
    rng = np.random.default_rng(38)
    p = rng.uniform(-1.5, 1.5, (500, 3))
    q = bridge.scan_points(scan_from_points(p, position=(0.2, -0.1, 0.3)))
    assert np.allclose(q, p, atol=1e-5)
    # a turned sensor: 30 deg about (1, 2, 3); returns in its own frame
    axis = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    th = np.radians(30.0)
    w, x, y, z = np.cos(th / 2), *(np.sin(th / 2) * axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                  [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K  # Rodrigues
    pos = np.array([0.2, -0.1, 0.3])
    s = scan_from_points((p - pos) @ R)  # R^T (p - pos), as rows
    s.position_m, s.orientation = list(pos), [w, x, y, z]
    assert np.allclose(bridge.scan_points(s), p, atol=1e-5)
    s = scan_from_points(p)
    s.range_m[0], s.range_m[1], s.range_m[2] = float("nan"), -1.0, 5.0
    s.n = len(s.range_m)
    assert len(bridge.scan_points(s)) == 497  # NaN, negative, max range


def test_envelope_is_seen_through():
    """A signed scan (authenticated_message_t) is drawn as the scan it
    carries; the header peek finds its type without decoding it."""
    data = scan_from_points(np.array([[0.5, 0.0, 0.2]])).encode()
    env = T["authenticated_message_t"]()
    env.channel, env.sender_id, env.counter = "QRT_SCAN", "s0", now_us()
    env.payload_size, env.payload = len(data), data
    env.nonce, env.mac = bytes(24), bytes(16)
    sealed = env.encode()
    assert bridge.carried_type(sealed) == "range_scan_t"
    assert bridge.lcm_type_name(sealed) == "authenticated_message_t"


DEMO = ROOT / "build" / "demo"


@pytest.mark.skipif(not (DEMO / "session.mcap").exists(),
                    reason="make demo has not recorded build/demo/session.mcap")
def test_demo_session():
    """make demo's closed loop: every joint state the daemon published
    while the demo traced them (can_trace.csv; the recorder started before
    and stopped after) is in the recording, in order, with the drives'
    states, beside the ok plan and the obstacle cloud."""
    rec = recording.read(DEMO / "session.mcap")
    with open(DEMO / "can_trace.csv") as f:
        rows = list(csv.DictReader(f))
    got = rec.values("/qrtplan/joint_state")
    first = [g["utime"] for g in got].index(int(rows[0]["utime"]))
    got = got[first:first + len(rows)]
    assert [g["utime"] for g in got] == [int(r["utime"]) for r in rows]
    assert np.allclose([g["joints_deg"] for g in got],
                       [[float(r[k]) for k in ("alpha_deg", "sigma_deg",
                                               "eta_deg")] for r in rows])
    assert [g["drive_state"] for g in got] == [r["drive_state"] for r in rows]
    assert any(p["status"] == "ok" for p in rec.values("/plan/status"))
    assert rec.count("/obstacles/s0") > 0
    assert any(d["can_state"] not in (None, "off")
               for d in rec.values("/drives"))


def _ws_frames(sock, timeout=5.0):
    """The text frames a WebSocket server sends first (no masking from a
    server; enough of RFC 6455 for serverInfo and advertise)."""
    import socket
    sock.settimeout(timeout)
    buf = b""
    while b"\r\n\r\n" not in buf:
        buf += sock.recv(65536)
    head, _, rest = buf.partition(b"\r\n\r\n")
    out, end = [], time.time() + timeout
    while time.time() < end and len(out) < 2:
        while len(rest) < 10 and time.time() < end:
            try:
                rest += sock.recv(65536)
            except socket.timeout:
                break
        if len(rest) < 2:
            break
        n, o = rest[1] & 0x7F, 2
        if n == 126:
            n, o = int.from_bytes(rest[2:4], "big"), 4
        elif n == 127:
            n, o = int.from_bytes(rest[2:10], "big"), 10
        while len(rest) < o + n:
            rest += sock.recv(65536)
        if rest[0] & 0x0F == 1:
            out.append(json.loads(rest[o:o + n]))
        rest = rest[o + n:]
    return head.split(b"\r\n")[0], out


def test_websocket_advertises():
    """--ws: a Foxglove client's handshake is answered (101), then
    serverInfo and the advertised topics, the arm among them once a joint
    state has been seen."""
    import base64
    import socket
    url = f"udpm://239.255.76.67:{PORT + 40}?ttl=0"
    port = 18700 + os.getpid() % 50
    view = subprocess.Popen([PY, "-m", "qrtplan.view", "--lcm-url", url,
                             "--ws", str(port)], env=ENV,
                            stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(2.0)
        js = T["joint_state_t"]()
        js.utime, js.joints_deg, js.drive_state = now_us(), [1, 2, 3], "x"
        lcm.LCM(url).publish("QRT_JOINT_STATE", js.encode())
        time.sleep(0.5)
        with socket.create_connection(("127.0.0.1", port)) as s:
            key = base64.b64encode(os.urandom(16)).decode()
            s.sendall((
                "GET / HTTP/1.1\r\nHost: localhost\r\nUpgrade: websocket\r\n"
                "Connection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
                f"Sec-WebSocket-Key: {key}\r\n"
                "Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n").encode())
            status, frames = _ws_frames(s)
    finally:
        _stop(view)
    assert b" 101 " in status
    assert frames[0]["op"] == "serverInfo"
    assert frames[0]["name"] == "qrtplan-view"
    topics = {c["topic"]: c for c in frames[1]["channels"]}
    assert frames[1]["op"] == "advertise"
    assert topics["/arm"]["schemaName"] == "foxglove.SceneUpdate"
    assert "/qrtplan/joint_state" in topics


@pytest.mark.skipif("point_cloud_t" not in T,
                    reason="the build has no point_cloud_t (lcm/point_cloud_t.lcm)")
def test_point_cloud_round_trip():
    """A point_cloud_t from a turned sensor, read by the bridge's own
    decoder, gives the base-frame points; non-finite points are left out;
    the header peek finds its type (it waits like a scan)."""
    rng = np.random.default_rng(7)
    p = rng.uniform(-1.5, 1.5, (300, 3))
    axis = np.array([0.0, 0.6, 0.8])
    th = np.radians(40.0)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                  [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K
    pos = np.array([0.1, 0.2, -0.3])
    local = (p - pos) @ R
    m = T["point_cloud_t"]()
    m.utime, m.sensor_id, m.n = now_us(), "cam", len(p) + 1
    m.position_m = list(pos)
    m.orientation = [np.cos(th / 2), *(np.sin(th / 2) * axis)]
    m.x_m = [*local[:, 0], float("nan")]
    m.y_m = [*local[:, 1], 0.0]
    m.z_m = [*local[:, 2], 0.0]
    data = m.encode()
    assert bridge.carried_type(data) in bridge.CLOUDS
    c = bridge.decode_cloud(data)
    assert c.sensor_id == "cam" and c.utime == m.utime
    assert np.allclose(bridge.cloud_points(c), p, atol=1e-5)


def test_plan_summary_says_clearance_and_blocked_cells():
    """/plan/log's line: an ok plan's clearance (1e9: no point) and the
    whole mask's blocked cells (-1: not built), as plan_t gives them."""
    m = T["plan_t"]()
    m.request_id, m.status, m.detail = 3, "ok", "a path."
    m.clearance_m, m.cells_blocked = 1e9, 120
    assert bridge.plan_summary(m) == \
        "request 3: ok: a path. [no obstacle point; 120 blocked cells]"
    m.status, m.clearance_m, m.cells_blocked = "no_path", 0.0, -1
    assert bridge.plan_summary(m) == ("request 3: no_path: a path. [blocked "
                                      "cells not counted (whole mask not "
                                      "built)]")
