"""Point clouds (point_cloud_t on QRT_CLOUD*) go where scans go: the same
pose, count, stamp, sensor and budget rules, the same counters, the same
picture (docs/spec-interfaces.md §point_cloud_t). Plans made from clouds
are checked by the independent oracle (tools/oracle.py)."""
import struct
import subprocess
import time

import numpy as np
from conftest import (DAEMON, cloud_from_points, now_us, quat_rotate, request,
                      scan_from_points, scene_points)
from test_daemon import assert_safe

# a sensor 0.8 m above the base and beside it, turned 40 degrees about an
# oblique axis (0.34, 0.77, 0.54): the points travel in its own frame
POSE = dict(position=(0.3, -0.2, 0.8),
            orientation=tuple(np.r_[np.cos(0.35), np.sin(0.35) *
                                    np.array([0.34, 0.77, 0.54]) /
                                    np.linalg.norm([0.34, 0.77, 0.54])]))


def test_clouds_give_plans_the_oracle_calls_safe(daemon):
    d, c = daemon()
    scene, pts = scene_points("ten_spheres.json")
    c.publish("QRT_CLOUD", cloud_from_points(pts, **POSE))
    c.publish("QRT_PLAN_REQUEST", request(scene["goal"]["joints_deg"],
                                          start=scene["start"]["joints_deg"],
                                          request_id=1))
    p = c.wait_plan(lambda p: p.request_id == 1)
    assert p is not None, d.text()
    assert p.status == "ok", p.detail
    assert p.points == len(pts) and p.returns_invalid == 0
    res = assert_safe(scene, p, pts)
    assert res.samples > 100
    # the same obstacles as a scan from the same pose: the same points
    # (scan_from_points takes them in the sensor frame, offset by its
    # position, when the sensor is turned)
    pos, w = np.asarray(POSE["position"]), np.asarray(POSE["orientation"])
    local = quat_rotate(w * [1, -1, -1, -1], pts - pos) + pos
    n = len(c.plans)
    c.publish("QRT_SCAN", scan_from_points(local, **POSE))
    c.publish("QRT_PLAN_REQUEST", request(scene["goal"]["joints_deg"],
                                          start=scene["start"]["joints_deg"],
                                          request_id=2))
    q = c.wait_plan(lambda q: q.request_id == 2, after=n)
    assert q is not None and q.status == "ok", d.text()
    assert q.points == len(pts)
    assert_safe(scene, q, pts)
    st = c.wait_status(lambda s: s.scans_received == 2)
    assert st.scans_rejected == 0, d.text()


def test_a_scan_and_a_cloud_share_the_picture(daemon):
    d, c = daemon()
    scene, pts = scene_points("three_spheres.json")
    half = len(pts) // 2
    # two sensors, one of each kind: both halves in one picture
    c.publish("QRT_SCAN_A", scan_from_points(pts[:half], sensor="a"))
    c.publish("QRT_CLOUD_B", cloud_from_points(pts[half:], sensor="b", **POSE))
    time.sleep(0.2)
    c.publish("QRT_PLAN_REQUEST", request(scene["goal"]["joints_deg"],
                                          start=scene["start"]["joints_deg"],
                                          request_id=1))
    p = c.wait_plan(lambda p: p.points == len(pts))
    assert p is not None, [q.points for _, q in c.plans]
    assert p.status == "ok"
    assert_safe(scene, p, pts)
    # one sensor id, both kinds: its newest message of either kind is its
    # entry (a's cloud replaces a's scan)
    n = len(c.plans)
    c.publish("QRT_CLOUD", cloud_from_points(pts[:10], sensor="a"))
    p = c.wait_plan(lambda p: p.points == 10 + len(pts) - half, after=n)
    assert p is not None, [q.points for _, q in c.plans[n:]]


def ring(n, radius=0.5, z=0.3):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[radius * np.cos(a), radius * np.sin(a), np.full(n, z)]


