"""Choosing the IK branch of an xyz_m target (docs/spec.md §Kinematics,
Branches; §Scene, ik): on a shelf, the default rule (the solution nearest
the start) turns the arm over its head, and asking for the front, elbow-up
solution gets it; a requested branch outside the limits or blocked gives
unreachable or goal_blocked with a detail naming it; bad requests are
refused with the valid values. Every scene and plan here is checked
against the schemas."""
import json

import jsonschema
import numpy as np
import oracle
import pytest

from conftest import ROOT, plan_scene, run_cli

FLAGS = ([], ["--whole-mask"])
GOAL = [0.6, 0.0, 0.45]
# a shelf board 0.1 m under the goal: the solutions that reach the goal
# from below (elbow down, either facing) pass link 3 through it
BOARD = [[round(0.45 + 0.025 * i, 4), round(-0.15 + 0.025 * j, 4), 0.35]
         for i in range(15) for j in range(13)]
# the arm starts turned away from the shelf, so that the nearest free
# solution is the one reaching over its head from behind
START = {"joints_deg": [150, 60, 0]}


def validator(name):
    schema = json.loads((ROOT / "docs" / "schema" / name).read_text())
    return jsonschema.Draft202012Validator(schema)


SCENE_SCHEMA = validator("scene.schema.json")
PLAN_SCHEMA = validator("plan.schema.json")


def shelf(goal_ik=None, start=START, **changes):
    goal = {"xyz_m": GOAL}
    if goal_ik is not None:
        goal["ik"] = goal_ik
    scene = {"version": 1, "points": BOARD, "start": start, "goal": goal}
    scene.update(changes)
    return scene


def plan(scene, tmp_path, *flags):
    assert SCENE_SCHEMA.is_valid(scene), list(SCENE_SCHEMA.iter_errors(scene))
    rc, result, err = plan_scene(scene, tmp_path, *flags)
    assert rc == 0 and err == "", err
    errors = [e.message for e in PLAN_SCHEMA.iter_errors(result)]
    assert not errors, errors
    if result["status"] == "ok":  # safe, in the branch asked, said right
        res = oracle.check_path(scene, result, np.array(scene["points"]))
        assert res.safe, str(res)
    return result


@pytest.mark.parametrize("flags", FLAGS, ids=["as-read", "whole-mask"])
def test_default_reaches_over_the_head(qrtplan, tmp_path, flags):
    p = plan(shelf(), tmp_path, *flags)
    assert p["status"] == "ok", p["detail"]
    assert p["goal_ik"] == {"facing": "back", "elbow": "up"}
    assert p["goal_deg"][0] == 180 and p["goal_deg"][1] > 90
    assert "start_ik" not in p  # a joints start has no branch


@pytest.mark.parametrize("flags", FLAGS, ids=["as-read", "whole-mask"])
@pytest.mark.parametrize("ik,expect", [
    ({"facing": "front", "elbow": "up"}, {"facing": "front", "elbow": "up"}),
    ({"facing": "front"}, {"facing": "front", "elbow": "up"}),
    ({"facing": "back", "elbow": "up"}, {"facing": "back", "elbow": "up"}),
    ({"elbow": "up"}, {"facing": "back", "elbow": "up"}),
    ({"facing": "any", "elbow": "any"}, {"facing": "back", "elbow": "up"}),
], ids=lambda v: json.dumps(v, separators=(",", ":")))
def test_requested_branch_is_planned(qrtplan, tmp_path, flags, ik, expect):
    p = plan(shelf(ik), tmp_path, *flags)
    assert p["status"] == "ok", p["detail"]
    assert p["goal_ik"] == expect
    q = p["goal_deg"]
    if expect["facing"] == "front":
        assert q[0] == 0 and 0 < q[1] < 180 and q[2] < 0, q  # elbow up, ahead
    assert p["waypoints_deg"][-1] == q


def test_requested_branch_free_without_the_shelf(qrtplan, tmp_path):
    """In open space every one of the four branches is planned to."""
    for facing in ("front", "back"):
        for elbow in ("up", "down"):
            ik = {"facing": facing, "elbow": elbow}
            p = plan(shelf(ik, points=[[-0.5, -0.5, -0.5]]), tmp_path)
            assert p["status"] == "ok" and p["goal_ik"] == ik, p


@pytest.mark.parametrize("flags", FLAGS, ids=["as-read", "whole-mask"])
def test_blocked_branch_is_named(qrtplan, tmp_path, flags):
    p = plan(shelf({"facing": "front", "elbow": "down"}), tmp_path, *flags)
    assert p["status"] == "goal_blocked"
    assert p["detail"] == ("every goal configuration facing front with the "
                           "elbow down collides with obstacle points")
    assert p["goal_ik"] == {"facing": "front", "elbow": "down"}
    p = plan(shelf({"elbow": "down"}), tmp_path, *flags)
    assert p["status"] == "goal_blocked"
    assert "with the elbow down" in p["detail"] and "facing" not in p["detail"]


@pytest.mark.parametrize("flags", FLAGS, ids=["as-read", "whole-mask"])
def test_branch_outside_the_limits_is_unreachable(qrtplan, tmp_path, flags):
    arm = {"limits_deg": [[-180, 180], [-40, 100], [-180, 140]]}
    p = plan(shelf({"facing": "back"}, arm=arm), tmp_path, *flags)
    assert p["status"] == "unreachable"
    assert p["detail"] == ("goal point has no IK solution facing back inside "
                           "the arm's reach and limits")
    assert "goal_ik" not in p and "goal_deg" not in p
    # the other facing is inside them
    p = plan(shelf({"facing": "front"}, arm=arm), tmp_path, *flags)
    assert p["status"] == "ok" and p["goal_ik"]["facing"] == "front"


