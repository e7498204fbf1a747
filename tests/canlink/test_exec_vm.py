#!/usr/bin/env python3
"""The whole loop on a real SocketCAN bus: plan -> CiA 402 master -> drives.

Run by CTest's `can_exec_vm` through tools/vm/run.sh (inside a VM when this
host's kernel has no CAN). On vcan0:
  1. servo_sim powers up at the paper's Table 4 start (-100, 0, 0);
     `qrtplan plan` plans Table 4; `qrtplan-exec` brings the drives up and
     executes the plan. The joints read back from the drives' PDOs during the
     motion (--trace) must stay on the planned segments, collide with no
     point (the independent oracle, tools/oracle.py, on every traced pose),
     cross +-180 the short way, and end at the goal.
  2. A drive fault injected in the middle of a move: qrtplan-exec reports
     the drive and the EMCY code and exits 1, and the capture shows the
     quick stop (controlword 0x0002) to every drive after the EMCY.
  3. The interface goes down in the middle of a move and comes back: the
     master reports the bus, nothing crashes; then a new plan from where the
     arm stopped executes to the goal (recovery).
  4. Drives with their own counts per degree and counts at 0 degrees each
     (--counts-per-deg X,Y,Z and --offset-counts A,B,C on servo_sim and
     qrtplan-exec): the arm is read where it stands and a plan from there
     executes to its goal.
  5. Every frame of every capture decodes with can/qrtplan.dbc (cantools).
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time

import cantools
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "tools"))
import oracle  # noqa: E402
from candump_capture import drain, dropped, start  # noqa: E402
from vm_checks import check, failures, joint_gap  # noqa: E402

SERVO_ERROR = 5  # counts = 0.005 deg at 1000 counts/deg


class Bus:
    """servo_sim and a candump capture on vcan0 for one scenario."""

    def __init__(self, args, name, sim_extra):
        self.args, self.name = args, name
        self.capture = os.path.join(args.out, name + ".candump")
        # candump listening before anything happens on the bus
        self.dump = start(self.capture)
        log = open(os.path.join(args.out, name + ".servo_sim.log"), "w")
        cmd = [args.servo_sim, "--iface", "vcan0", "--servo-error",
               str(SERVO_ERROR), "--watchdog-ms", "400", "--verbose"] + sim_extra
        print("$ " + " ".join(cmd), flush=True)
        self.sim = subprocess.Popen(cmd, stdout=log, stderr=log)
        time.sleep(0.3)

    def close(self):
        self.sim.terminate()
        self.sim.wait(10)
        check(drain(self.capture), f"{self.name}: candump caught up with the "
              "bus (the marker SYNC sent last is captured)")
        lost = dropped(self.capture)
        check(lost == 0, f"{self.name}: candump lost {lost} frames")
        self.dump.terminate()
        try:
            self.dump.wait(10)
        except subprocess.TimeoutExpired:
            self.dump.kill()


def plan(args, scene, out):
    r = subprocess.run([args.qrtplan, "plan", scene, "-o", out],
                       capture_output=True, text=True)
    check(r.returncode == 0, f"qrtplan plan {os.path.basename(scene)}: "
          f"{r.stderr.strip()}")
    with open(out) as f:
        return json.load(f)


def execute(args, plan_path, trace, extra=(), timeout=120):
    # emulated CPU, busy host: heartbeats may come late (default 300 ms)
    cmd = [args.exec, "--can", "vcan0", plan_path, "--trace", trace,
           "--speed", "90", "--accel", "180", "--timeout", "60",
           "--heartbeat-timeout", "1500", *extra]
    print("$ " + " ".join(cmd), flush=True)
    return subprocess.Popen(cmd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def wait_for_motion(trace, proc, timeout=60.0):
    """True once the trace (written in 4 KiB blocks) shows a moving row;
    False if the executor ends or the time runs out first."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and proc.poll() is None:
        try:
            with open(trace) as f:
                if ",moving," in f.read():
                    return True
        except FileNotFoundError:
            pass
        time.sleep(0.05)
    return False


