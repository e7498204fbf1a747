#!/usr/bin/env python3
"""The daemon against drives played by an independent CANopen stack.

Run by CTest's `canopen_drive_vm` through tools/vm/run.sh. Three CiA 402
drives are LocalNodes of the PyPI `canopen` package on vcan0 (its SDO
server answers from can/servo_sim.eds, its NMT slave takes the NMT commands
and produces the heartbeat); this file adds only the drive behaviour that
package leaves to the application: the CiA 402 power state machine on the
controlword of RPDO1, the set-point handshake, motion at the profile
velocity the master wrote by SDO, and TPDO1 after every SYNC. qrtpland
--can vcan0 must bring these drives up, plan from the joints they report,
and move them to the goal; so our codec and master are not the only ones
that think our frames are right.
"""
import argparse
import os
import struct
import subprocess
import sys
import threading
import time

import canopen

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [os.path.join(REPO, "tools"), os.path.join(REPO, "tests", "daemon")]
if "--lcmtypes" in sys.argv:
    os.environ["QRT_LCMTYPES_PY"] = sys.argv[sys.argv.index("--lcmtypes") + 1]
import conftest as cf  # noqa: E402
from vm_checks import DaemonWatch, check, failures  # noqa: E402
import lcm  # noqa: E402



# statusword state bits (CiA 402 table 30)
SW = {"switch_on_disabled": 0x0040, "ready": 0x0021, "switched_on": 0x0023,
      "enabled": 0x0027, "quick_stop": 0x0007, "fault": 0x0008}


