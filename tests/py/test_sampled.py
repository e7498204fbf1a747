"""The sampled fallback (docs/spec.md §Sampled fallback): where the lattice
has no path, two trees of proved straight motions grow between the ends.

- On seeded random scenes of every family, on a 20-degree lattice (whose
  cells close many passages), each scene is planned with the fallback and
  without it (`--sample-draws 0`). A scene the lattice solves gets the
  same plan both ways (the fallback runs only on no_path, or on a free end
  the lattice cannot join); every
  path the fallback finds is checked by the independent oracle along its
  whole motion, clearance claim included; and some scenes must be solved
  this way, so the check is not vacuous.
- The dense confined families (slots, shelves, cells, windows; 2*10^4
  points): every scene with clear ends is solved, and every path is safe.
- The three dense scenes whose passages the 5-degree lattice cannot prove
  (cell-2, window-0, window-2 of tools/dense_scenes.py) are solved, safely.
- The answer is a function of the input: the same bytes twice.
- A goal sealed in a sleeve of points is not joined after the whole budget
  of draws: the fallback runs, and the status stays what it was.
- --sample-draws is checked like every option."""
import json
import os
import subprocess
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import dense_scenes
import oracle
import scenes
from conftest import BIN, plan_scene
from test_safety import free_targets

SEED = int(os.environ.get("QRT_SEED", "20261207"))
PER_FAMILY = int(os.environ.get("QRT_SAMPLED_PER_FAMILY", "40"))
SAMPLED = "path found by sampling (none through the lattice)"
# the dense confined families of tools/dense_scenes.py, thinned
DENSE_POINTS, DENSE_SEEDS = 20000, 12


def without_times(plan):
    plan = dict(plan)
    plan["stats"] = {k: v for k, v in plan["stats"].items() if k != "time_us"}
    return plan


def coarse_scene(family, seed):
    """A random scene on a 20-degree lattice, whose cells sweep tens of
    centimetres, so that the lattice closes many passages that exist."""
    scene = scenes.make_scene(family, seed)
    scene["grid_deg"] = 20.0
    free_targets(scene, np.random.default_rng(seed + 1))
    return scene


def run_both(args):
    family, seed, out = args
    scene = coarse_scene(family, seed)
    rc0, lattice, err0 = plan_scene(scene, out, "--sample-draws", "0",
                                    name=f"{family}-{seed}")
    rc1, plan, err1 = plan_scene(scene, out, name=f"{family}-{seed}")
    assert rc0 == 0 and rc1 == 0, (family, seed, err0, err1)
    verdict = None
    if plan["status"] == "ok" and plan["detail"] == SAMPLED:
        verdict = str(oracle.check_path(scene, plan,
                                        np.asarray(scene["points"], float)))
    return family, seed, lattice, plan, verdict


@pytest.fixture(scope="module")
def planned(qrtplan, tmp_path_factory):
    out = tmp_path_factory.mktemp("sampled")
    jobs = [(f, SEED + 1000 * i + k, str(out))
            for i, f in enumerate(scenes.FAMILIES) for k in range(PER_FAMILY)]
    with ProcessPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        return list(pool.map(run_both, jobs, chunksize=4))


STRANDED = ("start is free but no move from it to the lattice can be proved "
            "safe",
            "goal is free but no move to it from the lattice can be proved safe")


def test_the_fallback_runs_only_where_the_lattice_has_no_path(planned):
    # no path through the lattice, or a free end the lattice cannot join
    def wanted(lattice):
        return (lattice["status"] == "no_path" or
                lattice["detail"] in STRANDED)
    changed = [(f, s) for f, s, lattice, plan, _ in planned
               if not wanted(lattice) and
               without_times(lattice) != without_times(plan)]
    assert not changed, f"plans changed by the fallback: {changed[:5]}"
    ran = [(f, s, lattice, plan) for f, s, lattice, plan, _ in planned
           if wanted(lattice)]
    for f, s, lattice, plan in ran:
        assert lattice["stats"]["sampled_nodes"] == 0
        assert plan["stats"]["sampled_nodes"] >= 2, (f, s)
        # what the fallback did not solve keeps the lattice's status
        if plan["status"] != "ok":
            assert plan["status"] == lattice["status"], (f, s)
    assert ran, "no scene for the fallback"


def test_every_sampled_path_is_safe(planned):
    sampled = [r for r in planned if r[4] is not None]
    unsafe = [(f, s, v) for f, s, _, _, v in sampled if not v.startswith("safe")]
    no_path = sum(r[2]["status"] == "no_path" for r in planned)
    stranded = sum(r[2]["detail"] in STRANDED for r in planned)
    print(f"{len(planned)} scenes: {no_path} no_path on the lattice and "
          f"{stranded} with an end it cannot join; {len(sampled)} of them "
          f"solved by sampling")
    assert not unsafe, f"unsafe sampled paths: {unsafe[:5]}"
    # not vacuous: these families have passages the lattice closes
    assert len(sampled) >= 3, f"only {len(sampled)} scenes solved by sampling"
    for _, _, _, plan, _ in sampled:
        assert plan["stats"]["lattice_path_nodes"] == 0
        assert plan["stats"]["lattice_cost_deg"] >= plan["cost_deg"] - 1e-6


