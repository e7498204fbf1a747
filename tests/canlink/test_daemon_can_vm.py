#!/usr/bin/env python3
"""qrtpland driving the simulated drives over vcan0, from scans and a goal.

Run by CTest's `daemon_can_vm` through tools/vm/run.sh (inside a VM when
this host's kernel has no CAN), and by `make bench` for the stop latency
(--trials 200). servo_sim powers up at the paper's Table 4 start; the
daemon gets the Table 4 sphere as a scan and a goal with no start, so it
plans from the joints the drives report (their own counts per degree and
counts at 0 degrees, given to both sides), and moves the arm. The scene
comes as a sensor would send it, a freshly stamped scan every 0.1 s
(vm_checks.ScanFeed): the daemon moves the arm only on evidence younger
than --max-scan-age.
  1. the joints the daemon publishes (from the drives' PDOs) reach the
     goal, and every pose on the way is collision-free by the oracle;
  2. trials: while the arm moves, the scans put an obstacle on the rest of
     its path; the daemon reports the blocked path and sends a quick stop;
     the time from that scan's publication to the first quick-stop frame on
     the bus (candump's timestamp) is the stop latency. Clear scans then
     let it move on (the next plan executes);
  3. the interface goes down for a second while the arm moves and comes
     back: the status reports the bus fault, the daemon stays up, brings
     the drives up again by itself, and the next plans take the arm on;
  4. at the goal, two malformed TPDOs: the arm holds, and the daemon's
     status counts them (and no frame dropped, no bus error since the
     unplugging);
  5. every captured frame but those two decodes with the DBC.
"""
import argparse
import os
import re
import subprocess
import sys
import time

import cantools
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# drives geared differently on each joint, their encoders zeroed elsewhere
# than the joints (both sides told the same)
DRIVES = ["--counts-per-deg", "1000,2000,500", "--offset-counts",
          "5000,-20000,0"]
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [os.path.join(REPO, "tools"), os.path.join(REPO, "tests", "daemon")]
# the VM does not pass the environment on: the generated types' path comes
# as an argument, before conftest imports them
if "--lcmtypes" in sys.argv:
    os.environ["QRT_LCMTYPES_PY"] = sys.argv[sys.argv.index("--lcmtypes") + 1]
import conftest as cf  # noqa: E402
import oracle  # noqa: E402
from candump_capture import drain, dropped, start  # noqa: E402
from vm_checks import (SANITIZER_ARGS, DaemonWatch, ScanFeed,  # noqa: E402
                       check, failures, stop_daemon_and_drives,
                       signing_lcm, trust)

# TPDO1 of nodes 1 and 2 with too few bytes (candump's spelling)
MALFORMED = ("181#00", "182#0102")


