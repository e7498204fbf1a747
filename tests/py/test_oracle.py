"""The oracle must be able to say no: these paths are wrong on purpose."""
import json
import subprocess
import sys

import numpy as np

import oracle


def scene(points, start=(0, 0, 0), goal=(90, 0, 0)):
    return {"version": 1, "points": points, "start": {"joints_deg": list(start)},
            "goal": {"joints_deg": list(goal)}}


def plan(wps):
    arm = oracle.Arm({})
    return {"status": "ok", "waypoints_deg": wps,
            "cost_deg": oracle.path_length(arm, wps)}


def test_free_path_passes():
    s = scene([[0.0, -0.5, 0.5]])
    r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]), np.array(s["points"]))
    assert r.safe, str(r)


def test_point_on_the_arm_is_a_collision():
    s = scene([[0.5, 0.0, 0.0]])
    r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]), np.array(s["points"]))
    assert not r.safe and "collision" in str(r)


def test_collision_between_free_waypoints_is_found():
    # the tip sweeps through a point at 45 degrees, 0.96 m out, while both
    # waypoints are far from it
    p = [0.96 * np.cos(np.radians(45)), 0.96 * np.sin(np.radians(45)), 0.0]
    s = scene([p])
    pts = np.array([p])
    arm = oracle.Arm(s)
    assert oracle.clearances(arm, [[0, 0, 0], [90, 0, 0]], pts).min() >= 0.05
    r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]), pts)
    assert not r.safe


def test_alpha_goes_the_short_way_round():
    # 170 -> -170 crosses 180 (20 degrees), not 0: a point at alpha 0 is safe,
    # one at alpha 180 is hit
    wps = [[170, 0, 0], [-170, 0, 0]]
    front = scene([[0.6, 0.0, 0.0]], start=(170, 0, 0), goal=(-170, 0, 0))
    back = scene([[-0.6, 0.0, 0.0]], start=(170, 0, 0), goal=(-170, 0, 0))
    assert oracle.check_path(front, plan(wps), np.array(front["points"])).safe
    assert not oracle.check_path(back, plan(wps), np.array(back["points"])).safe


def test_limit_violation_is_reported():
    s = scene([], start=(0, 0, 0), goal=(0, -50, 0))
    r = oracle.check_path(s, plan([[0, 0, 0], [0, -50, 0]]), np.zeros((0, 3)))
    assert not r.safe and "outside" in str(r)


def test_wrong_cost_and_wrong_end_are_reported():
    s = scene([])
    p = plan([[0, 0, 0], [80, 0, 0]])
    r = oracle.check_path(s, p, np.zeros((0, 3)))
    assert not r.safe and "goal" in str(r)
    p = plan([[0, 0, 0], [90, 0, 0]])
    p["cost_deg"] += 1.0
    assert not oracle.check_path(s, p, np.zeros((0, 3))).safe


def test_waypoint_that_is_not_three_finite_numbers_is_not_safe():
    s = scene([[0.0, -0.5, 0.5]])
    for bad in ([float("nan"), 0, 0], [0, float("inf"), 0], ["x", 0, 0],
                [0, 0], [True, 0, 0], None):
        p = {"status": "ok", "waypoints_deg": [[0, 0, 0], bad, [90, 0, 0]],
             "cost_deg": 90.0}
        r = oracle.check_path(s, p, np.array(s["points"]))
        assert not r.safe and "waypoint 1 is not three finite numbers" in str(r)


def test_a_point_that_is_not_finite_is_not_safe():
    """Its distances are NaN, and NaN < 0 is false: it must not pass."""
    s = scene([[0.0, -0.5, 0.5]])
    for bad in (float("nan"), float("inf")):
        pts = np.array([[0.0, -0.5, 0.5], [0.5, 0.0, bad]])
        r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]), pts)
        assert not r.safe and "not finite" in str(r)


def test_an_arm_that_is_not_finite_is_not_safe():
    for arm in ({"link_radius_m": [0.02, float("nan"), 0.02]},
                {"links_m": [0.09, float("inf"), 0.5]}):
        s = dict(scene([[0.0, -0.5, 0.5]]), arm=arm)
        r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]),
                              np.array(s["points"]))
        assert not r.safe and "not finite" in str(r)
    s = dict(scene([[0.0, -0.5, 0.5]]), margin_m=float("nan"))
    r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]), np.array(s["points"]))
    assert not r.safe and "not finite" in str(r)


def test_nan_in_the_cost_or_the_target_is_not_passed():
    """Each check is written so that NaN fails it (not x <= tol), since
    NaN > tol is false too."""
    s = scene([[0.0, -0.5, 0.5]])
    p = plan([[0, 0, 0], [90, 0, 0]])
    p["cost_deg"] = float("nan")
    r = oracle.check_path(s, p, np.array(s["points"]))
    assert not r.safe and "cost_deg" in str(r)
    s = scene([[0.0, -0.5, 0.5]], goal=(90, float("nan"), 0))
    r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]), np.array(s["points"]))
    assert not r.safe and "path goal" in str(r)
    s = {**scene([[0.0, -0.5, 0.5]]), "goal": {"xyz_m": [float("nan"), 0, 0]}}
    r = oracle.check_path(s, plan([[0, 0, 0], [90, 0, 0]]), np.array(s["points"]))
    assert not r.safe and "misses" in str(r)


def test_command_line_says_it_cannot_check_with_exit_2(tmp_path):
    """Unreadable or malformed files: one line, exit 2, never 0 (safe) and
    never a traceback."""
    good_scene = tmp_path / "s.json"
    good_scene.write_text(json.dumps(scene([[0.0, -0.5, 0.5]])))
    good_plan = tmp_path / "p.json"
    good_plan.write_text(json.dumps(plan([[0, 0, 0], [90, 0, 0]])))
    broken = tmp_path / "broken.json"
    broken.write_text("{")
    array = tmp_path / "array.json"
    array.write_text("[1, 2]")
    no_start = tmp_path / "no_start.json"
    no_start.write_text(json.dumps({"points": [[0.0, -0.5, 0.5]]}))
    # binary_compressed clouds cut short, before and inside the LZF stream
    head = (b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            b"WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n")
    cut = []
    for i, tail in enumerate((b"\x01", b"\x0d\x00\x00\x00\x0c\x00\x00\x00\x0b\x00")):
        (tmp_path / f"cut{i}.pcd").write_bytes(head + tail)
        cut.append(tmp_path / f"cut{i}.json")
        cut[-1].write_text(json.dumps({**scene([[0.0, -0.5, 0.5]]),
                                       "points_file": f"cut{i}.pcd"}))

    def run(*args):
        return subprocess.run([sys.executable, oracle.__file__, *map(str, args)],
                              capture_output=True, text=True, timeout=60)

    r = run(good_scene, good_plan)
    assert r.returncode == 0 and r.stdout.startswith("safe"), r.stderr
    for args in ((good_scene, broken), (broken, good_plan),
                 (good_scene, tmp_path / "missing.json"), (good_scene, array),
                 (no_start, good_plan), (good_scene,),
                 *((c, good_plan) for c in cut)):
        r = run(*args)
        assert r.returncode == 2, (args, r.stdout, r.stderr)
        assert "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1, r.stderr
