"""The installed Python package (issue 38): plans equal to the CLI's, safe
by the oracle, and bad input refused with a clear exception.

Run by tests/pkg/fresh_venv.sh in a new virtualenv where `pip install .`
put the package (never python/ of the source tree: the first test checks).
QRTPLAN_BIN: the CLI to compare with; QRT_SOURCE_DIR: the repository.
"""
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import qrtplan
from qrtplan import kinematics as kin

ROOT = Path(os.environ.get("QRT_SOURCE_DIR", Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(ROOT / "tools"))
import oracle  # noqa: E402

BIN = os.environ.get("QRTPLAN_BIN", str(ROOT / "build" / "bin" / "qrtplan"))


def cli_plan(scene, tmp_path, *flags):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    r = subprocess.run([BIN, "plan", str(path), *flags], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    plan = json.loads(r.stdout)
    del plan["stats"]["time_us"]
    return plan


def assert_same(py, cli):
    """Same status, detail, waypoints and clearance_m (bit for bit: the
    CLI prints the shortest decimal that reads back exactly; null when
    there is no point), cost and stats (the CLI prints those to 6
    decimals)."""
    d = py.to_dict()
    assert d["status"] == cli["status"]
    assert d["detail"] == cli["detail"]
    assert sorted(d) == sorted(cli)
    for key in cli:
        if key == "clearance_m":  # equal as floats (the CLI prints 0.0 as 0), or both null
            assert (d[key] is None) == (cli[key] is None), key
            assert d[key] is None or float(d[key]) == float(cli[key]), key
            assert d[key] == py.clearance_m
        elif key in ("cost_deg", "end_clearance_m"):
            assert abs(d[key] - cli[key]) <= 5e-7, key
        elif key == "stats":
            for k, v in cli["stats"].items():
                if isinstance(v, float) or isinstance(d["stats"][k], float):
                    assert abs(d["stats"][k] - v) <= 5e-7 * max(1, abs(v)), k
                else:
                    assert d["stats"][k] == v, k
            assert sorted(d["stats"]) == sorted(cli["stats"])
        else:
            assert d[key] == cli[key], key


def test_installed_not_source():
    where = Path(qrtplan.__file__).resolve()
    assert str(where).startswith(str(Path(sys.prefix).resolve())), where
    assert (where.parent / "_qrtcore.so").is_file()


@pytest.mark.parametrize("name", ["table4_one_sphere", "three_spheres", "ten_spheres"])
@pytest.mark.parametrize("whole", [False, True])
def test_paper_scenes_as_cli(name, whole, tmp_path):
    scene = json.loads((ROOT / "scenes" / f"{name}.json").read_text())
    py = qrtplan.plan_scene(scene, whole_mask=whole)
    assert_same(py, cli_plan(scene, tmp_path, *(["--whole-mask"] if whole else [])))
    assert py.ok
    res = oracle.check_path(scene, py.to_dict(), np.asarray(scene["points"], float))
    assert res.safe, str(res)


def sphere(rng, c, r, n):
    v = rng.normal(size=(n, 3))
    return c + r * v / np.linalg.norm(v, axis=1)[:, None]


def random_scene(rng, i):
    """Spheres of points around the arm; joints or xyz ends (some with an
    IK branch or the tool tip), a tool on some arms, grids 5-15 degrees."""
    arm = {}
    if i % 4 == 3:
        arm["tool"] = {"length_m": round(float(rng.uniform(0.02, 0.15)), 3),
                       "radius_m": round(float(rng.uniform(0.0, 0.03)), 3)}
    pts = [sphere(rng, rng.uniform([-0.8, -0.8, -0.3], [0.8, 0.8, 0.8]),
                  rng.uniform(0.05, 0.2), int(rng.integers(50, 400)))
           for _ in range(int(rng.integers(0, 5)))]
    pts = np.round(np.concatenate(pts) if pts else np.empty((0, 3)), 6)

    def end(k):
        if k % 3 == 2:
            t = {"xyz_m": [round(float(x), 4) for x in rng.uniform([-0.7, -0.7, -0.2],
                                                                  [0.7, 0.7, 0.7])]}
            if rng.random() < 0.5:
                t["ik"] = {"facing": str(rng.choice(["any", "front", "back"])),
                           "elbow": str(rng.choice(["any", "up", "down"]))}
            if "tool" in arm and rng.random() < 0.5:
                t["aim"] = "tool_tip"
            return t
        lim = oracle.DEFAULT_LIMITS
        return {"joints_deg": [round(float(rng.uniform(lo, hi)), 3) for lo, hi in lim]}
    return {"version": 1, "arm": arm, "margin_m": float(rng.choice([0.0, 0.01, 0.03])),
            "grid_deg": float(rng.choice([5, 10, 15])), "points": pts.tolist(),
            "start": end(i), "goal": end(i + 1 + int(rng.integers(0, 2)))}


@pytest.mark.parametrize("seed", range(24))
def test_random_scenes_as_cli(seed, tmp_path):
    rng = np.random.default_rng(3800 + seed)
    scene = random_scene(rng, seed)
    py = qrtplan.plan_scene(scene, whole_mask=bool(seed % 2))
    assert_same(py, cli_plan(scene, tmp_path, *(["--whole-mask"] if seed % 2 else [])))
    if py.ok:
        res = oracle.check_path(scene, py.to_dict(), np.asarray(scene["points"], float))
        assert res.safe, str(res)


def test_planner_reused_and_one_shot(tmp_path):
    scene = json.loads((ROOT / "scenes" / "three_spheres.json").read_text())
    pts = np.asarray(scene["points"])
    p = qrtplan.Planner()
    a = p.plan(pts, [-90, 0, 0], [90, 0, 0])
    b = p.plan(np.empty((0, 3)), [-90, 0, 0], [90, 0, 0])  # points replaced
    c = p.plan(pts, qrtplan.Joints(-90, 0, 0), {"joints_deg": [90, 0, 0]})
    assert a.ok and b.ok and len(b.waypoints_deg) == 2
    # clearance: certified with points (at least the margin), None with none
    assert isinstance(a.clearance_m, float) and a.clearance_m >= 0.01
    assert b.clearance_m is None and b.to_dict()["clearance_m"] is None
    assert np.array_equal(a.waypoints_deg, c.waypoints_deg) and a.cost_deg == c.cost_deg
    d = qrtplan.plan(pts, [-90, 0, 0], [90, 0, 0], margin_m=0.01, grid_deg=5)
    assert np.array_equal(a.waypoints_deg, d.waypoints_deg)
    assert a.waypoints_deg.dtype == np.float64 and a.waypoints_deg.shape[1] == 3


def test_dtypes_converted_exactly():
    scene = json.loads((ROOT / "scenes" / "table4_one_sphere.json").read_text())
    p32 = np.asarray(scene["points"], np.float32)
    p = qrtplan.Planner()
    a = p.plan(p32, [-90, 0, 0], [90, 0, 0])
    b = p.plan(p32.astype(np.float64), [-90, 0, 0], [90, 0, 0])
    assert np.array_equal(a.waypoints_deg, b.waypoints_deg)
    ints = p.plan(np.array([[2, 2, 2]], np.int32), [-90, 0, 0], [90, 0, 0])
    assert ints.ok and ints.stats["points"] + ints.stats["points_ignored"] == 1
    f = np.asfortranarray(np.asarray(scene["points"]))  # not C-contiguous
    assert np.array_equal(p.plan(f, [-90, 0, 0], [90, 0, 0]).waypoints_deg,
                          p.plan(np.ascontiguousarray(f), [-90, 0, 0], [90, 0, 0]).waypoints_deg)


@pytest.mark.parametrize("points", [np.zeros((4, 2)), np.zeros(3), np.zeros((2, 3, 1)),
                                    [[0, 0]], np.zeros((0, 2))])
def test_wrong_shape(points):
    with pytest.raises(qrtplan.InvalidInput, match=r"\(N, 3\)"):
        qrtplan.plan(points, [0, 0, 0], [10, 0, 0])


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_points(bad):
    pts = np.zeros((5, 3)) + 1.5
    pts[3, 1] = bad
    with pytest.raises(qrtplan.InvalidInput, match="row 3 .*non-finite value"):
        qrtplan.plan(pts, [0, 0, 0], [10, 0, 0])


@pytest.mark.parametrize("points", [np.zeros((2, 3), complex), np.zeros((2, 3), bool),
                                    np.array([["a", "b", "c"]]),
                                    np.array([[1, 2, None]], object),
                                    np.zeros((2, 3), np.float128)
                                    if hasattr(np, "float128") else np.zeros((2, 3), complex)])
def test_wrong_dtype(points):
    with pytest.raises(TypeError, match="dtype"):
        qrtplan.plan(points, [0, 0, 0], [10, 0, 0])


def test_bad_targets_and_settings():
    with pytest.raises(qrtplan.LimitsError, match="outside the arm's limits"):
        qrtplan.plan([], [0, -90, 0], [10, 0, 0])
    with pytest.raises(qrtplan.InvalidInput, match="finite"):
        qrtplan.plan([], [0, np.nan, 0], [10, 0, 0])
    with pytest.raises(qrtplan.InvalidInput, match="3 numbers"):
        qrtplan.plan([], [0, 0], [10, 0, 0])
    with pytest.raises(TypeError):
        qrtplan.plan([], "home", [10, 0, 0])
    with pytest.raises(qrtplan.InvalidInput, match="ik"):
        qrtplan.plan([], qrtplan.Point(0.5, 0, 0.3, facing="sideways"), [10, 0, 0])
    with pytest.raises(qrtplan.InvalidInput, match="grid_deg=7.0.*invalid input"):
        qrtplan.Planner(grid_deg=7)  # alpha wraps: 7 does not divide 360
    with pytest.raises(qrtplan.InvalidInput, match="invalid input"):
        qrtplan.Planner(margin_m=-1)
    with pytest.raises(qrtplan.InvalidInput):
        qrtplan.Planner(arm={"links_m": [0.1, -0.3, 0.5]})
    with pytest.raises(TypeError):
        qrtplan.Planner(margin_m="0.01")


def test_unreachable_is_a_result():
    r = qrtplan.plan([], [0, 0, 0], qrtplan.Point(5.0, 0, 0))
    assert r.status == "unreachable" and not r.ok and r.cost_deg is None
    assert r.clearance_m is None and "clearance_m" not in r.to_dict()
    assert r.waypoints_deg.shape == (0, 3) and r.detail


def test_more_points_than_the_table_warns():
    n = qrtplan._core.MAX_POINTS + 1000
    rng = np.random.default_rng(38)
    pts = sphere(rng, np.array([0.3, 0.0, -0.6]), 0.15, n)  # in reach, below
    with pytest.warns(qrtplan.planner.CapacityWarning, match="merged"):
        r = qrtplan.plan(pts, [-90, 0, 0], [90, 0, 0])
    assert r.stats["voxel_m"] > 0 and r.stats["points"] < n


def test_kinematics_as_oracle():
    rng = np.random.default_rng(7)
    for tool in (None, {"length_m": 0.1, "radius_m": 0.03}):
        scene = {"arm": {"tool": tool}} if tool else {}
        arm, ref = kin.Arm.from_scene(scene), oracle.Arm(scene)
        for _ in range(50):
            q = rng.uniform([-180, -40, -180], [180, 180, 140])
            p = kin.forward_points(arm, q)
            assert p.shape == (5, 3)
            assert np.allclose(p[:4], ref.joints(q)[0], atol=1e-12)
            assert np.allclose(p[4], ref.tip(q), atol=1e-12)
            caps = kin.capsules(arm, q)
            assert len(caps) == 3 and np.allclose(caps[2][1], p[4], atol=1e-12)
            assert caps[2][2] == max(0.02, tool["radius_m"] if tool else 0)
    assert kin.Arm.default().links_m == oracle.DEFAULT_LINKS
    with pytest.raises(qrtplan.LimitsError):
        kin.check_joints(kin.Arm.default(), [0, -90, 0])
    sols = kin.ik(kin.Arm.default(), [0.5, 0.2, 0.3])
    assert sols and all(np.allclose(kin.forward_points(kin.Arm.default(), q)[3],
                                    [0.5, 0.2, 0.3]) for q, _, _ in sols)


def test_lcm_types_round_trip():
    from qrtplan.lcmtypes import plan_request_t, plan_t
    m = plan_request_t()
    data = m.encode()
    assert plan_request_t.decode(data).encode() == data
    assert plan_t._get_packed_fingerprint()


def test_blocked_end_under_merged_points_as_cli(tmp_path):
    """More points than the exact table (the slot scene of
    tests/py/test_blocked_detail.py): the core holds merged points and
    cannot measure the blocked start; the package measures it against the
    caller's exact points, as the CLI does against the scene's, and both
    say the same (how clear, never "collides"); with a point inside the
    margin both say it collides."""
    sys.path.insert(0, str(ROOT / "tests" / "py"))
    from test_blocked_detail import slot_points, write_pcd
    pts = slot_points(int(2.3 * qrtplan._core.MAX_POINTS))
    for extra in (np.empty((0, 3)), np.array([[0.5, 0.025, 0.0]])):
        cloud = np.vstack([pts, extra])
        write_pcd(tmp_path / "slot.pcd", cloud)
        exact = np.asarray(cloud, np.float32).astype(np.float64)  # as the PCD holds them
        scene = {"version": 1, "points_file": "slot.pcd",
                 "start": {"joints_deg": [0.0, 0.0, 0.0]},
                 "goal": {"joints_deg": [90.0, 40.0, -60.0]}}
        path = tmp_path / "scene.json"
        path.write_text(json.dumps(scene))
        r = subprocess.run([BIN, "plan", str(path)], capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 0, r.stderr
        cli = json.loads(r.stdout)
        del cli["stats"]["time_us"]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", qrtplan.planner.CapacityWarning)
            py = qrtplan.Planner().plan(exact, [0, 0, 0], [90, 40, -60])
        assert py.status == "start_blocked" and py.end_clearance_m is not None
        assert ("collides" in py.detail) == (len(extra) > 0), py.detail
        assert_same(py, cli)


def test_planners_on_threads():
    """Two planners on two threads (the C call releases the GIL) and one
    planner shared by both (its lock) give the serial plans."""
    from concurrent.futures import ThreadPoolExecutor
    scenes = [json.loads((ROOT / "scenes" / f"{n}.json").read_text())
              for n in ("three_spheres", "ten_spheres")]
    pts = [np.asarray(s["points"]) for s in scenes]
    want = [qrtplan.plan(p, [-90, 0, 0], [90, 0, 0]).waypoints_deg for p in pts]
    shared = qrtplan.Planner()

    def run(k):
        own = qrtplan.Planner().plan(pts[k % 2], [-90, 0, 0], [90, 0, 0])
        common = shared.plan(pts[k % 2], [-90, 0, 0], [90, 0, 0])
        return k % 2, own.waypoints_deg, common.waypoints_deg
    with ThreadPoolExecutor(2) as ex:
        for k, own, common in ex.map(run, range(8)):
            assert np.array_equal(own, want[k]) and np.array_equal(common, want[k])
