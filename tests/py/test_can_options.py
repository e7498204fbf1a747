"""The CAN programs' inputs: values that would wrap a 32-bit CiA 402 object,
a node id outside CANopen's 1..127, a drive that is not simulated, and plans
qrtplan-exec cannot use (malformed, or past a joint limit) are refused with
one line, before any bus is opened (so these run on a machine without
SocketCAN)."""
import subprocess

import pytest

from conftest import BIN

SIM = BIN.parent / "servo_sim"  # built beside qrtplan
EXEC = BIN.parent / "qrtplan-exec"
DAEMON = BIN.parent / "qrtpland"


def run_sim(args):
    if not SIM.is_file():
        pytest.fail(f"{SIM} not found: run `make` first")
    return subprocess.run([str(SIM), *args, "--iface", "qrt_no_such_bus",
                           "--duration", "0.1"],
                          capture_output=True, text=True, timeout=30)


@pytest.mark.parametrize("args,words", [
    (["--nodes", "1,1,3"], "bad value for --nodes"),
    (["--nodes", "1,2,3,4,5,6,7,8,9"], "bad value for --nodes"),
    (["--nodes", "1,2,128"], "bad value for --nodes"),
    (["--nodes", "1,,3"], "bad value for --nodes"),
    (["--nodes", "1,2,"], "bad value for --nodes"),
    (["--nodes", ",1,2"], "bad value for --nodes"),
    (["--nodes", "1, 2"], "bad value for --nodes"),
    (["--nodes", "+1,2"], "bad value for --nodes"),
    (["--nodes", "0x2,3"], "bad value for --nodes"),
    (["--nodes", ""], "bad value for --nodes"),
    (["--limit", "2:1:5junk"], "bad value for --limit"),
    (["--limit", "200:1:5"], "bad value for --limit"),
    (["--limit", "2:-99999999999:5"], "bad value for --limit"),
    (["--limit", "2:1:2147483648"], "bad value for --limit"),
    (["--limit", "2:5:1"], "bad value for --limit"),
    (["--limit", "5:1:2"], "--limit for node 5, not in --nodes"),
    (["--fault-node", "4", "--fault-at", "0"], "--fault-node 4, not in --nodes"),
    (["--nodes", "4,5,6", "--mute-node", "1"], "--mute-node 1, not in --nodes"),
    (["--start-deg", "100000,0,0", "--counts-per-deg", "100000"],
     "beyond a 32-bit position"),
    (["--start-deg", "nan,0,0"], "bad value for --start-deg"),
    (["--start-deg", "1, 2,3"], "bad value for --start-deg"),
    (["--start-deg", "1,2,3,"], "bad value for --start-deg"),
    (["--fault-at", " 1"], "bad value for --fault-at"),
    (["--counts-per-deg", "inf"], "bad value for --counts-per-deg"),
    (["--counts-per-deg", "1000,2000"], "bad value for --counts-per-deg"),
    (["--counts-per-deg", "1000,2000,500,1"], "bad value for --counts-per-deg"),
    (["--counts-per-deg", "1000,,500"], "bad value for --counts-per-deg"),
    (["--counts-per-deg", "1000, 2000,500"], "bad value for --counts-per-deg"),
    (["--counts-per-deg", "1000,0,500"], "bad value for --counts-per-deg"),
    (["--counts-per-deg", "1000x"], "bad value for --counts-per-deg"),
    (["--offset-counts", "5000,2000"], "bad value for --offset-counts"),
    (["--offset-counts", "1.5"], "bad value for --offset-counts"),
    (["--offset-counts", "2e9"], "bad value for --offset-counts"),
    (["--offset-counts", "5000,,0"], "bad value for --offset-counts"),
    (["--offset-counts", "5000, 0,0"], "bad value for --offset-counts"),
    (["--offset-counts", "x"], "bad value for --offset-counts"),
    # 1e9 counts at 100000 degrees fit; from 1e9 at 0 degrees they do not
    (["--start-deg", "0,100000,0", "--counts-per-deg", "10000",
      "--offset-counts", "0,1000000000,0"], "(from 1e+09 at 0 degrees)"),
    # per joint: 30000 deg at 100000 counts a degree is sigma's alone
    (["--start-deg", "0,30000,0", "--counts-per-deg", "1000,100000,1000"],
     "--start-deg 30000 times --counts-per-deg 100000"),
])
def test_refused_before_the_bus_opens(args, words):
    r = run_sim(args)
    assert r.returncode == 2, r.stderr
    assert words in r.stderr
    assert "socket" not in r.stderr


