#!/usr/bin/env python3
"""qrtpland driving the simulated drives for a while, with goals that change
under it, as an operator's would.

Run by CTest's `daemon_soak_vm` through tools/vm/run.sh (inside a VM when
this host's kernel has no CAN). servo_sim powers up at the paper's Table 4
start; the Table 4 sphere comes as a scan every 0.1 s, each copy with its
points moved by up to 2 mm (so the daemon replans on every one), and a new
goal, drawn from the free poses below, every 0.5-3.5 s, mostly while the
arm is still moving (a new goal while the drives execute a path stops
them: the new path starts from rest). After the soak the sphere keeps
coming, a fresh scan every 0.1 s (vm_checks.ScanFeed: the daemon moves the
arm only on evidence younger than --max-scan-age). Then, once the arm
rests at the soak's last goal, a goal far from there and, while the arm
moves towards it, a last goal that it must reach. Checks:
  1. every joint state the daemon publishes is clear of the sphere by the
     independent oracle, to within the scans' noise (2 mm a coordinate);
  2. every plan is ok, at least one for each goal, and the daemon never
     stops answering and exits cleanly;
  3. the last goal is reached;
  4. its status: no scan refused (malformed, stale, from the future, from
     an unknown sensor), no CAN frame malformed, dropped or unsent, no bus
     error (scans replaced by newer ones before a plan used
     them are counted, not failed: how many depends on the machine).
"""
import argparse
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [os.path.join(REPO, "tools"), os.path.join(REPO, "tests", "daemon")]
# the VM does not pass the environment on: the generated types' path comes
# as an argument, before conftest imports them
if "--lcmtypes" in sys.argv:
    os.environ["QRT_LCMTYPES_PY"] = sys.argv[sys.argv.index("--lcmtypes") + 1]
import conftest as cf  # noqa: E402
import oracle  # noqa: E402
from vm_checks import (SANITIZER_ARGS, DaemonWatch, ScanFeed,  # noqa: E402
                       check, failures, joint_gap, stop_daemon_and_drives,
                       signing_lcm, trust)

NOISE_M = 0.002
# a point moved by NOISE_M on each axis moves by up to this much
NOISE_BOUND_M = NOISE_M * np.sqrt(3.0)
GOALS = [[100, 0, 0], [-100, 0, 0], [0, 30, -30], [150, -10, 0],
         [-150, 20, -40], [60, 45, -90], [-30, 60, -120], [170, 10, -20],
         [-170, 5, 10]]
