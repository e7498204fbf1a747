#!/usr/bin/env python3
"""Scan-to-plan latency of qrtpland (issue 4's benchmark).

Starts build/bin/qrtpland on its own LCM port, sends a plan request, then
N scans (default 1000) of the paper's 10-sphere x 1444-point scene
(scenes/ten_spheres.json, or --scene: any scene file, its points inline or
in a PCD, e.g. a dense cell of tools/dense_scenes.py) at 20 Hz, each
stamped with the wall clock when
published; the daemon echoes the newest scan's stamp in every plan, and the
plan's arrival is stamped here. Prints median, p99 and max, and writes
build/bench/daemon_latency.csv.

    .venv/bin/python tools/bench_daemon.py [--scans N] [--rate HZ]
        [--mask as-read|whole] [--mask-threads 1|2] [--scene FILE]
"""
import argparse
import collections
import csv
import json
import os
import struct
import subprocess
import sys
import time

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO, "tests", "daemon"), os.path.join(REPO, "tools")]
os.environ.setdefault("QRT_LCMTYPES_PY", os.path.join(REPO, "build", "lcmtypes", "python"))
import conftest as cf  # noqa: E402
import lcm  # noqa: E402
import oracle  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scans", type=int, default=1000)
    ap.add_argument("--rate", type=float, default=20.0)
    ap.add_argument("--mask", default="as-read", choices=["as-read", "whole"])
    ap.add_argument("--mask-threads", default="2")
    ap.add_argument("--scene", help="scene file (default scenes/ten_spheres.json)")
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    # the scene first: nothing to stop if it cannot be read
    if args.scene:
        scene = json.load(open(args.scene))
        pts = oracle.scene_points(scene, os.path.dirname(args.scene))
        what = f"{os.path.basename(args.scene)}, {len(pts)} points"
    else:
        scene, pts = cf.scene_points("ten_spheres.json")
        what = "10 spheres x 1444 points"
    port = 7600 + os.getpid() % 100
    url = f"udpm://239.255.76.67:{port}?ttl=0&recv_buf_size=4194304"
    daemon = subprocess.Popen([cf.DAEMON, "--lcm-url", url, "--mask", args.mask,
                               "--mask-threads", args.mask_threads,
                               "--log-level", "warn"])
    time.sleep(0.5)
    lc = lcm.LCM(url)
    arrived = {}

    def on_plan(channel, data):
        p = cf.plan_t.decode(data)
        arrived.setdefault(p.scan_utime, (time.time(), p))
    lc.subscribe("QRT_PLAN", on_plan)
    # encoded once; each scan only gets its stamp (bytes 8-15, after the
    # type fingerprint), so the publisher here costs what a C++ driver would
    base = bytearray(cf.scan_from_points(pts).encode())
    lc.publish("QRT_PLAN_REQUEST", cf.request(scene["goal"]["joints_deg"],
                                              start=scene["start"]["joints_deg"]).encode())
    sent = []
    period = 1.0 / args.rate
    t_next = time.time()
    try:
        for i in range(args.scans):
            now = time.time()
            while now < t_next:
                lc.handle_timeout(max(1, int((t_next - now) * 1000)))
                now = time.time()
            stamp = int(time.time() * 1e6)
            base[8:16] = struct.pack(">q", stamp)
            lc.publish("QRT_SCAN", bytes(base))
            sent.append(stamp)
            t_next += period
            if i % 100 == 99:
                print(f"\r{i + 1}/{args.scans} scans", end="", file=sys.stderr,
                      flush=True)
        end = time.time() + 1.0
        while time.time() < end:
            lc.handle_timeout(20)
    finally:
        daemon.terminate()
        daemon.wait(10)
    print(file=sys.stderr)
    rows, lat = [], []
    for u in sent:
        if u in arrived:
            t, p = arrived[u]
            ms = (t * 1e6 - u) / 1e3
            lat.append(ms)
            rows.append((u, f"{ms:.3f}", p.status, p.ingest_us, p.mask_us,
                         p.search_us, p.certify_us, p.total_us))
        else:
            rows.append((u, "", "no plan (scan replaced by a newer one)", "", "", "",
                         "", ""))
    path = os.path.join(args.out, "daemon_latency.csv")
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scan_utime", "latency_ms", "status", "ingest_us", "mask_us",
                    "search_us", "certify_us", "daemon_total_us"])
        w.writerows(rows)
    lat = np.array(lat)
    mask = np.array([r[4] for r in rows if r[4] != ""], float) / 1e3
    certify = np.array([r[6] for r in rows if r[6] != ""], float) / 1e3
    how = ("mask nodes asked as the plan reads them (mask + search)"
           if args.mask == "as-read" else
           f"whole mask on {args.mask_threads} thread(s)")
    print(f"qrtpland scan-to-plan latency, {what}, "
          f"{len(sent)} scans at {args.rate:g} Hz, {how}: median "
          f"{np.median(lat):.2f} ms, p99 {np.percentile(lat, 99):.2f} ms, max "
          f"{lat.max():.2f} ms; {len(sent) - len(lat)} scans without a plan of "
          f"their own; mask median {np.median(mask):.2f} ms, clearance "
          f"certified median {np.median(certify):.2f} ms; plans "
          f"{dict(collections.Counter(r[2] for r in rows if r[1]))} ({path})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