def run_dense(args):
    family, seed, out = args
    made = dense_scenes.make(family, seed, out, n_points=DENSE_POINTS,
                             clear_m=0.002 if seed % 2 else 0.022)
    if made is None:
        return family, seed, None, None
    path, scene, pts, _ = made
    r = subprocess.run([str(BIN), "plan", path], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    plan = json.loads(r.stdout)
    verdict = None
    if plan["status"] == "ok":
        verdict = str(oracle.check_path(scene, plan, pts))
    return family, seed, plan, verdict


def test_dense_confined_scenes_are_solved_and_safe(qrtplan, tmp_path):
    jobs = [(f, seed, str(tmp_path)) for f in sorted(dense_scenes.FAMILIES)
            for seed in range(DENSE_SEEDS)]
    with ProcessPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        rows = [r for r in pool.map(run_dense, jobs) if r[2] is not None]
    sampled = [r for r in rows if r[2]["detail"] == SAMPLED]
    print(f"{len(rows)} dense scenes of {DENSE_POINTS} points with clear ends: "
          f"{len(sampled)} solved by sampling; statuses "
          f"{sorted(r[2]['status'] for r in rows)}")
    unsafe = [(f, s, v) for f, s, p, v in rows
              if p["status"] == "ok" and not v.startswith("safe")]
    assert not unsafe, f"unsafe plans: {unsafe[:5]}"
    unsolved = [(f, s, p["status"], p["detail"]) for f, s, p, _ in rows
                if p["status"] != "ok"]
    assert not unsolved, f"dense scenes with clear ends not solved: {unsolved}"
    assert len(sampled) >= 5, f"only {len(sampled)} solved by sampling"


@pytest.mark.parametrize("family,seed", [("cell", 2), ("window", 0),
                                         ("window", 2)])
def test_the_dense_passages_the_lattice_cannot_prove_are_crossed(
        qrtplan, tmp_path, family, seed):
    clear = 0.002 if seed % 2 else 0.022  # as tests/py/test_dense.py makes them
    path, scene, pts, _ = dense_scenes.make(family, seed, str(tmp_path),
                                            clear_m=clear)
    plans = []
    for draws in ("0", "2000"):
        r = subprocess.run([str(BIN), "plan", path, "--sample-draws", draws],
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        plans.append(json.loads(r.stdout))
    assert plans[0]["status"] == "no_path"
    assert plans[1]["status"] == "ok" and plans[1]["detail"] == SAMPLED, (
        plans[1]["status"], plans[1]["detail"])
    res = oracle.check_path(scene, plans[1], pts)
    assert res.safe, str(res)


def test_the_same_input_gives_the_same_plan(planned, tmp_path):
    family, seed = next((f, s) for f, s, _, _, v in planned if v is not None)
    scene = coarse_scene(family, seed)
    outs = []
    for _ in range(2):
        rc, plan, err = plan_scene(scene, tmp_path)
        assert rc == 0, err
        outs.append(without_times(plan))
    assert outs[0] == outs[1]
    assert outs[0]["detail"] == SAMPLED


def tube_points(p, q, radius, spacing):
    """Rings of points round the segment p -> q, radius away from it."""
    d = q - p
    length = np.linalg.norm(d)
    u = d / length
    e1 = np.cross(u, [0.0, 0.0, 1.0] if abs(u[2]) < 0.9 else [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    around = max(8, int(2 * np.pi * radius / spacing))
    phi = np.linspace(0, 2 * np.pi, around, endpoint=False)
    ring = radius * (np.outer(np.cos(phi), e1) + np.outer(np.sin(phi), e2))
    return np.concatenate([p + t * u + ring
                           for t in np.arange(0.0, length + 1e-9, spacing)])


def test_a_goal_sealed_in_a_sleeve_is_not_joined_after_every_draw(
        qrtplan, tmp_path):
    # a sleeve of points 5 mm outside links 2 and 3 (and the margin) at the
    # goal, closed past the tip: the goal is free, every motion out of it
    # collides within a fraction of a degree, so nothing joins it, neither
    # the lattice nor the fallback's trees, which do run
    goal = [0.0, 60.0, -60.0]
    scene = {"version": 1, "start": {"joints_deg": [150.0, 60.0, -60.0]},
             "goal": {"joints_deg": goal}}
    arm = oracle.Arm(scene)
    p = arm.joints(np.asarray([goal], float))[0]
    gap = arm.radii.max() + arm.margin + 0.005
    shoulder = p[1] + 0.1 * (p[2] - p[1]) / np.linalg.norm(p[2] - p[1])
    tip_dir = (p[3] - p[2]) / np.linalg.norm(p[3] - p[2])
    pts = np.concatenate([tube_points(shoulder, p[2], gap, 0.008),
                          tube_points(p[2], p[3] + gap * tip_dir, gap, 0.008),
                          tube_points(p[3] + gap * tip_dir,
                                      p[3] + (gap + 0.001) * tip_dir, 0.5 * gap,
                                      0.008),
                          [p[3] + gap * tip_dir]])
    # where the two sleeves meet at the elbow, each one's rings run inside
    # the other: keep only the points of the union's surface
    near = oracle.segment_distances(pts, p[:3], p[1:]).min(axis=0)
    pts = pts[near >= gap - 1e-9]
    scene["points"] = pts.tolist()
    assert oracle.clearances(arm, [goal], pts).min() > 0.004
    rc, plan, err = plan_scene(scene, tmp_path, "--sample-draws", "300")
    assert rc == 0, err
    assert plan["status"] == "goal_blocked", (plan["status"], plan["detail"])
    assert plan["detail"] == STRANDED[1], plan["detail"]
    assert 2 <= plan["stats"]["sampled_nodes"] <= 4096


@pytest.mark.parametrize("value", ["-1", "1000001", "2k", "", "1e3"])
def test_bad_sample_draws_are_refused(qrtplan, value):
    scene = Path(__file__).resolve().parents[2] / "scenes" / "three_spheres.json"
    r = subprocess.run([str(BIN), "plan", str(scene), "--sample-draws", value],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert "--sample-draws takes a whole number from 0 to 1000000" in r.stderr
