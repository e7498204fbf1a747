"""Absence of evidence is not free space: qrtpland plans only on fresh
scans from the sensors it needs, refuses stale, future and unknown scans
and counts them, bounds the obstacle picture, and escapes what it logs."""
import time

import numpy as np
from conftest import now_us, request, scan_from_points


def ring(n, radius=0.5, z=0.3, sensor="s0", **kw):
    """n distinct points in the arm's reach, as one scan."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    pts = np.c_[radius * np.cos(a), radius * np.sin(a), np.full(n, z)]
    return scan_from_points(pts, sensor=sensor, **kw)


def test_no_plan_before_any_scan(daemon):
    d, c = daemon()
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=1))
    p = c.wait_plan(lambda p: p.request_id == 1)
    assert p is not None, d.text()
    assert (p.status, p.n_waypoints) == ("no_obstacle_data", 0), p.status
    assert "no scan" in p.detail
    # the first scan makes the same goal plannable
    c.publish("QRT_SCAN", ring(10))
    p = c.wait_plan(lambda p: p.request_id == 1 and p.status == "ok")
    assert p is not None and p.n_waypoints >= 2, d.text()


def test_stale_and_future_scans_are_refused_and_counted(daemon):
    d, c = daemon("--window", "5")
    c.publish("QRT_SCAN", ring(10, utime=now_us() - 3_000_000))
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=2))
    p = c.wait_plan(lambda p: p.request_id == 2)
    assert p is not None and p.status == "no_obstacle_data", d.text()
    st = c.wait_status(lambda s: s.scans_stale == 1)
    assert (st.scans_stale, st.scans_received, st.scans_future) == (1, 0, 0)
    assert "over --max-scan-age" in st.last_error
    # a good scan, then one stamped an hour ahead from another sensor: the
    # future scan is refused, and it does not purge the good one's points
    # out of the window
    n = len(c.plans)
    c.publish("QRT_SCAN", ring(40, sensor="good"))
    c.wait_plan(lambda p: p.status == "ok", after=n)  # the first one used
    c.publish("QRT_SCAN", ring(25, sensor="ahead", radius=0.6,
                               utime=now_us() + 3_600_000_000))
    c.pump(0.1)
    c.publish("QRT_SCAN", ring(40, sensor="good"))
    # two good scans in the window, nothing else
    p = c.wait_plan(lambda p: p.status == "ok" and p.points == 80, after=n)
    assert p is not None, [(q.status, q.points) for _, q in c.plans[n:]]
    st = c.wait_status(lambda s: s.scans_future == 1)
    assert st.scans_future == 1, d.text()
    assert "ahead of this computer's clock" in \
        d.wait_text("ahead of this computer's clock")
    assert max(q.points for _, q in c.plans[n:]) == 80


def test_required_sensors_and_the_timer(daemon):
    d, c = daemon("--require-sensor", "front", "--sensor", "side",
                  "--max-scan-age", "0.4")
    c.publish("QRT_SCAN", ring(10, sensor="side"))
    c.publish("QRT_SCAN", ring(10, sensor="rear"))  # not configured
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=3))
    p = c.wait_plan(lambda p: p.request_id == 3)
    assert p is not None and p.status == "no_obstacle_data", d.text()
    assert "'front'" in p.detail
    st = c.wait_status(lambda s: s.scans_unknown_sensor == 1)
    assert st.scans_unknown_sensor == 1 and st.scans_received == 1, d.text()
    # front's scan makes it plannable; then front goes quiet and the
    # daemon says so by itself, on its timer, without another message
    n = len(c.plans)
    stamp = now_us()
    c.publish("QRT_SCAN", ring(10, sensor="front", utime=stamp))
    p = c.wait_plan(lambda p: p.status == "ok", after=n)
    assert p is not None, d.text()
    m = len(c.plans)
    # side keeps sending: a sensor that is not required does not help
    for _ in range(8):
        c.publish("QRT_SCAN", ring(10, sensor="side"))
        c.pump(0.1)
    p = c.wait_plan(lambda p: p.status != "ok", after=m)
    assert p is not None, d.text()
    assert p.status == "stale_obstacle_data" and "'front'" in p.detail, p.detail
    published = next(t for t, q in c.plans[m:] if q is p)
    late = published - stamp * 1e-6
    print(f"front's last scan -> stale_obstacle_data published: {late:.3f} s")
    assert 0.4 <= late < 0.4 + 0.3, late


def test_the_picture_has_a_point_budget(daemon):
    d, c = daemon("--max-points", "1000")
    c.publish("QRT_SCAN", ring(800, sensor="a"))
    c.publish("QRT_SCAN", ring(300, sensor="b", radius=0.6))  # does not fit
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=4))
    p = c.wait_plan(lambda p: p.request_id == 4)
    assert p is not None and p.status == "ok", d.text()
    st = c.wait_status(lambda s: s.scans_over_budget == 1)
    assert st.scans_over_budget == 1, d.text()
    assert p.points == 800
    # b's smaller scan fits; a scan that alone exceeds the budget does not,
    # and its sensor keeps what it saw before
    n = len(c.plans)
    c.publish("QRT_SCAN", ring(150, sensor="b", radius=0.6))
    c.publish("QRT_SCAN", ring(1200, sensor="a", radius=0.7))
    c.publish("QRT_SCAN", ring(150, sensor="b", radius=0.6))
    p = c.wait_plan(lambda p: p.points == 950, after=n)
    assert p is not None, [q.points for _, q in c.plans[n:]]
    st = c.wait_status(lambda s: s.scans_over_budget == 2)
    assert st.scans_over_budget == 2, d.text()


def test_a_window_evicts_its_oldest_scans_to_the_budget(daemon):
    d, c = daemon("--window", "10", "--max-points", "1000")
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=5))
    for k in range(3):
        c.publish("QRT_SCAN", ring(400, sensor="a", radius=0.4 + 0.1 * k))
        c.pump(0.2)
    p = c.wait_plan(lambda p: p.request_id == 5 and p.points == 800)
    assert p is not None, [q.points for _, q in c.plans]
    assert c.wait_status(lambda s: s.points_in_picture == 800) is not None


def test_log_lines_escape_control_characters(daemon):
    d, c = daemon()
    # a channel the scan subscription takes (QRT_SCAN_*) with an escape
    # sequence in its name, carrying garbage: the refusal quotes the name
    c.publish("QRT_SCAN_\x1b[2J\x07forged", b"\x00" * 40)
    st = c.wait_status(lambda s: s.scans_rejected == 1)
    assert st is not None and st.scans_rejected == 1, d.text()
    log = d.wait_text("QRT_SCAN_\\x1b[2J\\x07forged")
    assert "QRT_SCAN_\\x1b[2J\\x07forged" in log, log
    assert "\x1b" not in log and "\x07" not in log


def test_evidence_options_are_checked(daemon, tmp_path):
    import subprocess
    from conftest import DAEMON
    for bad in (["--max-scan-age", "0"], ["--require-sensor", ""],
                ["--sensor", "a,,b"], ["--max-points", "10"],
                ["--max-clock-skew", "-1"], ["--guard-deadline", "5"]):
        r = subprocess.run([DAEMON, *bad], capture_output=True, text=True,
                           timeout=10)
        assert r.returncode == 2 and bad[0][2:] in r.stderr, (bad, r.stderr)
    # a list in the config file, more on the command line
    cfg = tmp_path / "q.conf"
    cfg.write_text("require-sensor = front,side\nmax-scan-age = 0.3\n")
    d, c = daemon("--config", str(cfg), "--require-sensor", "top")
    c.publish("QRT_SCAN", ring(10, sensor="front"))
    c.publish("QRT_SCAN", ring(10, sensor="side"))
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0],
                                          request_id=6))
    p = c.wait_plan(lambda p: p.request_id == 6)
    assert p is not None and p.status == "no_obstacle_data", d.text()
    assert "'top'" in p.detail
