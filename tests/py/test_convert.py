"""python/qrtplan/convert.py: points (numpy, PCD) to scenes that qrtplan plan
takes and docs/schema/scene.schema.json accepts, the points read back
exactly (float64 inline, float32 or float64 in the PCD file, read back with
pypcd4, another implementation); refusals with a clear message; and
`qrtplan setpoints`' CSV as seen from outside (the C test
tests/canmaster/test_setpoints.c compares it with the master's motion):
header, rows every period, first and last rows the plan's ends, no row
pair past a joint's speed or acceleration, --wrap-alpha, refusals."""
import importlib.util
import json
import os
import subprocess
import sys

import jsonschema
import numpy as np
import pytest
from pypcd4 import PointCloud

from conftest import BIN, ROOT, run_cli

# the module by its file: build/lcmtypes/python's top-level `qrtplan` (the
# LCM classes other tests import) would shadow a namespace package
_spec = importlib.util.spec_from_file_location(
    "qrtplan_convert", ROOT / "python" / "qrtplan" / "convert.py")
convert = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(convert)

SCHEMA = json.loads((ROOT / "docs" / "schema" / "scene.schema.json")
                    .read_text())


@pytest.fixture(autouse=True)
def _binary(monkeypatch):
    monkeypatch.setenv("QRTPLAN_BIN", str(BIN))


def valid(scene):
    v = jsonschema.Draft202012Validator(SCHEMA)
    errors = [f"{list(e.absolute_path)}: {e.message}"
              for e in v.iter_errors(scene)]
    assert not errors, errors


def plan(path):
    r = run_cli(["plan", path])
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def cloud(n, seed=38):
    rng = np.random.default_rng(seed)
    # a blob in front of the arm, and numbers with all 53 bits in use
    return rng.normal([0.55, 0.0, 0.25], 0.05, (n, 3))


def test_small_cloud_inline_exact(tmp_path):
    pts = cloud(200)
    path = tmp_path / "s.json"
    scene = convert.scene_from_points(pts, [-100, 0, 0], [100, 0, 0],
                                      margin_m=0.02, path=path)
    written = json.loads(path.read_text())
    assert written == scene and "points_file" not in written
    valid(written)
    # float64 exactly, as JSON's shortest repr keeps it
    assert np.array_equal(np.array(written["points"]), pts)
    p = plan(path)
    assert p["status"] == "ok"
    st = p["stats"]
    assert st["points"] + st["points_ignored"] == 200
    assert p["waypoints_deg"][0] == [-100, 0, 0]
    assert p["waypoints_deg"][-1] == [100, 0, 0]


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_large_cloud_in_pcd_beside(tmp_path, dtype):
    pts = cloud(12000)
    path = tmp_path / "big.json"
    scene = convert.scene_from_points(
        pts, {"joints_deg": [-100, 0, 0]}, [100, 0, 0],
        arm={"links_m": [0.09, 0.332, 0.538]}, path=path, pcd_dtype=dtype)
    assert scene["points_file"] == "big.pcd" and "points" not in scene
    valid(json.loads(path.read_text()))
    back = PointCloud.from_path(tmp_path / "big.pcd").numpy(("x", "y", "z"))
    assert back.dtype == np.dtype(dtype)
    # float32: the points rounded to float32, exactly; float64: exactly
    assert np.array_equal(back, pts.astype(dtype))
    p = plan(path)
    assert p["status"] in ("ok", "no_path")
    st = p["stats"]
    assert st["points"] + st["points_ignored"] == 12000 or st["voxel_m"] > 0


def test_pcd_elsewhere_named_relative(tmp_path):
    pts = cloud(300).astype(np.float32)
    (tmp_path / "data").mkdir()
    (tmp_path / "scenes").mkdir()
    convert.write_pcd(tmp_path / "data" / "scan.pcd", pts)
    path = tmp_path / "scenes" / "s.json"
    scene = convert.scene_from_pcd(tmp_path / "data" / "scan.pcd",
                                   [-100, 0, 0], [100, 0, 0], path=path)
    assert scene["points_file"] == os.path.join("..", "data", "scan.pcd")
    valid(scene)
    p = plan(path)
    assert p["status"] == "ok"
    assert p["stats"]["points"] + p["stats"]["points_ignored"] == 300
    # without a scene file: the absolute path
    s2 = convert.scene_from_pcd(tmp_path / "data" / "scan.pcd", [0, 0, 0],
                                [10, 0, 0])
    assert os.path.isabs(s2["points_file"])


@pytest.mark.parametrize("points, message", [
    (np.zeros((4, 2)), "shape (N, 3)"),
    (np.zeros(3), "shape (N, 3)"),
    ([[0.5, 0, 0], [0.5, np.nan, 0]], "points[1]"),
    ([[0.5, 0, np.inf]], "not finite"),
    ([["a", "b", "c"]], "must be numbers"),
])
def test_bad_points_refused(points, message):
    with pytest.raises(convert.ConversionError, match=message.replace(
            "(", r"\(").replace(")", r"\)").replace("[", r"\[")
            .replace("]", r"\]")):
        convert.scene_from_points(points, [0, 0, 0], [10, 0, 0])