def read_trace(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    q = np.array([[float(r["alpha_deg"]), float(r["sigma_deg"]),
                   float(r["eta_deg"])] for r in rows])
    return q, [r["state"] for r in rows]


def off_path(q, waypoints):
    """Distance (deg) of each pose from the planned polyline (alpha short way)."""
    best = np.full(len(q), np.inf)
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        a = np.asarray(a, float)
        d = np.asarray(b, float) - a
        d[0] = oracle.wrap180(d[0])
        p = q - a
        p[:, 0] = oracle.wrap180_array(p[:, 0])
        t = np.clip(p @ d / max(d @ d, 1e-12), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(p - t[:, None] * d, axis=1))
    return best


def decodes(args, capture):
    db = cantools.database.load_file(args.dbc)
    bad = total = 0
    with open(capture) as f:
        for line in f:
            parts = line.split()
            if len(parts) < 3 or "#" not in parts[2]:
                continue
            ident, data = parts[2].split("#", 1)
            total += 1
            try:
                db.decode_message(int(ident, 16), bytes.fromhex(data))
            except Exception:  # noqa: BLE001 - any failure counts
                bad += 1
    check(total > 0 and bad == 0,
          f"{os.path.basename(capture)}: {total} frames, {bad} do not decode")


def frames(capture):
    with open(capture) as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 3 and "#" in parts[2]:
                ident, data = parts[2].split("#", 1)
                yield int(ident, 16), bytes.fromhex(data)


def scenario_table4(args):
    scene_path = os.path.join(REPO, "scenes", "table4_one_sphere.json")
    with open(scene_path) as f:
        scene = json.load(f)
    plan_path = os.path.join(args.out, "table4.plan.json")
    p = plan(args, scene_path, plan_path)
    wps = p["waypoints_deg"]
    bus = Bus(args, "table4", ["--start-deg", "-100,0,0"])
    try:
        trace = os.path.join(args.out, "table4.trace.csv")
        proc = execute(args, plan_path, trace)
        out, err = proc.communicate(timeout=120)
        print(out + err, flush=True)
        check(proc.returncode == 0, f"qrtplan-exec Table 4: exit {proc.returncode}")
    finally:
        bus.close()
    q, states = read_trace(trace)
    moving = np.array([s == "moving" for s in states])
    check(moving.sum() > 50, f"{moving.sum()} poses traced while moving")
    dist = off_path(q[moving], wps)
    # the drives take their set-points from three frames in a row; the
    # simulator hands every frame already received to the drives before
    # they move on, so none starts a tick late: 0.012-0.015 deg measured
    # on an idle machine, 0.093 deg with three CPU hogs beside the VM
    # (0.043-0.054 and 0.40 deg when a tick could fall between the three
    # frames; 0.73 deg once in CI). The bound here is a sanity bound
    # (0.5 deg: 8 mm at full reach, inside the 10 mm margin); the
    # synchronisation itself is pinned down in tests/canmaster (0.05 deg),
    # and the oracle below checks what matters: no pose collides.
    check(float(dist.max()) < 0.5,
          f"the drives stayed within {dist.max():.4f} deg of the planned "
          f"segments (limit 0.5)")
    arm = oracle.Arm(scene)
    c = oracle.clearances(arm, q, oracle.scene_points(scene))
    check(float(c.min()) >= 0.0,
          f"every traced pose is collision-free (oracle): min clearance "
          f"{c.min():.4f} m over {len(q)} poses")
    check(joint_gap(q[-1], wps[-1]) < 0.02, f"ends at the goal: {q[-1].tolist()}")
    # the short way across +-180: alpha never passes through 0
    check(bool(np.all(np.abs(q[:, 0]) > 90.0)),
          "alpha crossed +-180, not 0 (min |alpha| "
          f"{np.abs(q[:, 0]).min():.1f})")
    decodes(args, bus.capture)


def scenario_fault(args):
    scene_path = os.path.join(REPO, "scenes", "table4_one_sphere.json")
    plan_path = os.path.join(args.out, "table4.plan.json")
    bus = Bus(args, "fault", ["--start-deg", "-100,0,0", "--fault-at", "2.0",
                              "--fault-node", "2", "--fault-code", "0x2310"])
    try:
        proc = execute(args, plan_path, os.path.join(args.out, "fault.trace.csv"))
        out, err = proc.communicate(timeout=120)
        print(out + err, flush=True)
    finally:
        bus.close()
    check(proc.returncode == 1, f"exit 1 on a drive fault (got {proc.returncode})")
    check("drive fault (node 2, code 0x2310)" in err,
          "the fault names node 2 and EMCY 0x2310")
    seen_emcy = False
    stopped = set()
    for ident, data in frames(bus.capture):
        if ident == 0x082 and len(data) == 8 and data[0:2] == b"\x10\x23":
            seen_emcy = True
        if seen_emcy and 0x201 <= ident <= 0x203 and len(data) == 6 and \
                data[0] == 0x02 and data[1] == 0x00:
            stopped.add(ident - 0x200)
    check(seen_emcy, "EMCY 0x2310 from node 2 on the bus")
    check(stopped == {1, 2, 3},
          f"quick stop (controlword 0x0002) to every drive after it: {sorted(stopped)}")
    decodes(args, bus.capture)
    del scene_path


def scenario_unplug(args):
    scene_path = os.path.join(REPO, "scenes", "table4_one_sphere.json")
    plan_path = os.path.join(args.out, "table4.plan.json")
    bus = Bus(args, "unplug", ["--start-deg", "-100,0,0"])
    try:
        trace = os.path.join(args.out, "unplug.trace.csv")
        # a third of the speed, and the bus taken down once the trace shows
        # the arm moving: a fixed 2 s after the start missed the motion
        # when the host was busy (the emulated guest's `ip` ran after the
        # arm had arrived, 3.3 s into the trace)
        if os.path.exists(trace):  # a last run's must not be read as this
            os.remove(trace)
        proc = execute(args, plan_path, trace, extra=("--speed", "30"))
        check(wait_for_motion(trace, proc),
              "the arm is moving before the bus goes down")
        subprocess.run(["ip", "link", "set", "vcan0", "down"], check=True)
        time.sleep(1.0)
        subprocess.run(["ip", "link", "set", "vcan0", "up"], check=True)
        out, err = proc.communicate(timeout=120)
        print(out + err, flush=True)
        check(proc.returncode == 1, f"exit 1 when the bus went down (got "
              f"{proc.returncode})")
        check("down" in err or "bus" in err.lower() or "heartbeat" in err,
              "the reason names the bus or the lost drives")
        # recovery: ask the drives where the arm stands (it coasted on
        # until their watchdogs stopped it), plan from there, and go on
        time.sleep(1.0)
        r = subprocess.run([args.exec, "--can", "vcan0", "--where"],
                           capture_output=True, text=True, timeout=60)
        check(r.returncode == 0, f"qrtplan-exec --where: {r.stderr.strip()}")
        here = json.loads(r.stdout)
        with open(scene_path) as f:
            scene = json.load(f)
        scene["start"] = {"joints_deg": [round(v, 6) for v in here]}
        again_scene = os.path.join(args.out, "recover.scene.json")
        with open(again_scene, "w") as f:
            json.dump(scene, f)
        again_plan = os.path.join(args.out, "recover.plan.json")
        p = plan(args, again_scene, again_plan)
        check(p["status"] == "ok", f"a plan from {here}: {p['status']}")
        trace2 = os.path.join(args.out, "recover.trace.csv")
        proc = execute(args, again_plan, trace2)
        out, err = proc.communicate(timeout=120)
        print(out + err, flush=True)
        check(proc.returncode == 0, f"after recovery the next plan executes "
              f"(exit {proc.returncode})")
        q2, _ = read_trace(trace2)
        c = oracle.clearances(oracle.Arm(scene), q2, oracle.scene_points(scene))
        check(float(c.min()) >= 0.0, f"the recovery motion is collision-free "
              f"(min clearance {c.min():.4f} m)")
    finally:
        bus.close()
    decodes(args, bus.capture)


def scenario_scales(args):
    """Drives geared differently on each joint (1000, 2000 and 500 counts a
    degree) whose encoders read 5000, -20000 and 0 counts at the joints' 0
    degrees: read with one scale for all and no offsets, the joints the
    drives power up at are (-95, 0, -10), not (-100, 10, -20); with the
    drives' own scales and offsets the arm is where it stands and a plan
    from there reaches its goal."""
    drive = ["--counts-per-deg", "1000,2000,500",
             "--offset-counts", "5000,-20000,0"]
    bus = Bus(args, "scales", ["--start-deg", "-100,10,-20", *drive])
    try:
        here = {}
        for name, given in (("plain", []), ("own", drive)):
            r = subprocess.run([args.exec, "--can", "vcan0", "--where",
                                "--heartbeat-timeout", "1500", *given],
                               capture_output=True, text=True, timeout=60)
            check(r.returncode == 0, f"--where {' '.join(given)}: "
                  f"{r.stderr.strip()}")
            here[name] = json.loads(r.stdout) if r.returncode == 0 else None
        check(here["plain"] is not None and
              np.allclose(here["plain"], [-95, 0, -10], atol=0.02),
              f"one scale for all, no offsets, reads {here['plain']}: the "
              "test can fail")
        check(here["own"] is not None and
              np.allclose(here["own"], [-100, 10, -20], atol=0.02),
              f"each joint's own scale and offset reads {here['own']}")
        scene = {"version": 1, "points": [[0.0, 0.9, 0.5]],
                 "start": {"joints_deg": [-100, 10, -20]},
                 "goal": {"joints_deg": [-60, 40, -50]}}
        scene_path = os.path.join(args.out, "scales.scene.json")
        with open(scene_path, "w") as f:
            json.dump(scene, f)
        plan_path = os.path.join(args.out, "scales.plan.json")
        p = plan(args, scene_path, plan_path)
        trace = os.path.join(args.out, "scales.trace.csv")
        proc = execute(args, plan_path, trace, extra=drive)
        out, err = proc.communicate(timeout=120)
        print(out + err, flush=True)
        check(proc.returncode == 0, f"qrtplan-exec with per-joint scales and "
              f"offsets: "
              f"exit {proc.returncode}")
        q, _ = read_trace(trace)
        end = q[-1] - np.asarray(p["waypoints_deg"][-1], float)
        check(float(np.abs(end).max()) < 0.02,
              f"ends at the goal: {q[-1].tolist()}")
    finally:
        bus.close()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--servo-sim", required=True)
    ap.add_argument("--exec", required=True)
    ap.add_argument("--qrtplan", required=True)
    ap.add_argument("--dbc", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    t0 = time.monotonic()
    for scenario in (scenario_table4, scenario_fault, scenario_unplug,
                     scenario_scales):
        print(f"== {scenario.__name__}", flush=True)
        try:
            scenario(args)
        except Exception as e:  # noqa: BLE001 - report and go on
            check(False, f"{scenario.__name__} raised {e!r}")
    print(f"{len(failures)} failures, {time.monotonic() - t0:.1f} s", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
