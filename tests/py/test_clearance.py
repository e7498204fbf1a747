"""A certified clearance on every ok plan (docs/spec.md §Guarantee,
Clearance): clearance_m is present, a lower bound on the least clearance
along the whole motion, at least the margin, and within 5 mm of the least
clearance by the oracle where the points are exact. The oracle checks the
same on every ok plan of test_safety, test_tool, test_ik_branch and
test_dense (oracle.check_clearance); this file makes sure the value is
there to check, and that the check itself can say no."""
import copy
import json

import numpy as np
import pytest

import oracle
import scenes
from conftest import ROOT, plan_scene

SCENES = ROOT / "scenes"


def oracle_least(scene, plan):
    """The least clearance along the plan's path by the oracle, margin not
    subtracted, exact at any distance."""
    arm = oracle.Arm(scene)
    q = oracle.sample_path(arm, plan["waypoints_deg"])
    pts = np.asarray(scene["points"], float)
    return float(oracle.clearances(arm, q, pts, reach=2.0).min()) + arm.margin


@pytest.mark.parametrize("name", ["table4_one_sphere.json",
                                  "three_spheres.json", "ten_spheres.json"])
def test_the_paper_scenes_carry_a_bound_close_to_the_truth(name, tmp_path):
    scene = json.loads((SCENES / name).read_text())
    rc, plan, err = plan_scene(scene, tmp_path)
    assert rc == 0 and plan["status"] == "ok", err
    least = oracle_least(scene, plan)
    claim = plan["clearance_m"]
    margin = oracle.Arm(scene).margin
    assert margin <= claim <= least + 1e-9, (claim, least)
    assert claim >= least - 0.005, (claim, least)


def test_random_scenes_with_tools_get_tight_bounds(tmp_path):
    """Seeded scenes of every family, half with a tool wider than link 3:
    every ok plan's bound lies within 5 mm below the oracle's least
    clearance (and never above it)."""
    checked = 0
    families = sorted(scenes.FAMILIES)
    for i in range(24):
        family = families[i % len(families)]
        scene = scenes.make_scene(family, 20261207 + i)
        if i % 2:
            scene = copy.deepcopy(scene)
            scene.setdefault("arm", {})["tool"] = {"length_m": 0.12,
                                                  "radius_m": 0.035}
        rc, plan, err = plan_scene(scene, tmp_path, name=f"s{i}")
        assert rc == 0, err
        if plan["status"] != "ok":
            continue
        res = oracle.check_path(scene, plan, np.asarray(scene["points"]))
        assert res.safe, f"{family} {i}: {res}"
        checked += 1
    assert checked >= 12, f"only {checked} ok plans"


def test_no_points_gives_null(tmp_path):
    scene = {"version": 1, "points": [], "start": {"joints_deg": [0, 0, 0]},
             "goal": {"joints_deg": [90, 10, 0]}}
    rc, plan, err = plan_scene(scene, tmp_path)
    assert rc == 0 and plan["status"] == "ok", err
    assert "clearance_m" in plan and plan["clearance_m"] is None


def test_a_point_beyond_reach_bounds_the_claim(tmp_path):
    """A point the planner ignores as out of reach still limits the claim:
    its distance from the base less how far out the arm reaches (here
    stretched: its whole length and radius), within the 4 mm slack."""
    arm = oracle.Arm({})
    length = sum(arm.links) + max(arm.radii)
    far = length + arm.margin + 0.03
    scene = {"version": 1, "points": [[far, 0.0, 0.0]],
             "start": {"joints_deg": [-90, 0, 0]},
             "goal": {"joints_deg": [-90, 10, 0]}}
    rc, plan, err = plan_scene(scene, tmp_path)
    assert rc == 0 and plan["status"] == "ok", err
    assert plan["stats"]["points_ignored"] == 1
    assert far - length - 0.004 - 1e-9 <= plan["clearance_m"] <= \
        far - length + 1e-9
    assert oracle.check_path(scene, plan, np.asarray(scene["points"])).safe


def test_the_oracle_refuses_wrong_claims(tmp_path):
    scene = json.loads((SCENES / "table4_one_sphere.json").read_text())
    rc, plan, err = plan_scene(scene, tmp_path)
    assert rc == 0, err
    pts = np.asarray(scene["points"], float)
    assert oracle.check_path(scene, plan, pts).safe
    least = oracle_least(scene, plan)
    margin = oracle.Arm(scene).margin
    for claim, says in ((least + 0.001, "above the least"),
                        (least - 0.008, "mm below"),
                        (margin * 0.5, "below the margin"),
                        (None, "null but")):
        wrong = dict(plan, clearance_m=claim)
        assert says in str(oracle.check_path(scene, wrong, pts)), claim
