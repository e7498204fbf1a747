#!/usr/bin/env python3
"""What authenticated LCM costs (issue 35's benchmark): scan-to-plan latency of two
qrtpland daemons in the same run, one taking unsigned messages, one with
--keys, on the paper's 10 spheres x 1444 points (scenes/ten_spheres.json).

Scans go to the two daemons in turn, one at a time (the order swapped every
pair): each is stamped, signed for the keyed daemon (PyNaCl, as a sensor
driver would sign), published, and timed to the plan that echoes its stamp.
The signed figure includes signing here and verifying in the daemon.
Prints both medians, their ratio and the median of the paired differences
(the steadier figure on a shared machine); writes
build/bench/auth_latency.csv.

    .venv/bin/python tools/bench_auth.py [--pairs N]
"""
import argparse
import csv
import os
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO, "tests", "daemon"), os.path.join(REPO, "tools")]
os.environ.setdefault("QRT_LCMTYPES_PY", os.path.join(REPO, "build", "lcmtypes", "python"))
import conftest as cf  # noqa: E402
import lcm  # noqa: E402
import qrtauth  # noqa: E402


class Peer:
    def __init__(self, port, extra, signers):
        self.url = f"udpm://239.255.76.67:{port}?ttl=0&recv_buf_size=4194304"
        self.proc = subprocess.Popen([cf.DAEMON, "--lcm-url", self.url,
                                      "--log-level", "warn", *extra])
        self.lc = lcm.LCM(self.url)
        self.signed = qrtauth.SignedPublisher(self.lc, signers) if signers else None
        self.arrived = {}
        self.lc.subscribe("QRT_PLAN", self.on_plan)

    def on_plan(self, channel, data):
        p = cf.plan_t.decode(data)
        self.arrived.setdefault(p.scan_utime, (time.time(), p))

    def publish(self, channel, data):
        (self.signed or self.lc).publish(channel, data)

    def one_scan(self, base, timeout=5.0):
        """Latency (ms) of one scan to its plan, or None."""
        stamp = time.time_ns() // 1000
        base[8:16] = struct.pack(">q", stamp)
        self.publish("QRT_SCAN", bytes(base))
        end = time.time() + timeout
        while stamp not in self.arrived and time.time() < end:
            self.lc.handle_timeout(5)
        if stamp not in self.arrived:
            return None
        t, p = self.arrived[stamp]
        return (t * 1e6 - stamp) / 1e3 if p.status == "ok" else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=300)
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    key_dir = tempfile.mkdtemp(prefix="qrt-bench-keys-")
    signers = qrtauth.gen_keys(cf.DAEMON, key_dir, [("op", "operator"), ("s0", "sensor")])
    port = 7500 + os.getpid() % 50 * 2
    peers = {"unsigned": Peer(port, [], None),
             "signed": Peer(port + 1, ["--keys", key_dir], signers)}
    scene, pts = cf.scene_points("ten_spheres.json")
    base = bytearray(cf.scan_from_points(pts).encode())
    rows = []
    try:
        time.sleep(0.5)
        for p in peers.values():
            p.publish("QRT_SCAN", bytes(base[:8]) + struct.pack(">q", time.time_ns() // 1000)
                      + bytes(base[16:]))
            p.publish("QRT_PLAN_REQUEST", cf.request(scene["goal"]["joints_deg"],
                                                     start=scene["start"]["joints_deg"])
                      .encode())
        for p in peers.values():  # warm: each has planned once
            if p.one_scan(base, timeout=15) is None:
                sys.exit(f"bench_auth: no plan from {p.url}")
        names = list(peers)
        for i in range(args.pairs):
            order = names if i % 2 == 0 else names[::-1]
            got = {n: peers[n].one_scan(base) for n in order}
            rows.append((i, got["unsigned"], got["signed"]))
            time.sleep(0.02)
            if i % 50 == 49:
                print(f"\r{i + 1}/{args.pairs} pairs", end="", file=sys.stderr, flush=True)
    finally:
        for p in peers.values():
            p.proc.terminate()
            p.proc.wait(10)
    print(file=sys.stderr)
    path = os.path.join(args.out, "auth_latency.csv")
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["pair", "unsigned_ms", "signed_ms"])
        w.writerows([(i, "" if u is None else f"{u:.3f}", "" if s is None else f"{s:.3f}")
                     for i, u, s in rows])
    both = np.array([(u, s) for _, u, s in rows if u is not None and s is not None])
    if len(both) < args.pairs // 2:
        sys.exit(f"bench_auth: only {len(both)} of {args.pairs} pairs planned")
    mu, ms = np.median(both[:, 0]), np.median(both[:, 1])
    diff = np.median(both[:, 1] - both[:, 0])
    print(f"authenticated LCM: scan-to-plan median {ms:.2f} ms with keys, "
          f"{mu:.2f} ms without (ratio {ms / mu:.3f}); median paired "
          f"difference {diff * 1e3:.0f} us = {100 * diff / mu:.1f} % of the "
          f"unkeyed median (target <= 5 %); {len(both)} pairs, 10 spheres x "
          f"1444 points ({path})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
