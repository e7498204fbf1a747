"""The JSON Schemas of docs/schema/ (docs/spec.md §Scene and §Plan) against
what qrtplan reads and writes: every shipped scene is valid, and so is every
plan the command line makes for them, by default and --whole-mask, and for scenes
made from them to reach every status of the CLI. Scenes the schema refuses
are refused by qrtplan too (exit 2), and plans with an unknown key, a wrong
type or a missing key are refused by the plan schema, so neither schema can
pass vacuously."""
import copy
import json
import math

import jsonschema
import numpy as np
import pytest

from conftest import ROOT, max_points, run_cli

SCHEMAS = ROOT / "docs" / "schema"
SCENES = sorted((ROOT / "scenes").glob("*.json"))
FLAGS = ([], ["--whole-mask"])


def validator(name):
    schema = json.loads((SCHEMAS / name).read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


@pytest.fixture(scope="module")
def scene_schema():
    return validator("scene.schema.json")


@pytest.fixture(scope="module")
def plan_schema():
    return validator("plan.schema.json")


def assert_valid(v, doc):
    errors = [f"{list(e.absolute_path)}: {e.message}" for e in v.iter_errors(doc)]
    assert not errors, errors


def plan_file(path, *flags):
    r = run_cli(["plan", path, *flags])
    assert r.returncode == 0 and r.stderr == "", (r.returncode, r.stderr)
    return json.loads(r.stdout)


def table4():
    return json.loads((ROOT / "scenes" / "table4_one_sphere.json").read_text())


def test_scenes_are_shipped():
    assert len(SCENES) >= 3, SCENES


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_shipped_scene_and_its_plans_are_valid(qrtplan, scene_schema,
                                               plan_schema, path):
    assert_valid(scene_schema, json.loads(path.read_text()))
    for flags in FLAGS:
        plan = plan_file(path, *flags)
        assert plan["status"] == "ok", plan["detail"]
        assert_valid(plan_schema, plan)


def without(plan, *keys):
    """The plan without the given stats keys."""
    plan = copy.deepcopy(plan)
    for key in keys:
        del plan["stats"][key]
    return plan


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_default_plan_is_the_whole_mask_plan(qrtplan, path):
    """The default asks only the mask nodes the plan reads
    (qrt_planner_plan_now) and gives the plan --whole-mask gives: the same
    status, waypoints, cost and nodes expanded; only the blocked-cell count
    (-1: no whole mask) and the times differ. --as-read is the default."""
    default = plan_file(path)
    whole = plan_file(path, "--whole-mask")
    as_read = plan_file(path, "--as-read")
    assert default["stats"]["cells_blocked"] == -1
    assert default["stats"]["time_us"]["convert"] == 0
    assert whole["stats"]["cells_blocked"] > 0
    assert without(default, "time_us") == without(as_read, "time_us")
    assert without(default, "time_us", "cells_blocked") == \
        without(whole, "time_us", "cells_blocked")


def walled_in():
    """Walls across link 1's circle at alpha 45 and 135 (as in
    test_bad_input.py): alpha 90 and 0 are cut off from each other."""
    return [[r * math.cos(a), r * math.sin(a), z]
            for a in (math.pi / 4, 3 * math.pi / 4)
            for r in np.arange(0.05, 0.151, 0.01)
            for z in np.arange(-0.04, 0.041, 0.01)]


def capacity_cloud(path):
    """One point in each 64 mm voxel (the coarsest) of a cube of k^3 of
    them, k^3 more than this build's table holds even as voxels (524,288 in
    the host profile, 16,384 in the board's). Binary PCD, float32; the
    arm's 3 m links reach them all (k is 83 in the host profile: 5.3 m)."""
    k = round(max_points() ** (1 / 3)) + 2
    i = np.arange(k) - k / 2
    xyz = (np.stack(np.meshgrid(i, i, i, indexing="ij"), -1).reshape(-1, 3)
           * 0.064).astype(np.float32)
    n = len(xyz)
    path.write_bytes(
        (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
         f"COUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
         f"POINTS {n}\nDATA binary\n").encode() + xyz.tobytes())


# the Table 4 scene (a sphere of radius 0.1 m centred 0.6 m behind the base)
# changed to reach each status the command line writes
STATUS_SCENES = [
    ("ok", {"goal": {"xyz_m": [-0.16, 0.93, 0.0]}}),
    ("ok", {"goal": {"joints_deg": [-100, 0, 0]}, "name": 7,
            "comment": {"any": [1]}}),
    ("ok", {"points": [], "version": 1.0,
            "arm": {"limits_deg": [[-170, 170], [-40, 180], [-180, 140]]},
            "grid_deg": 10, "margin_m": 0, "cspace_margin_deg": 2}),
    ("ok", {"arm": {"tool": {"length_m": 0.1, "radius_m": 0.03}},
            "goal": {"xyz_m": [-0.16, 0.93, 0.0], "aim": "tool_tip",
                     "ik": {"facing": "front"}}}),
    ("start_blocked", {"start": {"joints_deg": [180, 0, 0]}}),
    ("goal_blocked", {"goal": {"joints_deg": [180, 0, 0]}}),
    ("unreachable", {"goal": {"xyz_m": [2.0, 0.0, 0.0]}}),
    ("unreachable", {"start": {"xyz_m": [0.0, 0.0, 5.0]}}),
    ("no_path", {"points": "walled_in", "start": {"joints_deg": [90, 0, 0]},
                 "goal": {"joints_deg": [0, 0, 0]}}),
    ("capacity", {"points": None, "points_file": "cloud.pcd",
                  "arm": {"links_m": [0.09, 3.0, 3.0]},
                  "start": {"joints_deg": [0, 0, 0]},
                  "goal": {"joints_deg": [10, 0, 0]}}),
]


@pytest.mark.parametrize("status,changes", STATUS_SCENES,
                         ids=[f"{s}-{i}" for i, (s, _) in enumerate(STATUS_SCENES)])
def test_every_status_is_a_valid_plan(qrtplan, scene_schema, plan_schema,
                                      tmp_path, status, changes):
    scene = table4()
    for key, value in changes.items():
        if value is None:
            scene.pop(key)
        elif value == "walled_in":
            scene[key] = walled_in()
        else:
            scene[key] = value
    if "points_file" in scene:
        capacity_cloud(tmp_path / scene["points_file"])
    assert_valid(scene_schema, scene)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    for flags in FLAGS:
        plan = plan_file(path, *flags)
        assert plan["status"] == status, plan["detail"]
        assert_valid(plan_schema, plan)


GOOD = {"version": 1, "points": [[0.5, 0.5, 0.5]],
        "start": {"joints_deg": [-100, 0, 0]}, "goal": {"joints_deg": [100, 0, 0]}}


def changed(path, value):
    """GOOD with the value at path (a list of keys) replaced; None drops it."""
    doc = copy.deepcopy(GOOD)
    *outer, last = path
    at = doc
    for k in outer:
        at = at.setdefault(k, {})
    if value is None:
        at.pop(last)
    else:
        at[last] = value
    return doc


BAD_SCENES = [
    # unknown keys, at every level
    (["colour"], "red"),
    (["arm", "elbow"], 1),
    (["start", "joints"], [0, 0, 0]),
    # wrong types
    (["margin_m"], "big"),
    (["points"], [[1, "2", 3]]),
    (["points"], {"x": 1}),
    (["points_file"], 3),
    (["arm"], [0.09, 0.332, 0.538]),
    (["goal"], [100, 0, 0]),
    # missing required keys, wrong counts, values out of range
    (["start"], None),
    (["goal"], None),
    (["points"], None),
    (["start"], {}),
    (["start"], {"joints_deg": [0, 0, 0], "xyz_m": [0.5, 0, 0]}),
    (["points"], [[1, 2]]),
    (["version"], 2),
    (["grid_deg"], 1),
    (["cspace_margin_deg"], 46),
    (["points_file"], ""),
    (["arm", "links_m"], [0.1, 0.2]),
    (["arm", "link_radius_m"], [0.02, 0.02, -0.01]),
    (["arm", "limits_deg"], [[-190, 180], [-40, 180], [-180, 140]]),
    (["arm", "limits_deg"], [[-180, 180], [-40, 180]]),
    # IK branch requests: only on xyz_m, only the named values
    (["goal"], {"xyz_m": [0.6, 0, 0.45], "ik": {"facing": "sideways"}}),
    (["goal"], {"xyz_m": [0.6, 0, 0.45], "ik": {"elbow": "both"}}),
    (["goal"], {"xyz_m": [0.6, 0, 0.45], "ik": {"elbow": 1}}),
    (["goal"], {"xyz_m": [0.6, 0, 0.45], "ik": {"wrist": "up"}}),
    (["goal"], {"xyz_m": [0.6, 0, 0.45], "ik": "front"}),
    (["start"], {"joints_deg": [-100, 0, 0], "ik": {"facing": "front"}}),
    # a tool on the arm, and what a target's point is for
    (["arm", "tool"], {"length_m": -0.1, "radius_m": 0.02}),
    (["arm", "tool"], {"length_m": 0.1, "radius_m": -0.02}),
    (["arm", "tool"], {"length_m": "NaN", "radius_m": 0.02}),
    (["arm", "tool"], {"length_m": 0.1}),
    (["arm", "tool"], {"length_m": 0.1, "radius_m": 0.02, "mass_kg": 1}),
    (["arm", "tool"], 0.1),
    (["goal"], {"xyz_m": [0.6, 0, 0.45], "aim": "tip"}),
    (["start"], {"joints_deg": [-100, 0, 0], "aim": "tool_tip"}),
]


@pytest.mark.parametrize("path,value", BAD_SCENES,
                         ids=[".".join(p) + f"={v!r}"[:24] for p, v in BAD_SCENES])
def test_scene_schema_refuses_what_qrtplan_refuses(qrtplan, scene_schema,
                                                   tmp_path, path, value):
    scene = changed(path, value)
    assert not scene_schema.is_valid(scene)
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(scene))
    r = run_cli(["plan", p])
    assert r.returncode == 2 and r.stdout == "", (r.returncode, r.stdout)
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.fixture(scope="module")
def ok_plan(qrtplan):
    plan = plan_file(ROOT / "scenes" / "table4_one_sphere.json")
    assert plan["status"] == "ok"
    return plan