def quick_stops(capture):
    """Wall-clock times of quick-stop frames (RPDO1 controlword 0x0002)."""
    out = []
    with open(capture) as f:
        for line in f:
            parts = line.split()
            if len(parts) < 3 or "#" not in parts[2]:
                continue
            ident, data = parts[2].split("#", 1)
            if 0x201 <= int(ident, 16) <= 0x27F and data[:4] == "0200":
                out.append(float(parts[0].strip("()")))
    return np.array(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--daemon", required=True)
    ap.add_argument("--servo-sim", required=True)
    ap.add_argument("--dbc", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--trials", type=int, default=5)
    ap.add_argument("--lcmtypes", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    url = "udpm://239.255.76.67:7777?ttl=0&recv_buf_size=4194304"
    capture = os.path.join(args.out, "daemon_can.candump")
    dump = start(capture)  # listening before the drives start
    sim = subprocess.Popen([args.servo_sim, "--iface", "vcan0", "--start-deg",
                            "-100,0,0", "--servo-error", "5", "--watchdog-ms",
                            "500", *DRIVES],
                           stderr=open(os.path.join(args.out, "sim.log"), "w"))
    # emptied, then appended to: the log is read while the daemon runs,
    # and its writes must not land where that read's seek left the offset
    open(os.path.join(args.out, "qrtpland.log"), "w").close()
    daemon_log = open(os.path.join(args.out, "qrtpland.log"), "a+")
    daemon = subprocess.Popen([args.daemon, "--lcm-url", url, "--can", "vcan0",
             *trust(args.daemon, args.out),
                               "--speed", "30", "--accel", "60", *DRIVES,
                               # emulated CPU, busy host: heartbeats come late
                               "--heartbeat-timeout", "1500", *SANITIZER_ARGS],
                              stdout=daemon_log, stderr=subprocess.STDOUT)
    lc = signing_lcm(url)
    watch = DaemonWatch(lc, cf)
    joints, plans, statuses, pump = (watch.joints, watch.plans, watch.statuses,
                                     watch.pump)

    scene, pts = cf.scene_points("table4_one_sphere.json")
    arm = oracle.Arm(scene)
    goal = [100.0, 0.0, 0.0]
    t0 = time.time()
    latencies, sent_times = [], []
    feed = None
    try:
        ok = pump(15, lambda: joints and joints[-1].drive_state == "ready")
        check(ok, f"the daemon brought the drives up ({time.time() - t0:.1f} s)")
        # read with one scale for all and no offsets, they would be at
        # (-95, -20, 0)
        here = list(joints[-1].joints_deg) if joints else None
        check(here is not None and
              np.allclose(here, [-100, 0, 0], atol=0.02),
              f"the daemon reads the drives, each geared and zeroed its own "
              f"way, where they stand: {here}")
        # the sensor: the Table 4 sphere, a fresh scan every 0.1 s
        feed = ScanFeed(url, cf, pts)
        pump(1, lambda: feed.published > 0)
        lc.publish("QRT_PLAN_REQUEST", cf.request(goal, request_id=1).encode())
        moved = pump(10, lambda: any(j.moving for j in joints))
        check(moved, "the arm moves along the plan")
        first = next((p for p in plans if p.status == "ok"), None)
        check(first is not None and abs(first.waypoints_deg[0][0] + 100) < 1,
              "the plan starts at the joints the drives report")

        # stop trials: block the rest of the path while the arm moves
        tip = arm.joints(goal)[0]
        wall = np.vstack([pts, tip[2:] + [0.0, 0.0, 0.0],
                          0.5 * (tip[2] + tip[3])])
        for trial in range(args.trials):
            moving = pump(15, lambda: joints and joints[-1].moving)
            if not moving:
                # (re)start: a clear scan at once lets the daemon plan from
                # here (the feed's next would too)
                feed.set(pts)
                moving = pump(15, lambda: joints and joints[-1].moving)
            if not moving:
                check(False, f"trial {trial}: the arm did not move")
                break
            n_plans = len(plans)
            # the sensor sees the wall from now on: its first scan of it is
            # stamped when the encoded scan goes to LCM, as a sensor driver
            # would publish it (building it in numpy on the emulated CPU
            # takes milliseconds that are not the daemon's), and sent is
            # when it went
            sent = feed.set(wall)
            got = pump(15, lambda: any(p.executing_path_blocked
                                       for p in plans[n_plans:]))
            stopped = pump(15, lambda: joints and not joints[-1].moving and
                           joints[-1].drive_state == "stopped")
            if not (got and stopped):
                check(False, f"trial {trial}: blocked {got}, stopped {stopped}")
                continue
            sent_times.append(sent)
            # recover: clear picture, the next plan executes
            feed.set(pts)
        # (candump writes line by line: stdbuf -oL; a block-buffered capture
        # would not yet hold the stop frames when they are looked for)
        check(len(sent_times) == args.trials,
              f"{len(sent_times)} of {args.trials} trials stopped the arm")
        # the bus goes down for a second while the arm moves, and comes
        # back: the daemon reports it, stays up, brings the drives up again
        # by itself, and the next scan's plan goes on from where they stopped
        feed.set(pts)
        moving = pump(15, lambda: joints and joints[-1].moving)
        check(moving, "the arm is moving before the bus goes down")
        seen = len(statuses)
        subprocess.run(["ip", "link", "set", "vcan0", "down"], check=True)
        pump(1.0)
        subprocess.run(["ip", "link", "set", "vcan0", "up"], check=True)
        pump(5, lambda: any(s.can_bus_errors > 0 for s in statuses[seen:]))
        during = statuses[seen:]
        check(any(s.can_bus_errors > 0 for s in during) and
              any("fault" in s.can_state and "CAN bus error" in s.can_state
                  for s in during),
              "the daemon's status reports the bus: " +
              "; ".join(f"{s.can_state} ({s.can_bus_errors} bus errors)"
                        for s in during[:3]))
        check(daemon.poll() is None, "the daemon is still running")
        n_joints = len(joints)
        again = pump(30, lambda: len(joints) > n_joints and
                     joints[-1].drive_state in ("ready", "stopped"))
        check(again, "the daemon brought the drives up again by itself: " +
              (joints[-1].drive_state if joints else "no joint state"))
        # the errors counted up to now: the status after the drives are up
        # again (at 1 Hz, an earlier one may not have all of them yet)
        n_status = len(statuses)
        pump(3, lambda: len(statuses) > n_status)
        bus_errors = statuses[-1].can_bus_errors if statuses else -1
        # finally to the goal
        feed.set(pts)
        reached = pump(60, lambda: watch.at_rest_at(goal))
        if not reached:  # keep scanning: every scan replans from here
            reached = watch.rescan_until(
                lambda: cf.scan_from_points(pts).encode(),
                lambda: watch.at_rest_at(goal), 20, 3)
        check(reached, f"the arm reached the goal: {list(joints[-1].joints_deg) if joints else None}")
        # the frame counters in the daemon's status (1 Hz): a healthy run
        # loses nothing and reads nothing malformed from servo_sim, but the
        # two short TPDOs sent now are counted, and the arm holds
        for frame in MALFORMED:
            subprocess.run(["cansend", "vcan0", frame], check=True)
        # a status already on its way when the frames went out predates
        # them: wait (status at 1 Hz) for one that has read them, then
        # check that it counts exactly them and nothing else
        seen = len(statuses)
        pump(5, lambda: len(statuses) > seen and
             statuses[-1].can_frames_malformed >= len(MALFORMED))
        st = statuses[-1] if len(statuses) > seen else None
        check(watch.at_rest_at(goal),
              "the arm holds at the goal after the malformed frames")
        check(st is not None and st.can_frames_sent > 0 and
              st.can_frames_received > 0 and
              st.can_frames_malformed == len(MALFORMED) and
              st.can_frames_dropped == 0 and st.can_bus_errors == bus_errors,
              "status counts the CAN frames: " + (
                  f"sent {st.can_frames_sent}, received {st.can_frames_received}, "
                  f"malformed {st.can_frames_malformed}, dropped "
                  f"{st.can_frames_dropped}, unsent {st.can_frames_unsent}, "
                  f"withdrawn {st.can_frames_withdrawn}, bus errors "
                  f"{st.can_bus_errors} (all from the unplugging)"
                  if st else "no status"))
    finally:
        if feed:
            feed.stop()
        stop_daemon_and_drives(daemon, sim)
        drained = drain(capture)
        dump.terminate()
        dump.wait(10)
    check(daemon.returncode == 0, f"clean shutdown (exit {daemon.returncode})")
    check(drained, "candump caught up with the bus (the marker SYNC sent "
          "last is captured)")
    lost = dropped(capture)
    check(lost == 0, f"candump lost {lost} frames")
    # the capture is complete only now (candump runs behind on a busy VM):
    # each blocking scan against the first quick-stop frame after it
    qs = quick_stops(capture)
    for i, sent in enumerate(sent_times):
        nxt = sent_times[i + 1] if i + 1 < len(sent_times) else float("inf")
        after = qs[(qs >= sent - 0.001) & (qs < nxt)]
        if len(after):
            latencies.append((after[0] - sent) * 1e3)
    check(len(latencies) == len(sent_times) > 0,
          f"a quick-stop frame on the bus after each of the {len(sent_times)} "
          f"blocking scans ({len(latencies)} found)")
    q = np.array([j.joints_deg for j in joints])
    c = oracle.clearances(arm, q, pts)
    check(len(q) > 50 and float(c.min()) >= 0.0,
          f"{len(q)} joint states published; every pose collision-free "
          f"(min clearance {c.min():.4f} m)")
    db = cantools.database.load_file(args.dbc)
    bad = total = 0
    with open(capture) as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 3 and "#" in parts[2]:
                if parts[2] in MALFORMED:
                    continue  # sent to be refused
                ident, data = parts[2].split("#", 1)
                total += 1
                try:
                    db.decode_message(int(ident, 16), bytes.fromhex(data))
                except Exception:  # noqa: BLE001
                    bad += 1
    check(total > 0 and bad == 0, f"capture: {total} frames, {bad} do not decode")
    if latencies:
        lat = np.array(latencies)
        line = (f"scan that blocks the executing path -> quick-stop frame on "
                f"the bus: {len(lat)} trials, median {np.median(lat):.1f} ms, "
                f"p99 {np.percentile(lat, 99):.1f} ms, max {lat.max():.1f} ms")
        print(line, flush=True)
        with open(os.path.join(args.out, "stop_latency.txt"), "w") as f:
            f.write(line + "\n")
            f.write("\n".join(f"{v:.3f}" for v in lat) + "\n")
    daemon_log.seek(0)
    log = daemon_log.read()
    check("blocked" in log, "the daemon logged the blocked path")
    # the guard thread (not only the planner thread's replan) stops the arm:
    # its stops are the ones logged with their timing
    guard = re.findall(r"quick stop sent ([0-9.]+) ms after the scan arrived", log)
    check(len(guard) >= 1,
          f"the guard thread sent {len(guard)} of the {len(sent_times)} stops "
          f"(scan arrived -> stop sent: {', '.join(guard[:5])} ms)")
    print(f"{len(failures)} failures, {time.time() - t0:.1f} s", flush=True)
    if failures:
        print(log[-3000:])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
