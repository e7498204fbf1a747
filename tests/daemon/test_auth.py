"""Only trusted senders change what the arm does (docs/security.md): the
real daemon on loopback LCM, messages authenticated (or not) in Python with
PyNaCl.
CTest runs each test as auth_<name> (src/daemon/CMakeLists.txt)."""
import os
import subprocess
import time

import lcm
import pytest
import qrtauth
from conftest import (DAEMON, joint_state_t, request, scan_from_points,
                      scene_points)

OPERATOR, SENSOR = ("op", "operator"), ("s0", "sensor")
KEYS = [OPERATOR, SENSOR, ("s1", "sensor"), ("drives", "joints")]


def signers_by_name(c):
    return c.signed.by_name


def plan_for(c, rid, timeout=10.0):
    return c.wait_plan(lambda p: p.request_id == rid, timeout=timeout)


def test_authenticated_messages_are_planned(daemon):
    d, c = daemon(keys=KEYS)
    scene, pts = scene_points("ten_spheres.json")
    c.publish("QRT_SCAN", scan_from_points(pts, position=(0.0, 0.0, 0.5)))
    c.publish("QRT_PLAN_REQUEST", request(scene["goal"]["joints_deg"],
                                          start=scene["start"]["joints_deg"],
                                          request_id=1))
    p = plan_for(c, 1, timeout=20)
    assert p is not None, d.text()
    assert p.status == "ok" and p.points == len(pts), p.detail
    st = c.wait_status(lambda s: s.messages_authenticated >= 2)
    assert st.lcm_input == "authenticated"
    assert st.messages_authenticated >= 2 and st.messages_unsigned == 0
    trusted = ("trusted senders: drives (joints), op (operator), s0 (sensor), "
               "s1 (sensor)")
    assert trusted in d.wait_text(trusted)


