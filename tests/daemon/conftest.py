"""Helpers for the qrtpland tests: a daemon on its own LCM port, a client
built on the PyPI `lcm` package and the Python types lcm-gen made at build
time (QRT_LCMTYPES_PY), and scans made from obstacle points."""
import itertools
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(REPO, "tools"))
sys.path.insert(0, os.environ.get("QRT_LCMTYPES_PY",
                                  os.path.join(REPO, "build", "lcmtypes", "python")))
import lcm  # noqa: E402
from qrtplan import (daemon_status_t, joint_state_t, plan_request_t,  # noqa: E402
                     plan_t, point_cloud_t, range_scan_t)
import qrtauth  # noqa: E402

DAEMON = os.environ.get("QRTPLAND_BIN", os.path.join(REPO, "build", "bin", "qrtpland"))
_ports = itertools.count(7700 + (os.getpid() % 200) * 5)


def now_us():
    return int(time.time() * 1e6)


def scan_from_points(points, sensor="s0", position=(0.0, 0.0, 0.0),
                     orientation=(1.0, 0.0, 0.0, 0.0), max_range=5.0, utime=None):
    """A range scan whose returns hit the given base-frame points, from a
    sensor at `position` with identity orientation (or the given one, then
    the points are taken in the sensor frame)."""
    p = np.asarray(points, float).reshape(-1, 3) - np.asarray(position, float)
    r = np.linalg.norm(p, axis=1)
    msg = range_scan_t()
    msg.utime = now_us() if utime is None else utime
    msg.sensor_id = sensor
    msg.position_m = list(position)
    msg.orientation = list(orientation)
    msg.max_range_m = max_range
    msg.n = len(p)
    msg.azimuth_rad = np.arctan2(p[:, 1], p[:, 0]).tolist()
    msg.elevation_rad = np.arcsin(np.clip(p[:, 2] / np.maximum(r, 1e-12), -1, 1)).tolist()
    msg.range_m = r.tolist()
    return msg


def oracle_plan(plan):
    """A plan_t as tools/oracle.py's plan dict (the CLI's JSON): with
    clearance_m (1e9, no point, is the CLI's null) and stats.voxel_m, so
    that check_path checks the certified clearance of every plan it is
    given against every point given to it."""
    return {"status": plan.status,
            "waypoints_deg": [list(w) for w in plan.waypoints_deg],
            "cost_deg": plan.cost_deg,
            "clearance_m": None if plan.clearance_m >= 1e9 else plan.clearance_m,
            "stats": {"voxel_m": plan.voxel_m}}


def quat_rotate(q, v):
    """v (N x 3) turned by the unit quaternion q = (w, x, y, z)."""
    w, u = q[0], np.asarray(q[1:], float)
    v = np.asarray(v, float)
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def cloud_from_points(points, sensor="s0", position=(0.0, 0.0, 0.0),
                      orientation=(1.0, 0.0, 0.0, 0.0), utime=None):
    """A point cloud holding the given base-frame points, seen from a sensor
    at `position` turned by `orientation` (sensor -> base): the message
    carries them in the sensor frame, as a sensor would send them."""
    p = np.asarray(points, float).reshape(-1, 3) - np.asarray(position, float)
    q = np.asarray(orientation, float)
    local = quat_rotate([q[0], -q[1], -q[2], -q[3]], p)  # base -> sensor
    msg = point_cloud_t()
    msg.utime = now_us() if utime is None else utime
    msg.sensor_id = sensor
    msg.position_m = list(position)
    msg.orientation = list(orientation)
    msg.n = len(local)
    msg.x_m, msg.y_m, msg.z_m = (local[:, i].tolist() for i in range(3))
    return msg


def request(goal, kind=0, start=None, request_id=1, ik=(0, 0)):
    """A plan request; ik is (ik_facing, ik_elbow), read for kind 1 (xyz)."""
    r = plan_request_t()
    r.utime = now_us()
    r.request_id = request_id
    r.goal_kind = kind
    r.goal = list(goal)
    r.has_start = start is not None
    r.start_deg = list(start) if start is not None else [0.0, 0.0, 0.0]
    r.ik_facing, r.ik_elbow = ik
    return r


