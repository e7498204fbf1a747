"""What the CAN VM tests share: their "ok"/"FAIL" lines, what qrtpland
publishes on LCM, collected as it arrives, how far a pose is from a goal,
and stopping it and the drives. (The importer puts tools/ on sys.path.)"""
import subprocess
import time

import oracle

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


class DaemonWatch:
    """qrtpland's joint states, plans and statuses on the LCM instance lc,
    decoded with the generated types in `types` (tests/daemon/conftest), as
    pump() handles them."""

    def __init__(self, lc, types):
        self.lc = lc
        self.joints, self.plans, self.statuses = [], [], []
        lc.subscribe("QRT_JOINT_STATE", lambda c, d: self.joints.append(
            types.joint_state_t.decode(d)))
        lc.subscribe("QRT_PLAN", lambda c, d: self.plans.append(
            types.plan_t.decode(d)))
        lc.subscribe("QRT_STATUS", lambda c, d: self.statuses.append(
            types.daemon_status_t.decode(d)))

    def at_rest_at(self, goal):
        """Whether the last joint state is at rest within 0.05 deg of goal."""
        return (bool(self.joints) and not self.joints[-1].moving and
                joint_gap(self.joints[-1].joints_deg, goal) < 0.05)

    def pump(self, seconds, until=None):
        """Handle messages for up to `seconds`, or until until() is true;
        returns until()'s last answer (True without one)."""
        end = time.time() + seconds
        while time.time() < end:
            self.lc.handle_timeout(10)
            if until and until():
                return True
        return until() if until else True

    def rescan_until(self, scan, until, tries, seconds):
        """Publish a fresh scan, scan() encoded (every scan replans from
        where the arm is), and pump for `seconds`, up to `tries` times,
        until until() is true; returns whether it became true."""
        for _ in range(tries):
            self.lc.publish("QRT_SCAN", scan())
            if self.pump(seconds, until):
                return True
        return False


def joint_gap(a, b):
    """The largest joint difference between two poses, in degrees (alpha
    wraps)."""
    return max(abs(oracle.wrap180(a[0] - b[0])), abs(a[1] - b[1]),
               abs(a[2] - b[2]))


def stop_daemon_and_drives(daemon, sim):
    """SIGTERM to qrtpland (it leaves the drives holding), killed if it has
    not exited in 15 s; then servo_sim."""
    daemon.terminate()
    try:
        daemon.wait(15)
    except subprocess.TimeoutExpired:
        daemon.kill()
    sim.terminate()
    sim.wait(10)
