"""PCD files written by another implementation: pypcd4, which compresses
with liblzf (python-neo-lzf), as the Point Cloud Library does. The planner
must read a binary_compressed cloud as the very cloud it reads uncompressed,
and the independent oracle (tools/oracle.py, which decodes with liblzf, not
with the planner's code) must read the same points."""
import json
import struct

import numpy as np
import pytest
from pypcd4 import Encoding, PointCloud

import oracle
from conftest import run_cli


def clouds():
    rng = np.random.default_rng(20261205)
    # a scan's structure, which is what makes LZF pay: coordinates on a
    # millimetre grid, rows of points along lines
    wall = np.stack(np.meshgrid(np.arange(0.4, 0.7, 0.01),
                                np.arange(-0.3, 0.3, 0.01), [0.1]),
                    -1).reshape(-1, 3)
    yield "wall", wall.astype(np.float32), {}
    blob = np.round(rng.normal([0.5, 0.3, 0.2], 0.05, (3000, 3)), 3)
    yield "blob", blob.astype(np.float32), {}
    # one point repeated: the longest back references LZF has
    yield "same point", np.tile(np.float32([0.6, 0.0, 0.0]), (5000, 1)), {}
    yield "one point", np.float32([[0.5, 0.5, 0.5]]), {}
    # beyond the planner's 16,384 exact points (its voxels take over)
    big = np.round(rng.uniform(-0.9, 0.9, (40000, 3)), 2)
    yield "40,000 points", big.astype(np.float32), {}
    # x y z as doubles among other fields, before and after them
    extra = {"intensity": (np.float32, rng.uniform(0, 1, len(wall))),
             "label": (np.uint16, np.arange(len(wall)) % 7)}
    yield "doubles among other fields", wall.astype(np.float64), extra


def save(path, xyz, extra, encoding):
    names, types, cols = [], [], []
    if "intensity" in extra:
        names.append("intensity")
        types.append(extra["intensity"][0])
        cols.append(extra["intensity"][1].astype(extra["intensity"][0]))
    for k, axis in enumerate("xyz"):
        names.append(axis)
        types.append(xyz.dtype.type)
        cols.append(xyz[:, k])
    if "label" in extra:
        names.append("label")
        types.append(extra["label"][0])
        cols.append(extra["label"][1].astype(extra["label"][0]))
    PointCloud.from_points(cols, tuple(names), tuple(types)).save(
        str(path), encoding=encoding)


def scene(tmp_path, name, cloud):
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps({
        "version": 1, "points_file": cloud,
        "start": {"joints_deg": [-100, 0, 0]},
        "goal": {"joints_deg": [100, 0, 0]}}))
    return path


@pytest.mark.parametrize("name,xyz,extra", list(clouds()),
                         ids=[c[0] for c in clouds()])
def test_binary_compressed_reads_as_the_same_cloud(qrtplan, tmp_path, name,
                                                   xyz, extra):
    save(tmp_path / "plain.pcd", xyz, extra, Encoding.BINARY)
    save(tmp_path / "packed.pcd", xyz, extra, Encoding.BINARY_COMPRESSED)
    packed = (tmp_path / "packed.pcd").read_bytes()
    # pypcd4 falls back to binary where LZF would not shrink the data:
    # every cloud here must really be compressed, or the test tests nothing
    head = packed.index(b"\nDATA binary_compressed\n") + 24
    sizes = struct.unpack_from("<II", packed, head)
    assert len(xyz) < 100 or sizes[0] < sizes[1], sizes
    # the oracle, with liblzf, reads exactly the points written
    assert np.array_equal(oracle.read_pcd(str(tmp_path / "packed.pcd")),
                          xyz.astype(float))
    out = {}
    for kind in ("plain", "packed"):
        s = scene(tmp_path, kind, f"{kind}.pcd")
        mask = run_cli(["mask", s])
        assert mask.returncode == 0, mask.stderr
        plan = run_cli(["plan", s])
        assert plan.returncode == 0, plan.stderr
        p = json.loads(plan.stdout)
        del p["stats"]["time_us"]
        out[kind] = (json.loads(mask.stdout), p)
    assert out["packed"] == out["plain"]
    mask, plan = out["packed"]
    if plan["stats"]["voxel_m"] == 0:  # every point kept as it is
        assert plan["stats"]["points"] + plan["stats"]["points_ignored"] == len(xyz)
    else:
        assert len(xyz) > 16384
    assert plan["status"] in ("ok", "no_path", "start_blocked", "goal_blocked")
    if plan["status"] == "ok":
        sc = json.loads(scene(tmp_path, "check", "packed.pcd").read_text())
        r = oracle.check_path(sc, plan, oracle.scene_points(sc, str(tmp_path)))
        assert r.safe, str(r)


def test_an_organised_cloud_with_nan_pixels_is_refused_with_the_remedy(
        qrtplan, tmp_path):
    """A depth camera's organised cloud marks pixels without a return with
    NaN (is_dense false). docs/spec.md §Scene has the reader refuse NaN; the
    message says where and what to do."""
    rng = np.random.default_rng(7)
    xyz = rng.uniform(0.3, 0.6, (4 * 6, 3)).astype(np.float32)
    xyz[9] = np.nan
    pc = PointCloud.from_xyz_points(xyz)
    pc.metadata.width, pc.metadata.height = 6, 4
    pc.save(str(tmp_path / "organised.pcd"), encoding=Encoding.BINARY_COMPRESSED)
    assert b"WIDTH 6\nHEIGHT 4\n" in (tmp_path / "organised.pcd").read_bytes()
    r = run_cli(["plan", scene(tmp_path, "organised", "organised.pcd")])
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1
    assert "point 9 is not finite" in r.stderr
    assert "removeNaNFromPointCloud" in r.stderr
