"""A tool on the arm (docs/spec.md §Arm, Tool; §Collision): the scene's
arm.tool is a fourth capsule beyond the end effector, collinear with link 3,
and every ok plan keeps it clear of the points by the independent oracle
(tools/oracle.py, which checks the four capsules); an obstacle only the tool
can touch is avoided; "aim": "tool_tip" puts the tip on the goal point;
bad tool values and aims are refused (exit 2, one line)."""
import copy
import json
import os

import numpy as np
import pytest

import oracle
import scenes
from conftest import plan_scene

SEED = int(os.environ.get("QRT_SEED", "20261207"))
N_SCENES = int(os.environ.get("QRT_TOOL_SCENES", "96"))
FAMILIES = ("spheres", "boxes", "walls", "shelf", "varied", "tunnel")


def with_tool(scene, length, radius):
    scene = copy.deepcopy(scene)
    scene.setdefault("arm", {})["tool"] = {"length_m": length,
                                          "radius_m": radius}
    return scene


def free_targets(scene, rng):
    """Start and goal (joints, or a point for the end effector or the tool
    tip) resampled until the oracle, given the tool, finds the start's and
    a joints goal's configuration clear."""
    arm = oracle.Arm(scene)
    pts = np.asarray(scene["points"], float)
    for _ in range(40):
        start, goal = scenes.targets(rng, scenes.scene_limits(scene))
        if "xyz_m" in goal and rng.uniform() < 0.5:
            # a point the tip reaches: some configuration's tip
            q = scenes.random_joints(rng, scenes.scene_limits(scene))
            goal = {"xyz_m": arm.tip(q).round(6).tolist(), "aim": "tool_tip"}
        q = [start["joints_deg"]]
        if "joints_deg" in goal:
            q.append(goal["joints_deg"])
        if oracle.clearances(arm, q, pts).min() > 0.0:
            scene["start"], scene["goal"] = start, goal
            return True
    return False


def random_tool_scenes():
    """Seeded scenes of several families with a tool: short and thin, or
    long (up to 0.45 m, reaching past what the links pass) and wider than
    link 3."""
    out = []
    for i in range(N_SCENES):
        seed = SEED + i
        rng = np.random.default_rng(seed)
        family = FAMILIES[i % len(FAMILIES)]
        scene = scenes.make_scene(family, seed)
        length = float(rng.uniform(0.05, 0.45))
        radius = float(rng.choice([0.0, rng.uniform(0.005, 0.05)]))
        scene = with_tool(scene, round(length, 4), round(radius, 4))
        if free_targets(scene, rng):
            out.append((f"{family}-{seed}", scene))
    return out


def test_random_scenes_with_a_tool_are_safe(qrtplan, tmp_path):
    """Every ok plan is safe by the oracle, which checks the tool; and the
    tool matters: in some of these scenes the same arm without its tool
    plans a path that the tool would collide on."""
    statuses, tool_matters, unsafe = {}, 0, []
    cases = random_tool_scenes()
    assert len(cases) >= N_SCENES // 2, len(cases)
    for k, (name, scene) in enumerate(cases):
        flags = ["--whole-mask"] if k % 2 else []
        rc, plan, err = plan_scene(scene, tmp_path, *flags, name=name)
        assert rc == 0, (name, err)
        statuses[plan["status"]] = statuses.get(plan["status"], 0) + 1
        pts = np.asarray(scene["points"], float)
        if plan["status"] == "ok":
            res = oracle.check_path(scene, plan, pts)
            if not res.safe:
                unsafe.append((name, str(res)))
        # the same scene without the tool (a tip goal then aims Pe there)
        bare = copy.deepcopy(scene)
        del bare["arm"]["tool"]
        bare["goal"].pop("aim", None)
        rc, bare_plan, err = plan_scene(bare, tmp_path, name=name + "-bare")
        assert rc == 0, (name, err)
        if bare_plan["status"] == "ok":
            q = oracle.sample_path(oracle.Arm(scene),
                                   bare_plan["waypoints_deg"])
            if oracle.clearances(oracle.Arm(scene), q, pts).min() < 0.0:
                tool_matters += 1
    print(f"seed {SEED}: {len(cases)} scenes, {statuses}; the tool would "
          f"collide on {tool_matters} plans of the bare arm")
    assert not unsafe, unsafe[:3]
    assert statuses.get("ok", 0) >= len(cases) // 4, statuses
    assert tool_matters >= 3, tool_matters


def beyond_the_links(length=0.3, radius=0.02):
    """A ball of points 1.1 m out at alpha 0, beyond what the links reach
    (0.96 m, 0.99 m with radius and margin), on the path of a tool that
    sweeps from alpha -60 to 60 with the arm straight."""
    ball = scenes.sphere_points([1.1, 0.0, 0.0], 0.04, spacing=0.01)
    return {"version": 1,
            "arm": {"tool": {"length_m": length, "radius_m": radius}},
            "points": np.round(ball, 6).tolist(),
            "start": {"joints_deg": [-60, 0, 0]},
            "goal": {"joints_deg": [60, 0, 0]}}