def test_xyz_start_reports_its_branch(qrtplan, tmp_path):
    start = {"xyz_m": [0.5, 0.2, 0.3], "ik": {"facing": "front",
                                             "elbow": "down"}}
    p = plan(shelf({"facing": "front", "elbow": "up"}, start=start,
                   points=[[-0.5, -0.5, -0.5]]), tmp_path)
    assert p["status"] == "ok", p["detail"]
    assert p["start_ik"] == {"facing": "front", "elbow": "down"}
    assert p["goal_ik"] == {"facing": "front", "elbow": "up"}
    start["ik"] = {"facing": "back", "elbow": "down"}
    p = plan(shelf(start=start), tmp_path)
    assert p["status"] == "unreachable"
    assert p["detail"] == ("start point has no IK solution facing back with "
                           "the elbow down inside the arm's reach and limits")


def test_point_on_the_base_axis_is_both_facings(qrtplan, tmp_path):
    goal = {"xyz_m": [0, 0, 0.6]}
    for facing in ("front", "back"):
        goal["ik"] = {"facing": facing, "elbow": "up"}
        p = plan({"version": 1, "points": [[-0.5, -0.5, -0.5]],
                  "start": START, "goal": goal}, tmp_path)
        assert p["status"] == "ok"
        assert p["goal_ik"] == {"facing": "both", "elbow": "up"}


BAD_IK = [
    ({"facing": "sideways"},
     'goal.ik.facing is "sideways"; valid: "any", "front", "back"'),
    ({"elbow": "left"}, 'goal.ik.elbow is "left"; valid: "any", "up", "down"'),
    ({"facing": "both"},
     'goal.ik.facing is "both"; valid: "any", "front", "back"'),
    ({"facing": 1},
     'goal.ik.facing must be a string, not number (valid: "any", "front", '
     '"back")'),
    ({"side": "left"},
     'unknown field "side" in goal.ik (valid: facing, elbow)'),
    ("front", "goal.ik must be an object with facing and/or elbow, not string"),
]


@pytest.mark.parametrize("ik,message", BAD_IK,
                         ids=[json.dumps(i) for i, _ in BAD_IK])
def test_bad_request_is_refused_with_the_valid_values(qrtplan, tmp_path, ik,
                                                      message):
    scene = shelf(ik)
    assert not SCENE_SCHEMA.is_valid(scene)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    r = run_cli(["plan", path])
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == f"qrtplan: {path}: {message}\n"


def test_ik_on_joints_is_refused(qrtplan, tmp_path):
    scene = shelf(start={"joints_deg": [0, 0, 0], "ik": {"facing": "front"}})
    assert not SCENE_SCHEMA.is_valid(scene)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    r = run_cli(["plan", path])
    assert r.returncode == 2 and "start.ik applies only to xyz_m" in r.stderr


def test_plan_schema_checks_the_branch(qrtplan, tmp_path):
    p = plan(shelf({"facing": "front", "elbow": "up"}), tmp_path)
    for bad in ({"facing": "any", "elbow": "up"}, {"facing": "front"},
                {"facing": "front", "elbow": "up", "extra": 1}, "front/up"):
        assert not PLAN_SCHEMA.is_valid(dict(p, goal_ik=bad)), bad
    unreachable = plan(shelf({"facing": "back"}, arm={
        "limits_deg": [[-180, 180], [-40, 100], [-180, 140]]}), tmp_path)
    assert not PLAN_SCHEMA.is_valid(dict(unreachable, goal_ik=p["goal_ik"]))


def test_the_oracle_measures_the_branch():
    """tools/oracle.py tells the branch from joint positions alone, so a plan
    in another branch than asked, or one that misreports its branch, is not
    called safe."""
    arm = oracle.Arm({})
    assert oracle.ik_branch(arm, [0, 92.56, -79.85]) == ("front", "up")
    assert oracle.ik_branch(arm, [0, -9.71, 79.85]) == ("front", "down")
    assert oracle.ik_branch(arm, [180, 122.81, 38.66]) == ("back", "up")
    assert oracle.ik_branch(arm, [180, 170.97, -38.66]) == ("back", "down")
    assert oracle.ik_branch(arm, [0, 30, 0])[1] == "both"  # straight arm
    scene = shelf({"facing": "front", "elbow": "up"},
                  points=[[-0.5, -0.5, -0.5]])
    up = [0, 92.55938893921252, -79.85350235235528]
    down = [0, -9.712057689207228, 79.85350235235528]
    good = {"status": "ok", "waypoints_deg": [[150, 60, 0], up],
            "goal_ik": {"facing": "front", "elbow": "up"}}
    good["cost_deg"] = oracle.path_length(arm, good["waypoints_deg"])
    points = np.array(scene["points"])
    assert oracle.check_path(scene, good, points).safe
    wrong = dict(good, waypoints_deg=[[150, 60, 0], down],
                 goal_ik={"facing": "front", "elbow": "down"})
    wrong["cost_deg"] = oracle.path_length(arm, wrong["waypoints_deg"])
    assert "asked up" in str(oracle.check_path(scene, wrong, points))
    told = dict(good, goal_ik={"facing": "back", "elbow": "up"})
    assert "plan says goal facing back" in str(
        oracle.check_path(scene, told, points))
