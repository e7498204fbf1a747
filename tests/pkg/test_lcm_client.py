"""qrtplan.lcm against a real daemon with --keys: a signed scan or a
signed cloud and a signed request give a plan; the same request unsigned
is refused. Needs QRTPLAND_BIN (skipped without it) and the lcm, pynacl
packages."""
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

DAEMON = os.environ.get("QRTPLAND_BIN", "")
pytestmark = pytest.mark.skipif(not os.path.isfile(DAEMON),
                                reason="QRTPLAND_BIN: no daemon to talk to")
ROOT = Path(os.environ.get("QRT_SOURCE_DIR", Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(ROOT / "tools"))
import oracle  # noqa: E402


@pytest.fixture
def daemon(tmp_path):
    from qrtplan import auth
    auth.gen_keys(DAEMON, str(tmp_path / "keys"), [("op", "operator"), ("s0", "sensor")])
    port = 7900 + os.getpid() % 90
    # a group of its own: no crosstalk with tests/daemon running beside it
    url = f"udpm://239.255.76.68:{port}?ttl=0&recv_buf_size=4194304"
    log = open(tmp_path / "qrtpland.log", "w+")
    proc = subprocess.Popen([DAEMON, "--lcm-url", url, "--keys", str(tmp_path / "keys")],
                            stdout=log, stderr=subprocess.STDOUT)
    yield url, tmp_path / "keys", log
    proc.terminate()
    proc.wait(15)


def test_signed_scan_plan_and_unsigned_refused(daemon):
    from qrtplan.lcm import Client, points_to_scan
    url, keys, log = daemon
    scene = json.loads((ROOT / "scenes" / "table4_one_sphere.json").read_text())
    pts = np.asarray(scene["points"])
    with Client(url, keys=[keys / "op.key", keys / "s0.key"]) as c:
        c.status(timeout=30)  # the daemon is up and subscribed
        c.publish_scan(points_to_scan(pts, "s0"))
        end = time.monotonic() + 10
        while c.status(timeout=5).points_in_picture == 0:
            assert time.monotonic() < end, "the signed scan never arrived"
        # a fresh scan beside the request (--max-scan-age 0.5 s by default)
        c.publish_scan(points_to_scan(pts, "s0"))
        plan = c.plan([90, 0, 0], start=[-90, 0, 0], timeout=10)
        log.seek(0)
        assert plan.status == "ok", log.read()
        assert plan.points > 0 and plan.n_waypoints >= 2
        assert np.allclose(plan.waypoints_deg[0], [-90, 0, 0])
        assert np.allclose(plan.waypoints_deg[-1], [90, 0, 0])
        with Client(url) as unsigned:
            c.publish_scan(points_to_scan(pts, "s0"))
            rid = unsigned.request_plan([0, 90, 0], start=[-90, 0, 0])
            with pytest.raises(TimeoutError):
                c.wait_plan(rid, timeout=1.5)
        assert c.status(timeout=5).auth_unsigned >= 1


def test_signed_cloud_from_a_turned_sensor(daemon):
    """publish_points: a point_cloud_t on QRT_CLOUD, signed with the key of
    its sensor_id, the points in the frame of a sensor 0.8 m up and turned
    40 degrees about an oblique axis; the plan is the oracle's safe path
    around the scene's base-frame points."""
    from qrtplan.lcm import Client
    url, keys, log = daemon
    scene = json.loads((ROOT / "scenes" / "ten_spheres.json").read_text())
    pts = np.asarray(scene["points"])
    pos = np.array([0.3, -0.2, 0.8])
    axis = np.array([0.34, 0.77, 0.54]) / np.linalg.norm([0.34, 0.77, 0.54])
    w = np.r_[np.cos(0.35), np.sin(0.35) * axis]  # sensor -> base
    u = -w[1:]  # its inverse: base -> sensor
    v = pts - pos
    t = 2.0 * np.cross(u, v)
    local = v + w[0] * t + np.cross(u, t)
    start, goal = scene["start"]["joints_deg"], scene["goal"]["joints_deg"]
    with Client(url, keys=[keys / "op.key", keys / "s0.key"]) as c:
        c.status(timeout=30)
        sent = c.publish_points(local, sensor_id="s0", position_m=pos, orientation=w)
        assert sent.n == len(pts) and type(sent).__name__ == "point_cloud_t"
        end = time.monotonic() + 10
        while c.status(timeout=5).points_in_picture == 0:
            assert time.monotonic() < end, "the signed cloud never arrived"
        c.publish_points(local, sensor_id="s0", position_m=pos, orientation=w)
        plan = c.plan(goal, start=start, timeout=10)
        log.seek(0)
        assert plan.status == "ok", log.read()
        assert plan.points == len(pts) and plan.returns_invalid == 0
        st = c.status(timeout=5)
        assert st.scans_rejected == 0 and st.auth_not_permitted == 0
    # SignedPublisher picks the sensor's key on the cloud channel and its
    # NAME_* channels, as on the scan channel, and no key elsewhere
    from qrtplan.auth import SignedPublisher, Signer
    signed = SignedPublisher(None, [Signer(str(keys / k)) for k in ("op.key", "s0.key")])
    for channel in ("QRT_CLOUD", "QRT_CLOUD_front", "QRT_SCAN_rear"):
        assert signed.signer_for(channel, sent.encode()).name == "s0", channel
    with pytest.raises(KeyError):
        signed.signer_for("QRT_CLOUDS", sent.encode())
    as_json = {"status": plan.status, "cost_deg": plan.cost_deg,
               "waypoints_deg": [list(q) for q in plan.waypoints_deg]}
    res = oracle.check_path(scene, as_json, pts)
    assert res.safe, str(res)
    # the spheres block the straight motion: the plan went round them
    assert res.samples > 100 and plan.n_waypoints > 2