@pytest.fixture(scope="module")
def no_path_plan(qrtplan, tmp_path_factory):
    scene = dict(GOOD, points=walled_in(), start={"joints_deg": [90, 0, 0]},
                 goal={"joints_deg": [0, 0, 0]})
    path = tmp_path_factory.mktemp("no_path") / "scene.json"
    path.write_text(json.dumps(scene))
    plan = plan_file(path)
    assert plan["status"] == "no_path"
    return plan


def mutate(plan, path, value):
    doc = copy.deepcopy(plan)
    *outer, last = path
    at = doc
    for k in outer:
        at = at[k]
    if value is None:
        del at[last]
    else:
        at[last] = value
    return doc


BAD_OK_PLANS = [
    (["extra"], 1),
    (["stats", "extra"], 1),
    (["stats", "time_us", "extra"], 1),
    (["cost_deg"], "165"),
    (["status"], "maybe"),
    (["version"], 2),
    (["stats", "points"], 1.5),
    (["stats", "cells_blocked"], -2),
    (["waypoints_deg"], [[-100, 0, 0]]),
    (["waypoints_deg", 0], [-100, 0]),
    (["waypoints_deg", 0, 0], 190),
    (["detail"], None),
    (["waypoints_deg"], None),
    (["goal_deg"], None),
    (["stats"], None),
    (["stats", "time_us"], None),
    (["stats", "lattice_cost_deg"], None),
]


