"""Dense confined scenes (tools/dense_scenes.py: slots, shelves, cells,
windows; 5-12 mm point spacing, 5e4-3e5 points; the ends clear by the oracle):

- every ok plan, sampled at 0.1 degree per joint by the independent oracle,
  collides with nothing;
- no plan says a start or goal "collides" (each end is clear of every point
  by at least 2 mm beyond the margin, as the oracle measured it);
- every scene OMPL (RRTConnect or PRM, tools/bench_ompl) solves with 2 cm
  more margin than the scene's is solved. The 5-degree lattice alone cannot
  prove some of their passages free (its conservative raster blocks a node
  when any configuration in its cell collides, and a cell moves the tip by
  several centimetres: cell-2, window-0 and window-2 are no_path on it);
  the sampled fallback (docs/spec.md section Sampled fallback) crosses
  them.
"""
import csv
import json
import os
import subprocess
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

import dense_scenes
import oracle
from conftest import BIN

SEEDS = range(int(os.environ.get("QRT_DENSE_SEEDS", "3")))
OMPL = Path(os.environ.get("QRT_BENCH_OMPL", BIN.parent / "bench_ompl"))
EXTRA_M = 0.02  # OMPL's margin over the scene's


def plan(path):
    r = subprocess.run([str(BIN), "plan", str(path)], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, f"{path}: {r.stderr.strip()}"
    return json.loads(r.stdout)


def one(args):
    family, seed, out, clear_m = args
    made = dense_scenes.make(family, seed, out, clear_m=clear_m)
    if made is None:
        return family, seed, None, None, None
    path, scene, pts, _ = made
    p = plan(path)
    verdict = None
    if p["status"] == "ok":
        verdict = str(oracle.check_path(scene, p, pts))
    return family, seed, path, p, verdict


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    out = tmp_path_factory.mktemp("dense")
    # half the scenes with ends just clear (2 mm), half with room for OMPL's
    # extra margin at the ends (22 mm)
    jobs = [(f, s, str(out), 0.002 if s % 2 else 0.022)
            for f in sorted(dense_scenes.FAMILIES) for s in SEEDS]
    with ProcessPoolExecutor(max_workers=2) as ex:
        rows = list(ex.map(one, jobs))
    made = [r for r in rows if r[2] is not None]
    print(f"{len(made)} of {len(rows)} dense scenes had clear ends; statuses: "
          f"{sorted(r[3]['status'] for r in made)}")
    assert len(made) >= len(rows) // 2, "too few dense scenes with clear ends"
    return made


def test_every_ok_plan_is_safe(planned):
    oks = [r for r in planned if r[3]["status"] == "ok"]
    bad = [(r[0], r[1], r[4]) for r in oks if not r[4].startswith("safe")]
    assert not bad, f"unsafe plans: {bad}"


def test_no_end_said_to_collide_that_is_clear(planned):
    lies = [(r[0], r[1], r[3]["status"], r[3].get("detail"))
            for r in planned
            if r[3]["status"] in ("start_blocked", "goal_blocked") and
            "collides" in r[3].get("detail", "")]
    assert not lies, ("ends clear by the oracle said to collide: " +
                      "; ".join(map(str, lies)))


@pytest.mark.skipif(not OMPL.is_file(), reason=f"no {OMPL} (OMPL not built)")
def test_what_ompl_solves_with_more_margin_is_solved(planned, tmp_path):
    inflated = []
    for family, seed, path, p, _ in planned:
        scene = json.loads(Path(path).read_text())
        scene["margin_m"] = scene.get("margin_m", 0.01) + EXTRA_M
        scene["points_file"] = str(Path(path).parent / scene["points_file"])
        q = tmp_path / f"{family}-{seed}-inflated.json"
        q.write_text(json.dumps(scene))
        inflated.append((q, p, f"{family}-{seed}"))
    table = tmp_path / "ompl.csv"
    subprocess.run([str(OMPL), "--repeats", "1", "--time-limit", "2",
                    "--csv", str(table), *[str(q) for q, _, _ in inflated]],
                   check=True, capture_output=True, timeout=1200)
    solved = {r["scene"] for r in csv.DictReader(open(table))
              if r["planner"] in ("RRTConnect", "PRM") and r["success"] == "1"}
    missed = [(name, p["status"], p.get("detail")) for q, p, name in inflated
              if str(q) in solved and p["status"] != "ok"]
    print(f"OMPL solved {len(solved)} of {len(inflated)} with "
          f"{EXTRA_M * 100:.0f} cm more margin; missed by qrtplan: {missed}")
    assert not missed, ("solved by OMPL with more margin, not by "
                        f"qrtplan: {missed}")