class Drive:
    """CiA 402 behaviour around a canopen.LocalNode."""

    def __init__(self, network, node_id, eds):
        self.node = canopen.LocalNode(node_id, eds)
        network.add_node(self.node)
        self.network, self.id = network, node_id
        self.state = "switch_on_disabled"
        self.pos = 0.0  # counts
        self.target = 0
        self.moving = False
        self.ack = False
        self.last_cw = 0
        self.cw_seen = set()
        self.setpoints = 0
        self.sdo_writes = []
        self.lock = threading.Lock()
        self.node.add_write_callback(self.on_sdo_write)
        network.subscribe(0x200 + node_id, self.on_rpdo)
        self.node.nmt.send_command(0x80)  # boot-up, pre-operational

    def on_sdo_write(self, index, subindex, od, data):
        self.sdo_writes.append(index)
        if index == 0x6060:  # the mode display follows the mode
            self.node.set_data(0x6061, 0, data, check_writable=False)

    def speed(self):
        v = struct.unpack("<I", self.node.get_data(0x6081, 0))[0]
        return max(float(v), 1.0)

    def on_rpdo(self, can_id, data, timestamp):
        if len(data) != 6:
            return
        cw, target = struct.unpack("<Hi", bytes(data))
        with self.lock:
            self.cw_seen.add(cw & 0x8F)
            st = self.state
            # device control commands, CiA 402 table 30
            if cw & 0x80 and not self.last_cw & 0x80:
                if st == "fault":
                    st = "switch_on_disabled"
            elif cw & 0x82 == 0x00:  # disable voltage
                st = "switch_on_disabled"
                self.moving = False
            elif cw & 0x86 == 0x02:  # quick stop
                st = "quick_stop" if st in ("enabled", "quick_stop") \
                    else "switch_on_disabled"
                self.moving = False
            elif cw & 0x87 == 0x06:  # shutdown
                if st in ("switch_on_disabled", "switched_on", "enabled"):
                    st = "ready"
            elif cw & 0x8F == 0x07:  # switch on / disable operation
                if st in ("ready", "enabled"):
                    st = "switched_on"
            elif cw & 0x8F == 0x0F:  # enable operation
                if st in ("switched_on", "quick_stop"):
                    st = "enabled"
            self.state = st
            if st == "enabled":
                if cw & 0x10 and not self.last_cw & 0x10:  # new set-point
                    self.target = target
                    self.moving = True
                    self.ack = True
                    self.setpoints += 1
                elif not cw & 0x10:
                    self.ack = False
            self.last_cw = cw

    def step(self, dt):
        with self.lock:
            if self.state == "enabled" and self.moving:
                d = self.target - self.pos
                step = self.speed() * dt
                if abs(d) <= step:
                    self.pos = float(self.target)
                    self.moving = False
                else:
                    self.pos += step if d > 0 else -step
            self.node.set_data(0x6064, 0, struct.pack("<i", int(round(self.pos))),
                               check_writable=False)

    def statusword(self):
        with self.lock:
            sw = SW[self.state] | 0x0200  # remote
            if (self.state == "enabled" and not self.moving) or \
                    (self.state != "enabled" and not self.moving):
                sw |= 0x0400  # target reached
            if self.ack:
                sw |= 0x1000
            return sw

    def on_sync(self):
        if self.node.nmt.state == "OPERATIONAL":
            self.network.send_message(
                0x180 + self.id,
                struct.pack("<Hi", self.statusword(), int(round(self.pos))))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--daemon", required=True)
    ap.add_argument("--eds", required=True)
    ap.add_argument("--lcmtypes", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    network = canopen.Network()
    network.connect(interface="socketcan", channel="vcan0")
    drives = [Drive(network, i, args.eds) for i in (1, 2, 3)]
    network.subscribe(0x80, lambda c, d, t: [dr.on_sync() for dr in drives])
    stop = threading.Event()

    # the drives' motion every 10 ms, not 2: these Python threads share an
    # emulated CPU (and the GIL) with the notifier that must answer the
    # daemon's SYNCs and SDOs in time; step() integrates any interval
    def motion():
        last = time.monotonic()
        while not stop.is_set():
            time.sleep(0.010)
            now = time.monotonic()
            for dr in drives:
                dr.step(now - last)
            last = now
    threading.Thread(target=motion, daemon=True).start()

    url = "udpm://239.255.76.67:7778?ttl=0&recv_buf_size=4194304"
    log = open(os.path.join(args.out, "qrtpland.log"), "w+")
    # the VM's CPU is emulated and the drives here are Python threads: on a
    # busy host their heartbeats and SDO answers come late, so the daemon
    # waits 1.5 s (300 ms by default) before it calls a drive lost and 500
    # ms (50) for an SDO answer (seen: "drive did not answer an SDO" at 50)
    daemon = subprocess.Popen([args.daemon, "--lcm-url", url, "--can", "vcan0",
                               "--speed", "60", "--accel", "120",
                               "--heartbeat-timeout", "1500",
                               "--sdo-timeout", "500"],
                              stdout=log, stderr=subprocess.STDOUT)
    lc = lcm.LCM(url)
    watch = DaemonWatch(lc, cf)
    joints, pump = watch.joints, watch.pump

    goal = [60.0, 20.0, -30.0]
    t0 = time.time()
    try:
        up = pump(20, lambda: joints and joints[-1].drive_state == "ready")
        check(up, f"qrtpland brought the canopen drives to Operation Enabled "
              f"({time.time() - t0:.1f} s)")
        check(all(d.state == "enabled" for d in drives),
              f"drive states: {[d.state for d in drives]}")
        check(all({0x06, 0x07, 0x0F} <= d.cw_seen for d in drives),
              "each drive saw shutdown, switch on and enable operation")
        check(all(d.node.nmt.state == "OPERATIONAL" for d in drives),
              "NMT start reached every node")
        check(all({0x1017, 0x6060} <= set(d.sdo_writes) for d in drives),
              "heartbeat time and profile position mode written by SDO")
        scene, pts = cf.scene_points("table4_one_sphere.json")
        lc.publish("QRT_SCAN", cf.scan_from_points(pts).encode())
        lc.publish("QRT_PLAN_REQUEST", cf.request(goal, request_id=1).encode())
        done = pump(60, lambda: all(abs(d.pos / 1000.0 - g) < 0.01
                                    for d, g in zip(drives, goal)) and
                    joints and not joints[-1].moving)
        check(done, "the drives reached the goal: "
              f"{[round(d.pos / 1000.0, 3) for d in drives]}")
        check(all(d.setpoints >= 1 for d in drives),
              f"set-point handshakes: {[d.setpoints for d in drives]}")
        check(all({0x6081, 0x6083, 0x6084} <= set(d.sdo_writes) for d in drives),
              "profile velocity, acceleration and deceleration written per segment")
    finally:
        daemon.terminate()
        try:
            daemon.wait(15)
        except subprocess.TimeoutExpired:
            daemon.kill()
        # the daemon's last frames are on the bus when it exits, but the
        # canopen notifier thread may not have handed them to the drives
        # yet: give it time before the bus is closed (seen on a busy host)
        settle = time.time() + 5.0
        while time.time() < settle and not all(d.state == "quick_stop"
                                                for d in drives):
            time.sleep(0.05)
        stop.set()
        network.disconnect()
    check(daemon.returncode == 0, f"clean shutdown (exit {daemon.returncode})")
    check(all(d.state == "quick_stop" for d in drives),
          f"the daemon left the drives holding in quick stop: {[d.state for d in drives]}")
    print(f"{len(failures)} failures, {time.time() - t0:.1f} s", flush=True)
    if failures:
        log.seek(0)
        print(log.read()[-3000:])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