@pytest.mark.parametrize("path,value", BAD_OK_PLANS,
                         ids=[".".join(map(str, p)) + f"={v!r}"[:24]
                              for p, v in BAD_OK_PLANS])
def test_plan_schema_refuses_a_changed_ok_plan(plan_schema, ok_plan, path,
                                               value):
    assert_valid(plan_schema, ok_plan)
    assert not plan_schema.is_valid(mutate(ok_plan, path, value))


def test_plan_schema_ties_keys_to_the_status(plan_schema, ok_plan, no_path_plan):
    assert_valid(plan_schema, no_path_plan)
    # a plan that is not ok carries no path, and an ok one does
    assert not plan_schema.is_valid(mutate(no_path_plan, ["waypoints_deg"],
                                           ok_plan["waypoints_deg"]))
    assert not plan_schema.is_valid(mutate(ok_plan, ["status"], "no_path"))
    assert not plan_schema.is_valid(mutate(no_path_plan, ["status"], "ok"))
    # start_blocked has no goal_deg; unreachable and capacity neither joints
    assert not plan_schema.is_valid(mutate(no_path_plan, ["status"],
                                           "start_blocked"))
    assert plan_schema.is_valid(mutate(mutate(no_path_plan, ["goal_deg"], None),
                                       ["status"], "start_blocked"))
    for status in ("unreachable", "capacity"):
        assert not plan_schema.is_valid(mutate(no_path_plan, ["status"], status))
