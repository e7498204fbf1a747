"""`qrtplan gen`: the paper's obstacle family, inline or as PCD files that the
written scene can find wherever the two files are put."""
import json

import pytest

from conftest import run_cli


def test_inline_scene_has_the_requested_points(qrtplan, tmp_path):
    out = tmp_path / "s.json"
    r = run_cli(["gen", "--spheres", "3", "--points", "100", "-o", out])
    assert r.returncode == 0, r.stderr
    scene = json.loads(out.read_text())
    assert len(scene["points"]) == 300
    r = run_cli(["plan", out])
    assert r.returncode == 0 and json.loads(r.stdout)["status"] == "ok"


def test_pcd_in_another_directory(qrtplan, tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for pcd_flag in ("--pcd", "--pcd-ascii"):
        pcd, scene = tmp_path / "a" / "c.pcd", tmp_path / "b" / "s.json"
        r = run_cli(["gen", "--points", "64", pcd_flag, pcd, "-o", scene])
        assert r.returncode == 0, r.stderr
        r = run_cli(["plan", scene])
        assert r.returncode == 0, r.stderr
        assert json.loads(r.stdout)["stats"]["points"] == 64


def test_pcd_beside_the_scene_is_named_relatively(qrtplan, tmp_path):
    pcd, scene = tmp_path / "c.pcd", tmp_path / "s.json"
    r = run_cli(["gen", "--points", "64", "--pcd", pcd, "-o", scene])
    assert r.returncode == 0, r.stderr
    assert json.loads(scene.read_text())["points_file"] == "c.pcd"


@pytest.mark.parametrize("option,value", [
    ("--radius", "nan"), ("--radius", "0"), ("--radius", "1e400"),
    ("--distance", "inf"), ("--height", "-nan"), ("--height", ""),
    ("--phase", "inf"), ("--start", "nan,0,0"), ("--goal", "1,2,inf"),
    ("--goal", "1,2"), ("--spheres", "4294967297"), ("--spheres", "2x"),
    ("--points", "3"),
    # read as every other number on the command line (src/cli/args.h): no
    # space that strtod would skip, nothing after the last number
    ("--start", "0, 0,0"), ("--goal", "1,2,3,"), ("--radius", " 1"),
    ("--spheres", " 2"),
])
def test_values_that_would_write_garbage_are_refused(qrtplan, tmp_path,
                                                     option, value):
    """A NaN or Inf in a layout value used to come out as `nan` in the
    scene's JSON (not JSON at all), and an out-of-range count wrapped."""
    out = tmp_path / "s.json"
    r = run_cli(["gen", option, value, "-o", out])
    assert r.returncode == 2
    assert f"bad value '{value}' for {option}" in r.stderr
    assert r.stderr.count("\n") == 1
    assert not out.exists()


def test_more_than_1e8_points_in_all_is_refused(qrtplan, tmp_path):
    """Each count is in range, their product is not (it would overflow a
    32-bit long on the ARM builds)."""
    out = tmp_path / "s.json"
    r = run_cli(["gen", "--spheres", "1000", "--points", "100000000", "-o", out])
    assert r.returncode == 2 and "beyond 1e8 points in all" in r.stderr
    assert not out.exists()


def test_every_accepted_layout_writes_json_the_planner_reads(qrtplan,
                                                              tmp_path):
    out = tmp_path / "s.json"
    r = run_cli(["gen", "--spheres", "2", "--points", "16", "--radius", "1000",
                 "--distance", "-1000", "--height", "1e3", "--phase", "-1e6",
                 "--start", "10,0,0", "--goal", "-10,5,5", "-o", out])
    assert r.returncode == 0, r.stderr
    scene = json.loads(out.read_text())
    assert len(scene["points"]) == 32
    assert scene["goal"]["joints_deg"] == [-10, 5, 5]
    r = run_cli(["plan", out])
    assert r.returncode == 0, r.stderr