def test_refusals_are_counted_and_the_daemon_keeps_serving(daemon, tmp_path):
    d, c = daemon(keys=KEYS)
    keys = signers_by_name(c)
    op, s0, s1 = keys["op"], keys["s0"], keys["s1"]
    lc = c.lc
    # an obstacle picture from the real sensor: a sphere between start and
    # goal, so that erasing it would change the plan
    scene, pts = scene_points("table4_one_sphere.json")
    c.publish("QRT_SCAN", scan_from_points(pts))
    c.publish("QRT_PLAN_REQUEST", request([100, 0, 0], start=[-100, 0, 0],
                                          request_id=1))
    first = plan_for(c, 1)
    assert first is not None and first.status == "ok", d.text()

    # each attack of the issue, one refusal reason each; at the log's
    # sustained rate (2 lines/s), so that every refusal is logged
    def send(channel, data):
        lc.publish(channel, data)
        time.sleep(0.5)

    # unsigned: a request and an empty scan under the real sensor's id
    send("QRT_PLAN_REQUEST", request([0, 90, 0], request_id=2).encode())
    send("QRT_SCAN", scan_from_points(pts[:0]).encode())
    # unknown sender: a key the daemon does not have
    mallory = qrtauth.gen_keys(DAEMON, str(tmp_path / "other"),
                               [("mallory", "operator"), ("op", "operator")])
    send("QRT_PLAN_REQUEST", mallory[0].seal(
        "QRT_PLAN_REQUEST", request([0, 90, 0], request_id=3).encode()))
    # wrong key: the name of a trusted sender, another key
    send("QRT_PLAN_REQUEST", mallory[1].seal(
        "QRT_PLAN_REQUEST", request([0, 90, 0], request_id=4).encode()))
    # a sensor key sending a request; a sensor key sending another's scan
    send("QRT_PLAN_REQUEST", s0.seal(
        "QRT_PLAN_REQUEST", request([0, 90, 0], request_id=5).encode()))
    send("QRT_SCAN", s1.seal("QRT_SCAN", scan_from_points(pts[:0]).encode()))
    # replayed: the same bytes again (the first copy is taken)
    sealed = op.seal("QRT_PLAN_REQUEST", request([100, 0, 0], start=[-100, 0, 0],
                                                 request_id=6).encode())
    send("QRT_PLAN_REQUEST", sealed)
    assert plan_for(c, 6) is not None, d.text()
    send("QRT_PLAN_REQUEST", sealed)
    # tampered: one byte of the goal flipped after signing
    t = bytearray(op.seal("QRT_PLAN_REQUEST", request([0, 90, 0], request_id=7)
                          .encode()))
    t[-40 - 10] ^= 0x01
    send("QRT_PLAN_REQUEST", bytes(t))
    # signed for another channel (a scan replayed onto a sensor channel)
    send("QRT_SCAN_x", s0.seal("QRT_SCAN", scan_from_points(pts[:0]).encode()))
    # malformed: truncated; trailing bytes; a payload size that lies
    send("QRT_PLAN_REQUEST", sealed[:40])
    send("QRT_PLAN_REQUEST", op.seal("QRT_PLAN_REQUEST",
                                           request([0, 90, 0]).encode()) + b"x")
    # counter ahead of the daemon's clock by a second
    send("QRT_PLAN_REQUEST", op.seal(
        "QRT_PLAN_REQUEST", request([0, 90, 0], request_id=8).encode(),
        counter=time.time_ns() // 1000 + 1_000_000))
    st = c.wait_status(lambda s: s.auth_malformed >= 2 and s.auth_replayed >= 2
                       and s.auth_not_permitted >= 2 and s.auth_bad_mac >= 2
                       and s.auth_unsigned >= 2 and s.auth_unknown_sender >= 1
                       and s.auth_counter_ahead >= 1)
    assert st is not None, d.text()
    assert (st.auth_unsigned, st.auth_unknown_sender, st.auth_bad_mac,
            st.auth_not_permitted, st.auth_replayed, st.auth_malformed,
            st.auth_counter_ahead) == (2, 1, 2, 2, 2, 2, 1), d.text()
    expected = ("refused (unsigned)", "'mallory' has no key",
                "MAC of 'op' does not verify", "'s0' is a sensor key",
                "sensor key 's1' sent a scan of sensor 's0'", "did not grow",
                "signed it for channel QRT_SCAN", "does not match the",
                "ahead of this computer's clock")
    log = d.wait_text(*expected)
    for what in expected:
        assert what in log, what
    # none of them made a plan or changed the picture
    refused = {2, 3, 4, 5, 7, 8}
    assert not [p for _, p in c.plans if p.request_id in refused]
    # still serving, and the sphere is still there: a fresh signed request
    # plans around it exactly as before
    c.publish("QRT_SCAN", scan_from_points(pts))
    c.publish("QRT_PLAN_REQUEST", request([100, 0, 0], start=[-100, 0, 0],
                                          request_id=9))
    p = plan_for(c, 9)
    assert p is not None and p.status == "ok", d.text()
    assert p.points == first.points
    assert [list(w) for w in p.waypoints_deg] == [list(w) for w in first.waypoints_deg]
    assert d.proc.poll() is None


def test_joint_states_need_the_joints_key(daemon):
    d, c = daemon(keys=KEYS)
    lc = c.lc
    js = joint_state_t()
    js.joints_deg = [30.0, 10.0, 0.0]
    js.drive_state = "external"
    lc.publish("QRT_JOINT_STATE", js.encode())  # unsigned: refused
    lc.publish("QRT_JOINT_STATE", c.signed.by_name["op"].seal(
        "QRT_JOINT_STATE", js.encode()))  # operator key: not permitted
    st = c.wait_status(lambda s: s.auth_unsigned >= 1 and s.auth_not_permitted >= 1)
    assert st is not None, d.text()
    c.publish("QRT_SCAN", scan_from_points([[0.5, 0.5, 0.5]]))
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], request_id=1))
    p = plan_for(c, 1)
    assert p is not None and p.status == "invalid_request", d.text()  # no start
    js.joints_deg = [-30.0, 20.0, 5.0]
    c.publish("QRT_JOINT_STATE", js)  # signed with the joints key
    time.sleep(0.3)
    c.publish("QRT_SCAN", scan_from_points([[0.5, 0.5, 0.5]]))
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], request_id=2))
    p = plan_for(c, 2)
    assert p is not None and p.status == "ok", d.text()
    assert list(p.start_deg) == [-30.0, 20.0, 5.0]


