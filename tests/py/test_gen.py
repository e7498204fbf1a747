"""`qrtplan gen`: the paper's obstacle family, inline or as PCD files that the
written scene can find wherever the two files are put."""
import json

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
