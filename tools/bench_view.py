#!/usr/bin/env python3
"""qrtplan-view under load (docs/benchmarks.md, docs/view.md): this script
publishes, for --seconds, a range scan of --points returns at --scan-hz
and a joint state at --joint-hz (the daemon's 20 Hz with --can) on its own
LCM port, while `python -m qrtplan.view --mcap` records them; then it reads
the recording back and reports joint states published / recorded, scans
published / drawn / replaced by a newer one before being drawn, the MCAP's
size and the bridge's CPU time. Exit 1 if a joint state is missing.

  .venv/bin/python tools/bench_view.py [--seconds 10] [--points 100000]
"""
import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np

import lcm

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "python"))
from qrtplan.view import bridge, recording  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument("--scan-hz", type=float, default=20.0)
    ap.add_argument("--joint-hz", type=float, default=20.0)
    ap.add_argument("--port", type=int, default=7297)  # not the tests' ports
    ap.add_argument("--json", action="store_true", help="one JSON line")
    a = ap.parse_args()
    T = bridge.TYPES
    url = f"udpm://239.255.76.67:{a.port}?ttl=0&recv_buf_size=8388608"
    rng = np.random.default_rng(1)
    scan = T["range_scan_t"]()
    scan.sensor_id, scan.max_range_m, scan.n = "bench", 10.0, a.points
    scan.position_m, scan.orientation = [0.0, 0.0, 0.5], [1.0, 0.0, 0.0, 0.0]
    scan.azimuth_rad = rng.uniform(-np.pi, np.pi, a.points).tolist()
    scan.elevation_rad = rng.uniform(-0.5, 0.5, a.points).tolist()
    scan.range_m = rng.uniform(0.3, 3.0, a.points).tolist()
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "bench.mcap")
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            p for p in (sys.path[0], os.environ.get("PYTHONPATH")) if p))
        view = subprocess.Popen(
            [sys.executable, "-m", "qrtplan.view", "--lcm-url", url, "--mcap",
             out], stderr=subprocess.PIPE, text=True, env=env)
        lc = lcm.LCM(url)
        time.sleep(2.0)  # the bridge subscribed
        t0 = time.monotonic()
        next_scan = next_joint = t0
        n_js = n_scan = 0
        pub_s = 0.0
        while time.monotonic() - t0 < a.seconds:
            now = time.monotonic()
            if now >= next_joint:
                js = T["joint_state_t"]()
                js.utime = time.time_ns() // 1000
                js.joints_deg = [float(n_js % 360) - 179.0, 10.0, -20.0]
                js.moving, js.drive_state = True, "operation_enabled"
                lc.publish("QRT_JOINT_STATE", js.encode())
                n_js += 1
                next_joint += 1.0 / a.joint_hz
            if now >= next_scan:
                scan.utime = time.time_ns() // 1000
                t = time.perf_counter()
                lc.publish("QRT_SCAN", scan.encode())
                pub_s += time.perf_counter() - t
                n_scan += 1
                next_scan += 1.0 / a.scan_hz
            time.sleep(max(0.0, min(next_joint, next_scan) - time.monotonic()))
        time.sleep(1.0)  # the last ones arrive
        stop = time.monotonic()
        view.send_signal(signal.SIGINT)
        err = view.communicate(timeout=120)[1]
        drain_s = time.monotonic() - stop
        cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
        rec = recording.read(out)
        size = os.path.getsize(out)
    counts = rec.values("/qrtplan/view")[-1]
    r = {
        "seconds": a.seconds, "points": a.points, "scan_hz": a.scan_hz,
        "joint_hz": a.joint_hz,
        "scan_bytes": len(scan.encode()),
        "joint_states_published": n_js,
        "joint_states_recorded": rec.count("/qrtplan/joint_state"),
        "scans_published": n_scan,
        "scans_received": counts["scans_received"],
        "scans_drawn": rec.count("/obstacles/bench"),
        "scans_replaced": counts["scans_replaced"],
        "fifo_max": counts["fifo_max"],
        "bridge_cpu_s": round(cpu.ru_utime + cpu.ru_stime, 2),
        "stop_to_closed_s": round(drain_s, 2),
        "publish_ms_per_scan": round(1e3 * pub_s / max(n_scan, 1), 1),
        "mcap_mb": round(size / 1e6, 1),
    }
    if a.json:
        print(json.dumps(r))
    else:
        for k, v in r.items():
            print(f"{k:>24}: {v}")
    if view.returncode != 0:
        print(err, file=sys.stderr)
        return 1
    return 0 if r["joint_states_recorded"] == n_js else 1


if __name__ == "__main__":
    sys.exit(main())