def test_without_keys_unsigned_input_is_taken_and_the_status_says_so(daemon):
    d, c = daemon()
    c.publish("QRT_SCAN", scan_from_points([[0.5, 0.5, 0.5]]))
    c.publish("QRT_PLAN_REQUEST", request([90, 0, 0], start=[-90, 0, 0]))
    assert c.wait_plan(lambda p: p.status == "ok") is not None, d.text()
    st = c.wait_status(lambda s: s.messages_unsigned >= 2)
    assert st.lcm_input == "unsigned accepted" and st.messages_authenticated == 0
    assert "no --keys: unsigned LCM messages are taken" in \
        d.wait_text("no --keys: unsigned LCM messages are taken")


def run_daemon(*args, timeout=20):
    return subprocess.run([DAEMON, "--lcm-url", "udpm://239.255.76.67:7699?ttl=0",
                           *args], capture_output=True, text=True, timeout=timeout)


def test_can_without_keys_refuses_to_start(tmp_path):
    r = run_daemon("--can", "vcan-none")
    assert r.returncode == 2
    assert "--can needs --keys DIR" in r.stderr
    assert "CAN vcan-none: nodes" not in r.stderr  # refused before the bus
    # --insecure-lcm: it starts, and says what that means
    log = tmp_path / "insecure.log"
    with open(log, "w") as f:
        p = subprocess.Popen([DAEMON, "--lcm-url", "udpm://239.255.76.67:7699?ttl=0",
                              "--can", "vcan-none", "--insecure-lcm"],
                             stdout=f, stderr=subprocess.STDOUT)
    try:
        end = time.time() + 20
        while time.time() < end and "listening on" not in log.read_text():
            time.sleep(0.1)
        text = log.read_text()
        assert "--can needs --keys" not in text
        assert "--insecure-lcm: unsigned LCM messages are taken; anyone" in text
        assert "listening on" in text, text
    finally:
        p.terminate()
        p.wait(15)


def test_key_files_others_can_read_are_refused(tmp_path):
    kd = tmp_path / "keys"
    qrtauth.gen_keys(DAEMON, str(kd), [OPERATOR, SENSOR])
    pub = kd / "op.key"

    def refused(why):
        r = run_daemon("--keys", str(kd), timeout=10)
        assert r.returncode == 2 and why in r.stderr, r.stderr

    for mode in (0o640, 0o604, 0o620):
        os.chmod(pub, mode)
        refused(f"mode {mode:04o} lets other users read or change it")
    os.chmod(pub, 0o600)
    os.chmod(kd, 0o777)
    refused("mode 0777 lets other users read or change it")
    os.chmod(kd, 0o755)  # others may look, not add
    if os.geteuid() == 0:
        os.chown(pub, 65534, 65534)
        refused("owned by uid 65534, not by this user")
        os.chown(pub, 0, 0)
    pub.write_text(pub.read_text().replace("role operator", "role admin"))
    refused("role 'admin': want operator, sensor or joints")
    # the sender's side refuses its own secret key shared with others
    os.chmod(kd / "op.key", 0o644)
    with pytest.raises(qrtauth.KeyFileError, match="other users"):
        qrtauth.Signer(str(kd / "op.key"))