def test_bad_targets_and_float32_overflow(tmp_path):
    with pytest.raises(convert.ConversionError, match="three finite"):
        convert.scene_from_points(cloud(3), [0, np.nan, 0], [10, 0, 0])
    with pytest.raises(convert.ConversionError, match="three"):
        convert.scene_from_points(cloud(3), [0, 0], [10, 0, 0])
    with pytest.raises(convert.ConversionError, match="exactly one"):
        convert.scene_from_points(cloud(3), {"joints_deg": [0, 0, 0],
                                             "xyz_m": [0, 0, 1]}, [1, 0, 0])
    with pytest.raises(convert.ConversionError, match="margin_m"):
        convert.scene_from_points(cloud(3), [0, 0, 0], [1, 0, 0],
                                  margin_m=-1)
    huge = np.array([[1e39, 0, 0]] * 5)
    with pytest.raises(convert.ConversionError, match="float32"):
        convert.scene_from_points(huge, [0, 0, 0], [1, 0, 0],
                                  path=tmp_path / "h.json", inline_max=2)
    # float64 keeps it
    convert.scene_from_points(huge, [0, 0, 0], [1, 0, 0],
                              path=tmp_path / "h.json", inline_max=2,
                              pcd_dtype="float64")


def test_command_line(tmp_path):
    pts = cloud(500)
    np.save(tmp_path / "p.npy", pts)
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python"),
           "QRTPLAN_BIN": str(BIN)}
    out = tmp_path / "s.json"

    def run(*args):
        return subprocess.run([sys.executable, "-m", "qrtplan.convert",
                               *map(str, args)], capture_output=True,
                              text=True, env=env, cwd=tmp_path)
    r = run("scene", tmp_path / "p.npy", "--start=-100,0,0",
            "--goal=100,0,0", "--inline-max", "100", "-o", out)
    assert r.returncode == 0, r.stderr
    scene = json.loads(out.read_text())
    assert scene["points_file"] == "s.pcd"
    valid(scene)
    assert plan(out)["status"] == "ok"
    # the PCD in, as a reference
    r = run("scene", tmp_path / "s.pcd", "--start=-100,0,0",
            "--goal=100,0,0", "--reference", "-o", tmp_path / "r.json")
    assert r.returncode == 0, r.stderr
    assert json.loads((tmp_path / "r.json").read_text())["points_file"] == \
        "s.pcd"
    bad = tmp_path / "bad.npy"
    np.save(bad, np.array([[0.5, 0.0, np.nan]]))
    r = run("scene", bad, "--start=0,0,0", "--goal=1,0,0", "-o",
            tmp_path / "x.json")
    assert r.returncode == 2 and "not finite" in r.stderr
    assert not (tmp_path / "x.json").exists()
    # setpoints through the C command line
    (tmp_path / "plan.json").write_text(run_cli(["plan", out]).stdout)
    r = run("setpoints", tmp_path / "plan.json", "--period-ms", "50")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0] == "t_s,alpha_deg,sigma_deg,eta_deg"


# --- qrtplan setpoints ---------------------------------------------------

@pytest.fixture(scope="module")
def three_spheres_plan(tmp_path_factory):
    r = run_cli(["plan", ROOT / "scenes" / "three_spheres.json"])
    assert r.returncode == 0, r.stderr
    p = json.loads(r.stdout)
    assert p["status"] == "ok" and len(p["waypoints_deg"]) >= 3
    return p


def csv_rows(plan_dict, *flags):
    r = subprocess.run([str(BIN), "setpoints", "-", *flags],
                       input=json.dumps(plan_dict), capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "t_s,alpha_deg,sigma_deg,eta_deg"
    return np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])