def test_bad_clouds_are_refused_and_counted(daemon):
    d, c = daemon("--max-returns", "1000", "--max-points", "1000",
                  "--sensor", "s0", "--sensor", "s1")
    good = cloud_from_points(ring(20), **POSE)
    raw = good.encode()
    # the daemon's log is rate-limited: at its sustained rate, so that each
    # refusal is logged

    def send(msg):
        c.publish("QRT_CLOUD", msg)
        c.pump(0.5)

    # rejected (scans_rejected): a scan on the cloud channel (wrong
    # fingerprint), truncated, a count far beyond the bytes, a count over
    # --max-returns, NaN pose, non-unit quaternion, an empty sensor_id length
    send(scan_from_points(ring(20)))
    send(raw[: len(raw) // 2])
    head = bytearray(raw)
    n_at = 8 + 8 + 4 + len(b"s0") + 1 + 24 + 32
    head[n_at:n_at + 4] = struct.pack(">i", 2**31 - 1)
    send(bytes(head))
    send(cloud_from_points(ring(1001)))
    bad = cloud_from_points(ring(20))
    bad.position_m = [float("nan"), 0.0, 0.0]
    send(bad)
    bad = cloud_from_points(ring(20))
    bad.orientation = [1.0, 1.0, 0.0, 0.0]
    send(bad)
    zero = bytearray(raw)
    zero[16:20] = struct.pack(">i", 0)
    send(bytes(zero))
    # a sensor not configured, stale, from the future
    send(cloud_from_points(ring(20), sensor="rear"))
    send(cloud_from_points(ring(20), utime=now_us() - 3_000_000))
    send(cloud_from_points(ring(20), utime=now_us() + 3_600_000_000))
    st = c.wait_status(lambda s: s.scans_rejected == 7 and s.scans_stale == 1
                       and s.scans_future == 1 and s.scans_unknown_sensor == 1)
    assert st is not None and (st.scans_rejected, st.scans_unknown_sensor,
                               st.scans_stale, st.scans_future,
                               st.scans_received) == (7, 1, 1, 1, 0), d.text()
    expected = ("QRT_CLOUD: cloud refused: not a qrtplan.point_cloud_t",
                "cloud refused: claims 20 points but holds",
                "claims 2147483647 points", "claims 1001 points (limit 1000)",
                "non-finite or absurd sensor position", "not a unit quaternion",
                "bad sensor_id length",
                "sensor 'rear' is not one of --require-sensor/--sensor",
                "cloud from 's0' refused: 30", "ms old, over --max-scan-age",
                "ms ahead of this computer's clock")
    log = d.wait_text(*expected)
    for what in expected:
        assert what in log, what
    # nothing of it reached the picture
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=1))
    p = c.wait_plan(lambda p: p.request_id == 1)
    assert p is not None and p.status == "no_obstacle_data", d.text()
    # NaN and infinite points: the cloud is taken, those points skipped and
    # counted (plan_t.returns_invalid), the rest planned around
    pts = ring(30)
    cloud = cloud_from_points(pts)
    cloud.x_m[3] = float("nan")
    cloud.y_m[7] = float("inf")
    cloud.z_m[11] = float("-inf")
    n = len(c.plans)
    c.publish("QRT_CLOUD", cloud)
    p = c.wait_plan(lambda p: p.request_id == 1 and p.status == "ok", after=n)
    assert p is not None, d.text()
    assert (p.points, p.returns_invalid) == (27, 3)
    kept = np.delete(pts, [3, 7, 11], axis=0)
    assert_safe({"start": {"joints_deg": [-90, 0, 0]},
                 "goal": {"joints_deg": [90, 0, 0]}}, p, kept)
    # over the picture's budget beside s0's newest: refused and counted, s0
    # keeps what it saw
    n = len(c.plans)
    c.publish("QRT_CLOUD_1", cloud_from_points(ring(990, radius=0.6),
                                               sensor="s1"))
    st = c.wait_status(lambda s: s.scans_over_budget == 1)
    assert st.scans_over_budget == 1, d.text()
    assert "cloud from 's1' refused: its 990 points" in \
        d.wait_text("cloud from 's1' refused: its 990 points")
    cloud.utime = now_us()  # fresh again (--max-scan-age 0.5 s)
    c.publish("QRT_CLOUD", cloud)
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=2))
    p = c.wait_plan(lambda p: p.request_id == 2, after=n)
    assert p is not None and p.status == "ok" and p.points == 27, d.text()
    assert d.proc.poll() is None


def test_a_sensor_key_sends_clouds_of_its_own_id_only(daemon):
    d, c = daemon(keys=[("op", "operator"), ("s0", "sensor"),
                        ("s1", "sensor")])
    keys = c.signed.by_name

    def sign(name, msg):  # with a key SignedPublisher would not choose
        return keys[name].seal("QRT_CLOUD", msg.encode())

    scene, pts = scene_points("table4_one_sphere.json")
    # c.publish signs a cloud with its sensor_id's key (SignedPublisher)
    c.publish("QRT_CLOUD", cloud_from_points(pts, **POSE))
    c.publish("QRT_PLAN_REQUEST", request([100, 0, 0], start=[-100, 0, 0],
                                          request_id=1))
    first = c.wait_plan(lambda p: p.request_id == 1)
    assert first is not None and first.status == "ok", d.text()
    assert first.points == len(pts)
    assert_safe(scene, first, pts)
    # s1's key, an empty cloud of s0's: it would erase the sphere
    c.lc.publish("QRT_CLOUD", sign("s1", cloud_from_points(pts[:0])))
    # unsigned, and an operator's key: neither may send clouds
    c.lc.publish("QRT_CLOUD", cloud_from_points(pts[:0]).encode())
    c.pump(0.5)
    c.lc.publish("QRT_CLOUD", sign("op", cloud_from_points(pts[:0])))
    st = c.wait_status(lambda s: s.auth_not_permitted == 2
                       and s.auth_unsigned == 1)
    assert st is not None and st.scans_received == 1, d.text()
    log = d.wait_text("sensor key 's1' sent a cloud of sensor 's0'")
    assert "sensor key 's1' sent a cloud of sensor 's0'" in log
    # the sphere is still there (s0's cloud again, fresh): the same request
    # plans the same path
    c.publish("QRT_CLOUD", cloud_from_points(pts, **POSE))
    c.publish("QRT_PLAN_REQUEST", request([100, 0, 0], start=[-100, 0, 0],
                                          request_id=2))
    p = c.wait_plan(lambda p: p.request_id == 2)
    assert p is not None and p.points == len(pts), d.text()
    assert [list(w) for w in p.waypoints_deg] == \
        [list(w) for w in first.waypoints_deg]


def test_the_cloud_channel_option(daemon):
    # LCM subscribes by regular expression: QRT.CLOUD would also take QRTXCLOUD
    r = subprocess.run([DAEMON, "--cloud-channel", "QRT.CLOUD", "--help"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "cloud-channel:" in r.stderr, r.stderr
    r = subprocess.run([DAEMON, "--help"], capture_output=True, text=True)
    assert "--cloud-channel NAME" in r.stdout
    # clouds on NAME_* of another name; the default channel is then not read
    d, c = daemon("--cloud-channel", "PTS")
    c.publish("QRT_CLOUD", cloud_from_points(ring(10), sensor="old"))
    c.publish("PTS_front", cloud_from_points(ring(20), sensor="front"))
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=1))
    p = c.wait_plan(lambda p: p.request_id == 1 and p.status == "ok")
    assert p is not None and p.points == 20, d.text()
    assert "clouds PTS*" in d.text()