START = [-100, 0, 0]  # where servo_sim powers up: the paper's Table 4 start


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--daemon", required=True)
    ap.add_argument("--servo-sim", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--lcmtypes", required=True)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--seed", type=int, default=5)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    url = "udpm://239.255.76.67:7779?ttl=0&recv_buf_size=4194304"
    sim = subprocess.Popen([args.servo_sim, "--iface", "vcan0", "--start-deg",
                            ",".join(map(str, START)), "--servo-error", "5",
                            "--watchdog-ms", "500"],
                           stderr=open(os.path.join(args.out, "sim.log"), "w"))
    log_path = os.path.join(args.out, "qrtpland.log")
    daemon = subprocess.Popen([args.daemon, "--lcm-url", url, "--can", "vcan0",
             *trust(args.daemon, args.out),
                               "--speed", "60", "--accel", "120",
                               # emulated CPU, busy host: heartbeats come late
                               "--heartbeat-timeout", "1500", *SANITIZER_ARGS],
                              stdout=open(log_path, "w"), stderr=subprocess.STDOUT)
    lc = signing_lcm(url)
    watch = DaemonWatch(lc, cf)
    joints, plans, statuses, pump = (watch.joints, watch.plans, watch.statuses,
                                     watch.pump)

    scene, pts = cf.scene_points("table4_one_sphere.json")
    arm = oracle.Arm(scene)
    rng = np.random.default_rng(args.seed)
    free = [g for g in GOALS
            if oracle.clearances(arm, np.array([g], float), pts).min() > 0.03]
    check(len(free) >= 5, f"{len(free)} of the {len(GOALS)} goals are clear "
          "of the sphere by 3 cm")
    requests = moving_requests = 0
    goal = START  # the arm's goal until the soak gives one
    t0 = time.time()
    feed = None
    try:
        ready = pump(15, lambda: joints and joints[-1].drive_state == "ready")
        check(ready, "the daemon brought the drives up")
        next_scan = next_goal = time.time()
        while time.time() - t0 < args.seconds and daemon.poll() is None:
            now = time.time()
            if now >= next_scan:
                noisy = pts + rng.uniform(-NOISE_M, NOISE_M, pts.shape)
                lc.publish("QRT_SCAN", cf.scan_from_points(noisy).encode())
                next_scan = now + 0.1
            if now >= next_goal:
                requests += 1
                moving_requests += bool(joints and joints[-1].moving)
                goal = free[rng.integers(len(free))]
                lc.publish("QRT_PLAN_REQUEST",
                           cf.request(goal, request_id=requests).encode())
                next_goal = now + rng.uniform(0.5, 3.5)
            lc.handle_timeout(10)
        check(daemon.poll() is None, f"the daemon ran through {requests} "
              f"goals, {moving_requests} given while the arm moved")
        # the soak's last goal is reached first: a last goal given to an arm
        # already resting there would never start it moving (the soak's
        # timing, hence where it ends, depends on the machine)
        soak_goal = goal
        # from here on the sensor keeps scanning on its own (the waits
        # below pump for a second between their own scans, longer than
        # --max-scan-age)
        feed = ScanFeed(url, cf, pts)

        def scan():
            return cf.scan_from_points(pts).encode()
        check(watch.rescan_until(scan, lambda: watch.at_rest_at(soak_goal),
                                 60, 1.0),
              f"the arm came to rest at the soak's last goal {soak_goal}")
        # the last goal is given while the arm moves towards another, far
        # from where it rests: the daemon must stop on that path and go on
        # to this one from rest
        towards = max(free, key=lambda g: joint_gap(g, soak_goal))
        goal = max((g for g in free if g not in (towards, soak_goal)),
                   key=lambda g: joint_gap(g, towards))
        requests += 1
        lc.publish("QRT_PLAN_REQUEST",
                   cf.request(towards, request_id=requests).encode())
        moving = watch.rescan_until(
            scan, lambda: joints and joints[-1].moving, 30, 0.5)
        requests += 1
        lc.publish("QRT_PLAN_REQUEST", cf.request(goal, request_id=requests).encode())
        check(moving and joints[-1].moving,
              f"the last goal {goal} is given while the arm moves from "
              f"{soak_goal} towards {towards}")
        reached = watch.rescan_until(scan, lambda: watch.at_rest_at(goal),
                                     90, 1.0)
        check(reached, f"the arm reached the last goal {goal}: "
              f"{list(joints[-1].joints_deg) if joints else None}")
        seen = len(statuses)
        pump(3, lambda: len(statuses) > seen)
    finally:
        if feed:
            feed.stop()
        stop_daemon_and_drives(daemon, sim)
    check(daemon.returncode == 0, f"clean shutdown (exit {daemon.returncode})")
    kinds = {}
    for p in plans:
        kinds[p.status] = kinds.get(p.status, 0) + 1
    # (how many scans each plan covers depends on the machine: a scan that
    # arrives while a plan is made replaces the one waiting, by design)
    check(len(plans) >= requests and set(kinds) == {"ok"},
          f"{len(plans)} plans for {requests} goals, every one ok: {kinds}")
    q = np.array([j.joints_deg for j in joints]).reshape(-1, 3)
    c = oracle.clearances(arm, q, pts)
    moving = sum(j.moving for j in joints)
    check(len(q) > 50 and moving > len(q) / 4 and
          float(c.min()) >= -NOISE_BOUND_M,
          f"{len(q)} joint states ({moving} moving), every pose clear of the "
          f"sphere: min clearance {c.min():.4f} m (the scans' noise allows "
          f"{-NOISE_BOUND_M:.4f})")
    st = statuses[-1] if statuses else None
    check(st is not None and st.scans_rejected == 0 and
          st.scans_stale == 0 and st.scans_future == 0 and
          st.scans_unknown_sensor == 0 and
          st.can_frames_malformed == 0 and st.can_frames_dropped == 0 and
          st.can_frames_unsent == 0 and st.can_bus_errors == 0 and
          st.can_frames_sent > 0 and st.can_frames_received > 0,
          "status: " + (f"scans {st.scans_received} (dropped {st.scans_dropped}, "
                        f"refused {st.scans_rejected}, stale {st.scans_stale}, "
                        f"from the future {st.scans_future}, unknown sensor "
                        f"{st.scans_unknown_sensor}); CAN sent {st.can_frames_sent}, "
                        f"received {st.can_frames_received}, malformed "
                        f"{st.can_frames_malformed}, dropped {st.can_frames_dropped}, "
                        f"unsent {st.can_frames_unsent}, bus errors {st.can_bus_errors}"
                        if st else "none"))
    print(f"{len(failures)} failures, {time.time() - t0:.1f} s", flush=True)
    if failures:
        with open(log_path) as f:
            print(f.read()[-3000:])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