def test_accepted_values_reach_the_bus():
    """The same options within range get past the checks: the run then fails
    only on the bus that does not exist (exit 1, a socket error)."""
    r = run_sim(["--nodes", "4,5,6", "--limit", "5:-2147483648:2147483647",
                 "--start-deg", "10,20,30", "--counts-per-deg", "1000"])
    assert r.returncode == 1, r.stderr
    assert "qrt_no_such_bus" in r.stderr or "socket" in r.stderr


BAD_IDS = ["0,2,3", "1,128,3", "-1,2,3", "1,1,3", "4294967297,2,3",
           " 1,2,3", "+1,2,3", "1,2,3x", "1,2", "1,2,3,4", ""]


@pytest.mark.parametrize("ids", BAD_IDS)
def test_node_ids_refused_by_the_daemon_and_exec(tmp_path, ids):
    """4294967297 used to wrap to node 1 in the daemon (sscanf's %u)."""
    for prog in (EXEC, DAEMON):
        if not prog.is_file():
            pytest.fail(f"{prog} not found: run `make` first")
    plan = tmp_path / "p.json"
    plan.write_text('{"status": "ok", "waypoints_deg": [[0, 0, 0], [5, 0, 0]]}')
    r = subprocess.run([str(EXEC), "--nodes", ids, "--can", "qrt_no_such_bus",
                        str(plan)], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "--nodes wants three distinct ids" in r.stderr
    r = subprocess.run([str(DAEMON), "--can-nodes", ids, "--help"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert "can-nodes: three distinct node ids in 1..127" in r.stderr


def test_good_node_ids_accepted():
    r = subprocess.run([str(DAEMON), "--can-nodes", "4,5,127", "--help"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("text,words", [
    (None, "cannot read: Is a directory"),
    ("", "unexpected end of input"),
    ("[1, 2]", 'no "status" string'),
    ('{"status": "no_path", "waypoints_deg": [[0, 0, 0]]}', "nothing to execute"),
    ('{"status": "ok", "waypoints_deg": []}', "must be an array of 1..256"),
    ('{"status": "ok", "waypoints_deg": [[0, 0]]}', "is not [a, s, e]"),
    ('{"status": "ok", "waypoints_deg": [[0, "x", 0]]}', "has a non-number"),
    ('{"status": "ok", "waypoints_deg": [[0, 0, 0], [0, 180.01, 0]]}',
     "waypoint 1 (0.000000, 180.010000, 0.000000) is outside the joint limits"),
    ('{"status": "ok", "waypoints_deg": [[0, 0, 0], [0, -40.01, 0]]}',
     "waypoint 1"),
    ('{"status": "ok", "waypoints_deg": [[0, 0, 0], [0, 0, 140.01]]}',
     "waypoint 1"),
    ('{"status": "ok", "waypoints_deg": [[0, 0, -180.5], [0, 0, 0]]}',
     "waypoint 0"),
])
def test_exec_refuses_a_plan_it_cannot_use_before_the_bus(tmp_path, text,
                                                          words):
    plan = tmp_path / "p.json"
    if text is None:
        plan.mkdir()  # opens, then cannot be read
    else:
        plan.write_text(text)
    r = subprocess.run([str(EXEC), "--can", "qrt_no_such_bus", str(plan)],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2, r.stderr
    assert words in r.stderr and "SocketCAN" not in r.stderr


def test_exec_takes_a_plan_on_the_limits_and_across_alpha_180(tmp_path):
    """Waypoints on the limits, and alpha 179 -> -179 (it wraps: 2 degrees
    the short way), pass the limits and reach the bus (absent here)."""
    plan = tmp_path / "p.json"
    plan.write_text('{"status": "ok", "waypoints_deg": '
                    '[[0, 0, 0], [179, -40, 140], [-179, 180, -180]]}')
    r = subprocess.run([str(EXEC), "--can", "qrt_no_such_bus", "--timeout",
                        "5", str(plan)], capture_output=True, text=True,
                       timeout=30)
    assert r.returncode != 0 and "joint limits" not in r.stderr, r.stderr
    assert "qrt_no_such_bus" in r.stderr


def run_exec_with_limits(tmp_path, limits, waypoints):
    plan = tmp_path / "p.json"
    plan.write_text('{"status": "ok", "waypoints_deg": %s}' % waypoints)
    return subprocess.run([str(EXEC), "--can", "qrt_no_such_bus", "--timeout",
                           "5", "--limits-deg", limits, str(plan)],
                          capture_output=True, text=True, timeout=30)


@pytest.mark.parametrize("limits,waypoints,refused", [
    # sigma narrowed to 90: a plan made for the default arm's 180
    # (docs/spec.md §Arm) is refused
    ("-180,180,-40,90,-180,140", "[[0, 0, 0], [0, 120, 0]]", "waypoint 1"),
    ("-180,180,-40,90,-180,140", "[[0, 0, 0], [0, 90, 0]]", None),
    # alpha not wrapping: 160 -> -160 is a 320 degree turn, not 40
    ("-170,170,-40,180,-180,140", "[[0, 0, 0], [160, 0, 0], [-160, 0, 0]]",
     "waypoint 2"),
    ("-170,170,-40,180,-180,140", "[[0, 0, 0], [175, 0, 0]]", "waypoint 1"),
    ("-180,180,-40,180,-180,140", "[[160, 0, 0], [-160, 0, 0]]", None),
])
def test_exec_checks_the_plan_against_the_arms_limits(tmp_path, limits,
                                                      waypoints, refused):
    r = run_exec_with_limits(tmp_path, limits, waypoints)
    if refused:
        assert r.returncode == 2, r.stderr
        assert refused + " (" in r.stderr and "joint limits" in r.stderr
    else:
        assert r.returncode != 0 and "joint limits" not in r.stderr, r.stderr
        assert "qrt_no_such_bus" in r.stderr


@pytest.mark.parametrize("limits", [
    "-180,180,-40,90,-180", "-180,180,-40,90,-180,140,0",
    "-180,180,-40,90,-180,140,", "-180,180,-40,,-180,140",
    "-180,180,90,-40,-180,140", "-180,180,-40,190,-180,140",
    "nan,180,-40,90,-180,140", "-180,inf,-40,90,-180,140", "",
])
def test_exec_refuses_bad_limits(tmp_path, limits):
    r = run_exec_with_limits(tmp_path, limits, "[[0, 0, 0]]")
    assert r.returncode == 2 and "--limits-deg wants six numbers" in r.stderr


def test_per_joint_counts_reach_the_bus():
    """One scale each: the start check takes each joint's own (sigma 30000
    deg at 1000 counts is in range), so the simulator gets to the bus."""
    r = run_sim(["--start-deg", "0,30000,0", "--counts-per-deg",
                 "100000,1000,100000"])
    assert r.returncode == 1, r.stderr
    assert "qrt_no_such_bus" in r.stderr or "socket" in r.stderr


# the per-joint drive settings qrtpland and qrtplan-exec share a parser for:
# each option's malformed values, and the words that name what it wants
PER_JOINT_BAD = (
    [("--counts-per-deg", v, "non-zero") for v in
     ["1000,2000", "0", "1000,0,1", "1e8", "1000,-2e7,1", "nan",
      "1000, 2000,500", ""]] +
    [(o, v, "0.001..10000") for o in ("--speed", "--accel") for v in
     ["30,60", "0", "30,0,30", "1e5", "-30", "nan", "30,60,90,1", "30,,30"]] +
    [("--offset-counts", v, "whole") for v in
     ["5000,2000", "1.5", "2e9", "5000,,0", "5000, 0,0", "nan", "0,0,0,0",
      ""]])


@pytest.mark.parametrize("option,value,wants", PER_JOINT_BAD)
def test_bad_per_joint_values_refused_by_the_daemon_and_exec(tmp_path, option,
                                                             value, wants):
    plan = tmp_path / "p.json"
    plan.write_text('{"status": "ok", "waypoints_deg": [[0, 0, 0], [5, 0, 0]]}')
    r = subprocess.run([str(EXEC), option, value, "--can", "qrt_no_such_bus",
                        str(plan)], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and f"{option} wants {wants}" in r.stderr
    r = subprocess.run([str(DAEMON), option, value, "--help"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and f"{option[2:]}: {wants}" in r.stderr


def test_per_joint_counts_accepted_by_the_daemon():
    r = subprocess.run([str(DAEMON), "--counts-per-deg", "1000,-2000,500",
                        "--help"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stderr


def test_per_joint_speed_and_accel_accepted(tmp_path):
    r = subprocess.run([str(DAEMON), "--speed", "40,10,20", "--accel",
                        "80,20,40", "--help"], capture_output=True, text=True,
                       timeout=30)
    assert r.returncode == 0, r.stderr
    plan = tmp_path / "p.json"
    plan.write_text('{"status": "ok", "waypoints_deg": [[0, 0, 0], [5, 0, 0]]}')
    r = subprocess.run([str(EXEC), "--speed", "40,10,20", "--accel",
                        "80,20,40", "--can", "qrt_no_such_bus", "--timeout",
                        "5", str(plan)], capture_output=True, text=True,
                       timeout=30)
    assert r.returncode != 2 and "qrt_no_such_bus" in r.stderr, r.stderr
