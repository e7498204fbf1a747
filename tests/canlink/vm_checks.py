"""What the CAN VM tests share: their "ok"/"FAIL" lines, what qrtpland
publishes on LCM, collected as it arrives, a sensor that keeps scanning
(ScanFeed), how far a pose is from a goal, what a candump capture says
about the drives, and stopping the daemon and the drives. (The importer
puts tools/ and tests/daemon/ on sys.path.)"""
import os
import subprocess
import threading
import time

import lcm
import numpy as np

import oracle

failures = []

# A sanitizer build (the suites set ASAN_OPTIONS or TSAN_OPTIONS) on the
# emulated CPU is one to two orders slower than the shipped daemon.
SANITIZED = "ASAN_OPTIONS" in os.environ or "TSAN_OPTIONS" in os.environ
# Under ThreadSanitizer its planner thread was seen to take most of a
# second per scan (the plan and the certification of its clearance), so a
# plan reached the hand-over on a scan 0.65 to 1.1 s old and was rightly
# refused (the arm never moved), and certifying one plan kept the thread
# from its loop for over the 2 s planner deadline, so the host watchdog
# stopped the arm. These runs give evidence 1.5 s and the planner 10 s,
# as they give heartbeats 1.5 s; the shipped 0.5 s and 2 s hold in the
# release suite, and failsafe_watchdog_vm trips the deadline on purpose.
SANITIZER_ARGS = (["--max-scan-age", "1.5", "--planner-deadline", "10000"]
                  if SANITIZED else [])


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


# The senders the VM tests sign as (qrtpland --keys): trust() makes their
# keys; from then on signing_lcm() and every ScanFeed sign what they publish.
_SIGNERS = None
SENDERS = (("op", "operator"), ("s0", "sensor"), ("s1", "sensor"),
           ("front", "sensor"), ("side", "sensor"), ("rogue", "sensor"))


def trust(daemon_bin, out):
    """Keys for SENDERS in out/keys; returns qrtpland's --keys arguments."""
    import qrtauth  # needs the generated types, which test_exec_vm lacks
    key_dir = os.path.join(out, "keys")
    sign_as(qrtauth.gen_keys(daemon_bin, key_dir, SENDERS))
    return ["--keys", key_dir]


def sign_as(signers):
    """From now on signing_lcm() and every ScanFeed sign with these
    qrtauth.Signer keys."""
    global _SIGNERS
    _SIGNERS = list(signers)


class SigningLCM:
    """An lcm.LCM whose publish() signs as the trusted senders do."""

    def __init__(self, url):
        import qrtauth
        self._lc = lcm.LCM(url)
        self._signed = qrtauth.SignedPublisher(self._lc, _SIGNERS)

    def publish(self, channel, data):
        self._signed.publish(channel, data)

    def __getattr__(self, name):
        return getattr(self._lc, name)


def signing_lcm(url):
    """An LCM instance that signs (after trust()), else a plain one."""
    return SigningLCM(url) if _SIGNERS else lcm.LCM(url)


class ScanFeed:
    """A sensor that keeps scanning: the current scene as a range scan
    (conftest.scan_from_points with the generated types in `types`),
    stamped afresh and published every `period` seconds, as a sensor driver
    would. qrtpland takes a scan as evidence for --max-scan-age only (0.5 s
    by default): one scan and then silence stops the arm.

    It publishes from its own thread on its own LCM instance (an LCM object
    must not publish in one thread while another handles on it); the
    caller's instance stays the caller's. points None or empty: scans with
    no returns (evidence of free space within max_range)."""

    def __init__(self, url, types, points=None, sensor="s0", period=0.1,
                 channel="QRT_SCAN"):
        self.types, self.sensor, self.period = types, sensor, period
        self.channel = channel
        self.lc = signing_lcm(url)
        self.lock = threading.Lock()  # the message, the instance, the stamps
        self.published = 0
        self.last_utime = None  # stamp of the newest scan published (us)
        self.last_sent = None   # time.time() when it was published
        self.msg = self._make(points)
        self.next = time.time()
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True,
                                       name="scan feed " + sensor)
        self.thread.start()

    def _make(self, points):
        pts = np.zeros((0, 3)) if points is None else \
            np.asarray(points, float).reshape(-1, 3)
        return self.types.scan_from_points(pts, sensor=self.sensor)

    def _publish(self):
        # caller holds the lock; stamped as the encoded scan goes to LCM
        self.msg.utime = self.types.now_us()
        data = self.msg.encode()
        self.lc.publish(self.channel, data)
        self.last_sent = time.time()
        self.last_utime = self.msg.utime
        self.published += 1
        self.next = self.last_sent + self.period

    def _run(self):
        while not self.stopping.is_set():
            with self.lock:
                if self.stopping.is_set():
                    break
                if time.time() >= self.next:
                    self._publish()
                wait = self.next - time.time()
            self.stopping.wait(max(0.001, min(wait, self.period)))

    def set(self, points):
        """Show `points` from now on: published at once (the period starts
        again from here). Returns the time.time() of that publication."""
        msg = self._make(points)  # built outside the lock: numpy takes time
        with self.lock:
            self.msg = msg
            if not self.stopping.is_set():
                self._publish()
            return self.last_sent

    def stop(self):
        """The sensor goes silent: nothing is published after this returns.
        Returns the stamp (us) of the last scan published, None if none."""
        with self.lock:
            self.stopping.set()
        self.thread.join(5)
        return self.last_utime


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