def wall_behind_the_links():
    """A wall across the arm's plane that the links pass under and the tool
    reaches: the arm straight and level at 0.96 m; the wall from 1.0 m to
    1.3 m out, from 0.05 m below link 3's line to 0.5 m above."""
    wall = scenes.rect_points([1.0, -0.3, -0.05], [0.0, 0.6, 0.0],
                              [0.0, 0.0, 0.55], spacing=0.02)
    wall = np.vstack([wall, wall + [0.3, 0.0, 0.0]])
    return {"version": 1,
            "arm": {"tool": {"length_m": 0.35, "radius_m": 0.03}},
            "points": np.round(wall, 6).tolist(),
            "start": {"joints_deg": [-70, 0, 0]},
            "goal": {"joints_deg": [70, 0, 0]}}


@pytest.mark.parametrize("make", [beyond_the_links, wall_behind_the_links])
@pytest.mark.parametrize("flags", [[], ["--whole-mask"]])
def test_an_obstacle_only_the_tool_touches_is_avoided(qrtplan, tmp_path,
                                                      make, flags):
    """The straight motion is free for the links and collides for the
    tool: the plan goes round (or is blocked), never through, by the
    oracle given the tool; without the tool the same scene's plan is the
    straight motion, which the tool would collide on."""
    scene = make()
    pts = np.asarray(scene["points"], float)
    arm = oracle.Arm(scene)
    straight = oracle.sample_path(arm, [scene["start"]["joints_deg"],
                                        scene["goal"]["joints_deg"]])
    assert oracle.clearances(arm, straight, pts).min() < 0.0
    bare = copy.deepcopy(scene)
    del bare["arm"]
    rc, plan, err = plan_scene(bare, tmp_path, *flags, name="bare")
    assert rc == 0, err
    assert plan["status"] == "ok" and len(plan["waypoints_deg"]) == 2, plan
    rc, plan, err = plan_scene(scene, tmp_path, *flags)
    assert rc == 0, err
    assert plan["status"] in ("ok", "no_path"), plan
    # the reach that keeps points counts the tool (docs/spec.md §Collision)
    tool = scene["arm"]["tool"]
    reach = 0.96 + tool["length_m"] + max(0.02, tool["radius_m"]) + 0.01
    far = np.linalg.norm(pts, axis=1)
    assert not np.any(np.abs(far - reach) < 1e-6)
    assert plan["stats"]["points_ignored"] == np.count_nonzero(far > reach)
    assert np.count_nonzero(far > 0.99) > 0
    if plan["status"] == "ok":
        res = oracle.check_path(scene, plan, pts)
        assert res.safe, str(res)
        assert len(plan["waypoints_deg"]) > 2


TIP_GOALS = [[0.5, 0.4, 0.3], [-0.6, 0.2, 0.5], [0.0, 0.0, 1.0],
             [0.3, -0.7, -0.2], [0.9, 0.0, 0.3]]


@pytest.mark.parametrize("goal", TIP_GOALS)
@pytest.mark.parametrize("ik", [{}, {"facing": "front", "elbow": "up"},
                                {"elbow": "down"}])
def test_aim_tool_tip_puts_the_tip_on_the_goal(qrtplan, tmp_path, goal, ik):
    """The tip, by the oracle's own kinematics (Pe + L (Pe - P2)/|Pe - P2|),
    lies within 1e-6 m of the goal; the branch reported is the one the
    oracle measures on the tip arm, and the one asked for; Pe itself is
    elsewhere."""
    scene = {"version": 1,
             "arm": {"tool": {"length_m": 0.15, "radius_m": 0.01}},
             "points": [[-0.5, -0.5, -0.3]],
             "start": {"joints_deg": [0, 30, -30]},
             "goal": {"xyz_m": goal, "aim": "tool_tip"}}
    if ik:
        scene["goal"]["ik"] = ik
    rc, plan, err = plan_scene(scene, tmp_path)
    assert rc == 0, err
    if plan["status"] == "unreachable":
        assert ik, plan  # only a branch asked for may be out of the limits
        return
    assert plan["status"] == "ok", plan
    arm = oracle.Arm(scene)
    tip = arm.tip(plan["goal_deg"])
    assert np.linalg.norm(tip - goal) <= 1e-6, (tip, goal)
    assert plan["waypoints_deg"][-1] == plan["goal_deg"]
    pe = arm.joints(plan["goal_deg"])[0, 3]
    assert np.linalg.norm(pe - goal) > 0.14
    res = oracle.check_path(scene, plan, np.asarray(scene["points"], float))
    assert res.safe, str(res)


def test_aim_end_effector_is_the_default(qrtplan, tmp_path):
    scene = {"version": 1,
             "arm": {"tool": {"length_m": 0.15, "radius_m": 0.01}},
             "points": [],
             "start": {"joints_deg": [0, 30, -30]},
             "goal": {"xyz_m": [0.5, 0.4, 0.3]}}
    for aim in (None, "end_effector"):
        if aim:
            scene["goal"]["aim"] = aim
        rc, plan, err = plan_scene(scene, tmp_path)
        assert rc == 0 and plan["status"] == "ok", (err, plan)
        pe = oracle.Arm(scene).joints(plan["goal_deg"])[0, 3]
        assert np.linalg.norm(pe - [0.5, 0.4, 0.3]) <= 1e-6


