"""qrtplan.lcm against a real daemon with --keys: signed points and a
signed request give a plan; the same request unsigned is refused.
Needs QRTPLAND_BIN (skipped without it) and the lcm, pynacl packages."""
import json
import os
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

DAEMON = os.environ.get("QRTPLAND_BIN", "")
pytestmark = pytest.mark.skipif(not os.path.isfile(DAEMON),
                                reason="QRTPLAND_BIN: no daemon to talk to")
ROOT = Path(os.environ.get("QRT_SOURCE_DIR", Path(__file__).resolve().parents[2]))


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


def test_signed_plan_and_unsigned_refused(daemon):
    from qrtplan.lcm import Client
    url, keys, log = daemon
    scene = json.loads((ROOT / "scenes" / "table4_one_sphere.json").read_text())
    pts = np.asarray(scene["points"])
    with Client(url, keys=[keys / "op.key", keys / "s0.key"]) as c:
        c.status(timeout=30)  # the daemon is up and subscribed
        c.publish_points(pts, sensor_id="s0")
        end = time.monotonic() + 10
        while c.status(timeout=5).points_in_picture == 0:
            assert time.monotonic() < end, "the signed scan never arrived"
        # a fresh scan beside the request (--max-scan-age 0.5 s by default)
        c.publish_points(pts, sensor_id="s0")
        plan = c.plan([90, 0, 0], start=[-90, 0, 0], timeout=10)
        log.seek(0)
        assert plan.status == "ok", log.read()
        assert plan.points > 0 and plan.n_waypoints >= 2
        assert np.allclose(plan.waypoints_deg[0], [-90, 0, 0])
        assert np.allclose(plan.waypoints_deg[-1], [90, 0, 0])
        with Client(url) as unsigned:
            c.publish_points(pts, sensor_id="s0")
            rid = unsigned.request_plan([0, 90, 0], start=[-90, 0, 0])
            with pytest.raises(TimeoutError):
                c.wait_plan(rid, timeout=1.5)
        assert c.status(timeout=5).auth_unsigned >= 1