def test_gen_key_writes_owner_only_files_and_never_overwrites(tmp_path):
    kd = tmp_path / "k"  # made by --gen-key, owner-only
    r = subprocess.run([DAEMON, "--gen-key", "lidar0", "--role", "sensor",
                        "--key-dir", str(kd)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert os.listdir(kd) == ["lidar0.key"]
    assert os.stat(kd).st_mode & 0o777 == 0o700
    assert os.stat(kd / "lidar0.key").st_mode & 0o777 == 0o600
    before = (kd / "lidar0.key").read_text()
    r = subprocess.run([DAEMON, "--gen-key", "lidar0", "--key-dir", str(kd)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "File exists" in r.stderr
    assert (kd / "lidar0.key").read_text() == before
    for bad in ("../x", ".hidden", "a b", ""):
        r = subprocess.run([DAEMON, "--gen-key", bad, "--key-dir", str(kd)],
                           capture_output=True, text=True)
        assert r.returncode == 2, bad
    r = subprocess.run([DAEMON, "--gen-key", "x", "--role", "admin"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "operator, sensor or joints" in r.stderr
    # two keys are not the same key
    subprocess.run([DAEMON, "--gen-key", "lidar1", "--key-dir", str(kd)], check=True,
                   capture_output=True)
    secrets = {ln for f in ("lidar0.key", "lidar1.key")
               for ln in (kd / f).read_text().splitlines() if ln.startswith("secret ")}
    assert len(secrets) == 2
    # the seal verifies with the key (as the daemon checks) and fails with
    # another or after a change
    import nacl.bindings
    import nacl.exceptions
    s = qrtauth.Signer(str(kd / "lidar0.key"))
    sealed = s.seal("QRT_SCAN", b"payload")
    nonce, data, mac = sealed[-40:-16], sealed[:-16], sealed[-16:]
    nacl.bindings.crypto_aead_xchacha20poly1305_ietf_decrypt(mac, data, nonce, s._key)
    for key, msg in ((qrtauth.Signer(str(kd / "lidar1.key"))._key, data),
                     (s._key, data[:30] + b"X" + data[31:])):
        with pytest.raises(nacl.exceptions.CryptoError):
            nacl.bindings.crypto_aead_xchacha20poly1305_ietf_decrypt(mac, msg, nonce, key)


def test_the_sender_tool_sends_a_signed_request(daemon, tmp_path):
    d, c = daemon(keys=KEYS)
    key = os.path.join(str(tmp_path / "keys0"), "op.key")
    # the picture has a scan before the request: a request that comes
    # first is rightly answered no_obstacle_data, which ends the tool
    for _ in range(3):
        c.publish("QRT_SCAN", scan_from_points([[0.5, 0.5, 0.5]]))
        c.pump(0.1)
    tool = subprocess.Popen(
        [os.sys.executable, os.path.join(os.path.dirname(qrtauth.__file__), "qrtsend.py"),
         "--key", key, "--lcm-url", d.url, "--joints", "90", "0", "0",
         "--start", "-90", "0", "0", "--request-id", "77", "--wait", "10"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    end = time.time() + 30
    while tool.poll() is None and time.time() < end:  # a sensor keeps scanning
        c.publish("QRT_SCAN", scan_from_points([[0.5, 0.5, 0.5]]))
        c.pump(0.1)
    out = tool.communicate(timeout=5)[0]
    assert tool.returncode == 0, out + d.text()
    assert "request 77: sent as 'op'" in out and "request 77: ok" in out
    assert plan_for(c, 77) is not None


def test_the_example_client_prints_a_plan(daemon, tmp_path):
    """examples/plan_client.py, the README's Python client, against a
    daemon with keys: its signed request is planned among the Table 4
    sphere, and what it prints is the plan the daemon published; signed
    with a key the daemon does not hold, it gets no plan."""
    d, c = daemon(keys=KEYS)
    _, pts = scene_points("table4_one_sphere.json")
    example = os.path.join(os.path.dirname(os.path.dirname(qrtauth.__file__)),
                           "examples", "plan_client.py")

    def run_example(key, wait):
        for _ in range(3):  # a scan before the request (as the sender tool's)
            c.publish("QRT_SCAN", scan_from_points(pts))
            c.pump(0.1)
        tool = subprocess.Popen(
            [os.sys.executable, example, "--key", key, "--lcm-url", d.url,
             "--start", "-100", "0", "0", "--goal", "100", "0", "0",
             "--wait", str(wait)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        end = time.time() + wait + 20
        while tool.poll() is None and time.time() < end:  # a sensor scans
            c.publish("QRT_SCAN", scan_from_points(pts))
            c.pump(0.1)
        out, err = tool.communicate(timeout=5)
        return tool.returncode, out, err

    rc, out, err = run_example(os.path.join(str(tmp_path / "keys0"), "op.key"), 10)
    assert rc == 0, out + err + d.text()
    lines = out.splitlines()
    assert lines[0].startswith("status ok: "), out
    printed = [[float(v) for v in line.split()[1:]] for line in lines
               if line.startswith("waypoint ")]
    assert printed[0] == [-100, 0, 0] and printed[-1] == [100, 0, 0], out
    # what it printed is a plan the daemon published among the sphere
    assert any(p.status == "ok" and p.points == len(pts) and
               len(p.waypoints_deg) == len(printed) and
               all(abs(a - b) < 1e-6 for w, q in zip(p.waypoints_deg, printed)
                   for a, b in zip(w, q)) for _, p in c.plans), (out, d.text())
    # an operator key of the same name that the daemon does not hold
    qrtauth.gen_keys(DAEMON, str(tmp_path / "other"), [("op", "operator")])
    rc, out, err = run_example(str(tmp_path / "other" / "op.key"), 2)
    assert rc == 1 and "no plan within" in err, out + err
