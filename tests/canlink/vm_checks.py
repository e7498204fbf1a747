"""What the CAN VM tests share: their "ok"/"FAIL" lines, what qrtpland
publishes on LCM, collected as it arrives, and stopping it and the drives."""
import subprocess
import time

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

    def pump(self, seconds, until=None):
        """Handle messages for up to `seconds`, or until until() is true;
        returns until()'s last answer (True without one)."""
        end = time.time() + seconds
        while time.time() < end:
            self.lc.handle_timeout(10)
            if until and until():
                return True
        return until() if until else True


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