# --- what a candump -L capture says (candump_capture.start) ----------------

MASTER_HEARTBEAT = 0x700 + 127  # the master's node id is 127


def read_capture(capture):
    """The frames of a candump -L capture, in order: (time, COB-ID, data)
    with the kernel's receive time (CLOCK_REALTIME seconds, as time.time())."""
    out = []
    with open(capture) as f:
        for line in f:
            parts = line.split()
            if len(parts) < 3 or "#" not in parts[2] or \
                    not parts[0].startswith("("):
                continue
            ident, data = parts[2].split("#", 1)
            if data.startswith("R"):
                continue  # remote frames carry no data
            try:
                out.append((float(parts[0].strip("()")), int(ident, 16),
                            bytes.fromhex(data)))
            except ValueError:
                continue
    return out


def quick_stop_frames(frames, nodes=(1, 2, 3)):
    """(time, node) of every RPDO1 whose controlword is the CiA 402 quick
    stop command (bits 7, 2, 1 = 0, 0, 1: cw & 0x86 == 0x02)."""
    out = []
    for t, ident, data in frames:
        node = ident - 0x200
        if node in nodes and len(data) >= 2 and \
                int.from_bytes(data[:2], "little") & 0x86 == 0x02:
            out.append((t, node))
    return out


def quick_stop_onsets(frames, nodes=(1, 2, 3)):
    """(time, node) of the quick-stop RPDO1s that start a stop: the node's
    RPDO1 before was something else. (A stopped master repeats the quick
    stop controlword after every SYNC until the next path.)"""
    out, last = [], {}
    stops = set(quick_stop_frames(frames, nodes))
    for t, ident, data in frames:
        node = ident - 0x200
        if node not in nodes or len(data) < 2:
            continue
        qs = (t, node) in stops
        if qs and last.get(node) is False:
            out.append((t, node))
        last[node] = qs
    return out


def tpdo_poses(frames, counts_per_deg=(1000.0,) * 3, offset_counts=(0,) * 3,
               nodes=(1, 2, 3)):
    """The drives' own positions, densely: their TPDO1s (statusword,
    position actual in counts) after every SYNC, as joint degrees with each
    drive's scale and counts at 0 degrees (alpha wrapped). One pose per
    TPDO1 once every drive has sent one. Returns (times, poses (N, 3),
    statuswords (N, 3))."""
    last_pos, last_sw = [None] * 3, [None] * 3
    ts, qs, sws = [], [], []
    for t, ident, data in frames:
        if ident - 0x180 not in nodes or len(data) != 6:
            continue
        j = nodes.index(ident - 0x180)
        last_sw[j] = int.from_bytes(data[:2], "little")
        last_pos[j] = int.from_bytes(data[2:6], "little", signed=True)
        if None in last_pos:
            continue
        q = [(last_pos[k] - offset_counts[k]) / counts_per_deg[k]
             for k in range(3)]
        q[0] = oracle.wrap180(q[0])
        ts.append(t)
        qs.append(q)
        sws.append(list(last_sw))
    return np.array(ts), np.array(qs).reshape(-1, 3), np.array(sws).reshape(-1, 3)


def quick_stop_active(statusword):
    """CiA 402: Quick Stop Active is xxxx xxxx x00x 0111."""
    return statusword & 0x006F == 0x0007


def switch_on_disabled(statusword):
    """CiA 402: Switch On Disabled is xxxx xxxx x1xx 0000."""
    return statusword & 0x004F == 0x0040