@pytest.mark.parametrize("speed, accel, period", [
    ((30, 30, 30), (60, 60, 60), 10),
    ((40, 10, 20), (80, 20, 40), 10),
    ((90, 90, 90), (30, 30, 30), 7.5),
])
def test_setpoints_csv(three_spheres_plan, speed, accel, period):
    wp = np.array(three_spheres_plan["waypoints_deg"])
    rows = csv_rows(three_spheres_plan,
                    "--speed", ",".join(map(str, speed)),
                    "--accel", ",".join(map(str, accel)),
                    "--period-ms", str(period))
    t = rows[:, 0]
    # a row every period, then the end
    assert np.allclose(t[:-1], np.arange(len(t) - 1) * period * 1e-3,
                       atol=1e-9)
    assert 0 < t[-1] - t[-2] <= period * 1e-3 + 1e-12
    # first and last rows: the plan's ends (alpha continuous: a turn away)
    assert list(rows[0, 1:]) == list(wp[0])
    assert rows[-1, 2] == wp[-1, 1] and rows[-1, 3] == wp[-1, 2]
    assert abs((rows[-1, 1] - wp[-1, 0] + 180) % 360 - 180) < 1e-9
    # alpha never jumps (continuous), every joint within its limits
    v = np.diff(rows[:, 1:], axis=0) / np.diff(t)[:, None]
    assert (np.abs(v) <= np.array(speed) * (1 + 1e-6) + 1e-6).all()
    a = np.diff(v, axis=0) / (0.5 * (np.diff(t)[1:] + np.diff(t)[:-1]))[:,
                                                                       None]
    assert (np.abs(a) <= np.array(accel) * (1 + 1e-6) + 1e-4).all()
    # every waypoint passed: the unwrapped path's waypoints appear as rows
    # where all three joints stand (velocity 0 on both sides) or at the end
    steps = np.diff(wp, axis=0)
    steps[:, 0] = (steps[:, 0] + 180) % 360 - 180
    cum = wp[0] + np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    for k in range(1, len(wp)):
        d = np.abs(rows[:, 1:] - cum[k]).max(axis=1)
        assert d.min() < 0.5, f"waypoint {k} never passed ({d.min()})"


def test_setpoints_wrap_alpha(three_spheres_plan):
    cont = csv_rows(three_spheres_plan)
    wrapped = csv_rows(three_spheres_plan, "--wrap-alpha")
    assert np.array_equal(cont[:, [0, 2, 3]], wrapped[:, [0, 2, 3]])
    assert (wrapped[:, 1] > -180).all() and (wrapped[:, 1] <= 180).all()
    gap = cont[:, 1] - wrapped[:, 1]
    assert (np.abs((gap + 180) % 360 - 180) < 1e-6).all()
    # the plan crosses +-180: continuous alpha leaves (-180, 180]
    assert cont[:, 1].min() < -180 or cont[:, 1].max() > 180


def test_setpoints_python(three_spheres_plan, tmp_path):
    rows = convert.setpoints(three_spheres_plan, tmp_path / "sp.csv",
                             speed=20, period_ms=20)
    assert rows.shape[1] == 4
    assert np.array_equal(rows, csv_rows(three_spheres_plan, "--speed", "20",
                                         "--period-ms", "20"))
    assert (tmp_path / "sp.csv").read_text().startswith("t_s,")
    with pytest.raises(convert.ConversionError, match="--speed"):
        convert.setpoints(three_spheres_plan, speed=0)


@pytest.mark.parametrize("doc, flags, message", [
    ({"status": "no_path"}, [], "status is no_path"),
    ({"status": "ok", "waypoints_deg": [[0, 0, 0], [0, -50, 0]]}, [],
     "outside the joint limits"),
    ({"status": "ok", "waypoints_deg": [[0, 0, 0], [170, 0, 0],
                                        [-170, 0, 0]]},
     ["--limits-deg", "-175,175,-40,180,-180,140"], "long way round"),
    ({"status": "ok", "waypoints_deg": [[0, 0]]}, [], "not [a, s, e]"),
    ({"status": "ok", "waypoints_deg": [[0, 0, 0]]}, ["--speed", "1e5"],
     "bad value"),
    ({"status": "ok", "waypoints_deg": [[0, 0, 0]]}, ["--period-ms", "0"],
     "bad value"),
    ({"status": "ok", "waypoints_deg": [[0, 0, 0]]}, ["--bogus", "1"],
     "unknown option"),
])
def test_setpoints_refusals(doc, flags, message):
    r = subprocess.run([str(BIN), "setpoints", "-", *flags],
                       input=json.dumps(doc), capture_output=True, text=True)
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert r.stdout == ""


def test_setpoints_one_waypoint():
    rows = csv_rows({"status": "ok", "waypoints_deg": [[10, 20, 30]]})
    assert rows.tolist() == [[0, 10, 20, 30]]


# qrtpland's and qrtplan-exec's --speed/--accel refusals
# (test_can_options.py): the same values, the same range
@pytest.mark.parametrize("option", ["--speed", "--accel"])
@pytest.mark.parametrize("value, ok", [
    ("30,60", False), ("0", False), ("30,0,30", False), ("1e5", False),
    ("-30", False), ("nan", False), ("30,60,90,1", False), ("30,,30", False),
    ("0.001", True), ("10000", True), ("40,10,20", True)])
def test_setpoints_speed_accel_as_the_daemon(option, value, ok):
    r = subprocess.run([str(BIN), "setpoints", "-", option, value],
                       input='{"status": "ok", "waypoints_deg": '
                             '[[0, 0, 0], [5, 0, 0]]}',
                       capture_output=True, text=True)
    if ok:
        assert r.returncode == 0, r.stderr
    else:
        assert r.returncode == 2 and "0.001..10000" in r.stderr, r.stderr