BAD = [
    ({"tool": {"length_m": -0.1, "radius_m": 0.02}},
     "arm.tool.length_m = -0.1 is outside [0, 100]"),
    ({"tool": {"length_m": 0.1, "radius_m": -0.02}},
     "arm.tool.radius_m = -0.02 is outside [0, 10]"),
    ({"tool": {"length_m": 101, "radius_m": 0.02}},
     "arm.tool.length_m = 101 is outside [0, 100]"),
    ({"tool": {"length_m": "NaN", "radius_m": 0.02}},
     "arm.tool.length_m must be a number, not string"),
    ({"tool": {"length_m": 0.1, "radius_m": "inf"}},
     "arm.tool.radius_m must be a number, not string"),
    ({"tool": {"length_m": 0.1}}, 'missing field "radius_m" in arm.tool'),
    ({"tool": {"length_m": 0.1, "radius_m": 0.02, "mass_kg": 1}},
     'unknown field "mass_kg" in arm.tool (valid: length_m, radius_m)'),
    ({"tool": {"length_m": 0, "radius_m": 0.02}},
     "arm.tool.radius_m = 0.02 needs a length_m above 0 (a tool of length 0 "
     "is no tool)"),
    ({"tool": [0.1, 0.02]},
     "arm.tool must be an object with length_m and radius_m, not array"),
    ({"tools": {"length_m": 0.1, "radius_m": 0.02}},
     'unknown field "tools" in arm (valid: links_m, link_radius_m, '
     'limits_deg, tool)'),
]


@pytest.mark.parametrize("arm,message", BAD, ids=[m[:30] for _, m in BAD])
def test_bad_tool_values_are_refused(qrtplan, tmp_path, arm, message):
    scene = {"arm": arm, "points": [], "start": {"joints_deg": [0, 0, 0]},
             "goal": {"joints_deg": [10, 0, 0]}}
    rc, plan, err = plan_scene(scene, tmp_path)
    assert rc == 2 and plan is None
    assert err.strip().splitlines() == [f"qrtplan: {tmp_path}/scene.json: "
                                        f"{message}"], err


@pytest.mark.parametrize("key,target,message", [
    ("goal", {"xyz_m": [0.5, 0, 0], "aim": "tip"},
     'goal.aim is "tip"; valid: "end_effector", "tool_tip"'),
    ("goal", {"xyz_m": [0.5, 0, 0], "aim": 1},
     'goal.aim must be a string, not number (valid: "end_effector", '
     '"tool_tip")'),
    ("start", {"joints_deg": [0, 0, 0], "aim": "tool_tip"},
     "start.aim applies only to xyz_m (joints_deg names one configuration)"),
])
def test_bad_aims_are_refused(qrtplan, tmp_path, key, target, message):
    scene = {"arm": {"tool": {"length_m": 0.1, "radius_m": 0.02}},
             "points": [], "start": {"joints_deg": [0, 0, 0]},
             "goal": {"joints_deg": [10, 0, 0]}}
    scene[key] = target
    rc, plan, err = plan_scene(scene, tmp_path)
    assert rc == 2 and plan is None
    assert err.strip().splitlines() == [f"qrtplan: {tmp_path}/scene.json: "
                                        f"{message}"], err


def test_oracle_reads_the_tool(tmp_path):
    """The oracle's own check, without the planner: the straight sweep past
    the ball is safe for the bare arm and collides for the arm with the
    tool."""
    scene = beyond_the_links()
    pts = np.asarray(scene["points"], float)
    wps = [scene["start"]["joints_deg"], scene["goal"]["joints_deg"]]
    bare = copy.deepcopy(scene)
    del bare["arm"]
    for s, safe in ((bare, True), (scene, False)):
        plan = {"status": "ok", "waypoints_deg": wps,
                "cost_deg": oracle.path_length(oracle.Arm(s), wps)}
        assert oracle.check_path(s, plan, pts).safe == safe
    # a tool length or radius that is not finite: never called safe
    for tool in ({"length_m": float("nan"), "radius_m": 0.02},
                 {"length_m": 0.3, "radius_m": float("nan")},
                 {"length_m": float("inf"), "radius_m": 0.02}):
        s = dict(bare, arm={"tool": tool})
        assert not oracle.check_path(s, plan, pts).safe, tool
    # a tool without its radius: nothing checked, nothing called safe
    path, plan_path = tmp_path / "scene.json", tmp_path / "plan.json"
    path.write_text(json.dumps(dict(scene, arm={"tool": {"length_m": 0.1}})))
    plan_path.write_text(json.dumps(plan))
    assert oracle.main(["oracle", str(path), str(plan_path)]) == 2