class Client:
    """An LCM peer on the daemon's URL that collects what it publishes.
    With signers (qrtauth.Signer) it signs what it publishes."""

    def __init__(self, url, signers=None):
        self.lc = lcm.LCM(url)
        self.signed = qrtauth.SignedPublisher(self.lc, signers) if signers else None
        self.plans, self.status = [], []
        self.lc.subscribe("QRT_PLAN", lambda c, d: self.plans.append(
            (time.time(), plan_t.decode(d))))
        self.lc.subscribe("QRT_STATUS", lambda c, d: self.status.append(
            daemon_status_t.decode(d)))

    def publish(self, channel, msg):
        data = msg if isinstance(msg, bytes) else msg.encode()
        if self.signed:
            self.signed.publish(channel, data)
        else:
            self.lc.publish(channel, data)

    def pump(self, seconds):
        end = time.time() + seconds
        while time.time() < end:
            self.lc.handle_timeout(20)

    def wait_plan(self, pred=lambda p: True, timeout=20.0, after=0):
        end = time.time() + timeout
        while time.time() < end:
            for _, p in self.plans[after:]:
                if pred(p):
                    return p
            self.lc.handle_timeout(50)
        return None

    def wait_status(self, pred, timeout=10.0):
        end = time.time() + timeout
        while time.time() < end:
            if self.status and pred(self.status[-1]):
                return self.status[-1]
            self.lc.handle_timeout(50)
        return self.status[-1] if self.status else None


# The daemon's LCM receive buffer. A 14,440-return scan is 350 KB, more
# than the kernel's default 208 KB: with the LCM thread descheduled for a
# moment on a busy machine, its fragments overflowed the socket and the scan
# was lost (seen once in CI: a plan from an empty picture). 4 MiB, as the
# kernel here allows (net.core.rmem_max), as the daemon would be run.
RECV_BUF = "&recv_buf_size=4194304"


class Daemon:
    def __init__(self, tmp_path, *args, url_options=RECV_BUF):
        self.port = next(_ports)
        self.url = f"udpm://239.255.76.67:{self.port}?ttl=0{url_options}"
        # appending: the daemon shares this file description, so with "w+"
        # its writes went where text()'s seek(0) had left the offset and
        # overwrote the log's first line
        self.log = open(tmp_path / f"qrtpland-{self.port}.log", "a+")
        env = dict(os.environ)
        if "ASAN_OPTIONS" in env:
            # ASan keeps freed memory in quarantine (256 MiB): without it the
            # flood test's RSS measures the daemon, not the sanitizer
            env["ASAN_OPTIONS"] += ":quarantine_size_mb=0"
        self.proc = subprocess.Popen([DAEMON, "--lcm-url", self.url, *args],
                                     stdout=self.log, stderr=subprocess.STDOUT,
                                     env=env)
        time.sleep(0.3)
        assert self.proc.poll() is None, self.text()

    def text(self):
        self.log.flush()
        self.log.seek(0)
        return self.log.read()

    def wait_text(self, *needles, timeout=10.0):
        """The log once it holds every needle, or as it is at the timeout:
        the daemon writes its log on a thread of its own, so a line may
        reach the file after the plan or status that follows it on LCM."""
        end = time.time() + timeout
        while True:
            text = self.text()
            if all(n in text for n in needles) or time.time() >= end:
                return text
            time.sleep(0.02)

    def rss_kib(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
        return 0

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                return self.proc.wait(15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                return None
        return self.proc.returncode


@pytest.fixture
def daemon(tmp_path):
    started = []

    def start(*args, url_options=RECV_BUF, keys=None):
        """keys: (name, role) pairs: the daemon trusts them (--keys) and
        the client signs with them."""
        signers = None
        if keys:
            key_dir = str(tmp_path / f"keys{len(started)}")
            signers = qrtauth.gen_keys(DAEMON, key_dir, keys)
            args = (*args, "--keys", key_dir)
        d = Daemon(tmp_path, *args, url_options=url_options)
        started.append(d)
        c = Client(d.url, signers)
        # its first status comes after it has subscribed: from then on
        # nothing published here is missed (slow starts under ASan)
        assert c.wait_status(lambda s: True, timeout=30) is not None, d.text()
        return d, c
    yield start
    for d in started:
        d.stop()


def scene_points(name):
    with open(os.path.join(REPO, "scenes", name)) as f:
        scene = json.load(f)
    return scene, np.asarray(scene["points"], float)
