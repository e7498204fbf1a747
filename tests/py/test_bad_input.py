"""Every failure mode of docs/spec.md §CLI: a plan status for well-formed
scenes, one line on stderr and exit 2 for input qrtplan cannot use; never a
crash or a hang."""
import json
import math
import struct
import subprocess

import numpy as np
import pytest

from conftest import plan_scene, run_cli

GOOD = {"version": 1, "points": [[0.5, 0.5, 0.5]],
        "start": {"joints_deg": [-100, 0, 0]}, "goal": {"joints_deg": [100, 0, 0]}}


def expect_error(path, *words):
    r = run_cli(["plan", path])
    assert r.returncode == 2, (r.returncode, r.stdout[:200])
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("qrtplan: "), r.stderr
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


def write(tmp_path, text, name="scene.json"):
    p = tmp_path / name
    p.write_text(text) if isinstance(text, str) else p.write_bytes(text)
    return p


def with_(**changes):
    s = json.loads(json.dumps(GOOD))
    for k, v in changes.items():
        if v is None:
            s.pop(k, None)
        else:
            s[k] = v
    return s


@pytest.mark.parametrize("text,words", [
    ("", ["unexpected end"]),
    ("{", ["end of input"]),
    (json.dumps(GOOD)[:-7], ["end of input"]),
    (json.dumps(GOOD) + " x", ["trailing"]),
    ("[1, 2, 3]", ["object"]),
    ('{"version": 1, "points": [[NaN, 0, 0]]}', ["unexpected character"]),
    ('{"version": 1, "points": [[1e400, 0, 0]]}', ["out of range"]),
    ('{"a": 1, "a": 2}', ["duplicate"]),
    ("[" * 100000 + "]" * 100000, ["nesting"]),
    ('{"points": "\x01"}', ["control character"]),
])
def test_malformed_json(qrtplan, tmp_path, text, words):
    expect_error(write(tmp_path, text), *words)


@pytest.mark.parametrize("scene,words", [
    (with_(start=None), ["start"]),
    (with_(goal=None), ["goal"]),
    (with_(points=None), ["points"]),
    (with_(version=2), ["version"]),
    (with_(points=[[1, 2]]), ["points[0]"]),
    (with_(points=[[1, "2", 3]]), ["points[0][1]", "number"]),
    (with_(points={"x": 1}), ["points"]),
    (with_(margin_m=-0.1), ["margin_m"]),
    (with_(margin_m="big"), ["margin_m", "number"]),
    (with_(grid_deg=1), ["grid_deg"]),
    (with_(grid_deg=7), ["grid_deg"]),  # 7 does not divide 360
    (with_(arm={"links_m": [0.1, 0.2]}), ["links_m"]),
    (with_(arm={"limits_deg": [[-180, 180], [90, 0], [-180, 140]]}), ["limits"]),
    # an unknown field is named, and so is every valid one
    (with_(arm={"elbow": 1}),
     ['"elbow" in arm (valid: links_m, link_radius_m, limits_deg, tool)']),
    (with_(colour="red"),
     ['"colour" in the scene (valid: version, name, comment, arm, margin_m, '
      'cspace_margin_deg, grid_deg, points, points_file, start, goal)']),
    (with_(start={"joints": [0, 0, 0]}), ['"joints" in start (valid: joints_deg, xyz_m, ik, aim)']),
    (with_(start={"joints_deg": [0, -60, 0]}), ["outside the joint limits"]),
    (with_(goal={"joints_deg": [0, 0, 150]}), ["outside the joint limits"]),
    (with_(start={"joints_deg": [190, 0, 0]}), ["outside the joint limits"]),
    (with_(start={"joints_deg": [0, 0, 0], "xyz_m": [0, 0, 0]}), ["exactly one"]),
    (with_(start={}), ["exactly one"]),
    (with_(points_file="does-not-exist.pcd"), ["does-not-exist.pcd"]),
])
def test_invalid_scenes(qrtplan, tmp_path, scene, words):
    expect_error(write(tmp_path, json.dumps(scene)), *words)


def pcd_header(n, data="binary", fields="x y z", size="4 4 4", type_="F F F",
               count="1 1 1", width=None):
    return (f"# .PCD v0.7\nVERSION 0.7\nFIELDS {fields}\nSIZE {size}\n"
            f"TYPE {type_}\nCOUNT {count}\nWIDTH {n if width is None else width}\n"
            f"HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n").encode()


def scene_with_pcd(tmp_path, payload):
    write(tmp_path, payload, "cloud.pcd")
    return write(tmp_path, json.dumps(with_(points=None, points_file="cloud.pcd")))


@pytest.mark.parametrize("payload,words", [
    (pcd_header(10) + b"\0" * 50, ["truncated"]),
    (pcd_header(3, "ascii") + b"0 0 0\n1 1\n", ["truncated"]),
    (pcd_header(2, "ascii") + b"0 0 0\n1 x 1\n", ["bad number"]),
    (pcd_header(2, "ascii") + b"0 0 0\nnan 0 0\n", ["not finite"]),
    (pcd_header(1) + struct.pack("<3f", 0.0, math.inf, 0.0), ["not finite"]),
    (pcd_header(4, width=3) + b"\0" * 48, ["POINTS"]),
    (pcd_header(1, "binary_lz4") + b"\0" * 12, ["not supported"]),
    (pcd_header(1, fields="x y", size="4 4", type_="F F", count="1 1") + b"\0" * 8,
     ["x, y and z"]),
    (b"hello world\n", ["header"]),
    (b"VERSION 0.7\nFIELDS x y z\n", ["DATA"]),
])
def test_malformed_pcd(qrtplan, tmp_path, payload, words):
    expect_error(scene_with_pcd(tmp_path, payload), *words)


def lzf_pcd(n, packed, stated, stream):
    """A binary_compressed PCD of n x y z points: the two sizes as stated,
    then the LZF stream as given."""
    return pcd_header(n, "binary_compressed") + struct.pack("<II", packed, stated) + stream


ONE_POINT = struct.pack("<3f", 0.6, 0.0, 0.0)


@pytest.mark.parametrize("payload,words", [
    (pcd_header(1, "binary_compressed") + b"\0" * 4, ["no sizes"]),
    (lzf_pcd(1, 13, 24, b"\x0b" + ONE_POINT), ["says 24 bytes", "are 12"]),
    (lzf_pcd(1, 100, 12, b"\x0b" + ONE_POINT), ["truncated", "100 bytes"]),
    # a stated size the file cannot hold is refused before it is allocated
    (lzf_pcd(1_000_000, 13, 12_000_000, b"\x0b" + ONE_POINT),
     ["13 bytes cannot expand to 12000000"]),
    (lzf_pcd(100_000_000, 13, 1_200_000_000, b"\x0b" + ONE_POINT),
     ["more than 1 GiB"]),
    # the stream itself: a literal cut short, a reference before the start,
    # more or less than the stated size, a NaN inside
    (lzf_pcd(1, 6, 12, b"\x0b" + ONE_POINT[:5]), ["ends inside a run"]),
    (lzf_pcd(1, 4, 12, b"\x20\x00" + b"\x09\x00"), ["refers back before"]),
    (lzf_pcd(1, 15, 12, b"\x0b" + ONE_POINT + b"\x00\x00"),
     ["more than its stated size"]),
    (lzf_pcd(1, 12, 12, b"\x0a" + ONE_POINT[:11]), ["less than its stated"]),
    (lzf_pcd(1, 13, 12, b"\x0b" + struct.pack("<3f", 0.6, math.nan, 0.0)),
     ["point 0 is not finite"]),
])
def test_malformed_binary_compressed_pcd(qrtplan, tmp_path, payload, words):
    expect_error(scene_with_pcd(tmp_path, payload), *words)


def test_binary_compressed_pcd_by_hand(qrtplan, tmp_path):
    """Two points, the second a back reference to the first (LZF's copy
    that overlaps what it writes): x x ... then y y ... then z z."""
    soa = struct.pack("<2f", 0.6, 0.6) + struct.pack("<2f", 0.1, 0.1) + \
        struct.pack("<2f", 0.0, 0.0)
    assert soa[:4] == soa[4:8]
    # literal 4 bytes, then copy 4 from 4 back; y and z likewise
    stream = b"".join(b"\x03" + soa[i:i + 4] + b"\x40\x03" for i in (0, 8, 16))
    write(tmp_path, lzf_pcd(2, len(stream), 24, stream), "cloud.pcd")
    # on the whole mask, whose blocked cells the two must share
    code, plan, err = plan_scene(with_(points=None, points_file="cloud.pcd"),
                                 tmp_path, "--whole-mask")
    assert code == 0, err
    assert plan["stats"]["points"] == 2
    inline = [[0.6, 0.1, 0.0], [0.6, 0.1, 0.0]]
    code2, plan2, err2 = plan_scene(with_(points=[[float(np.float32(v)) for v in p]
                                                  for p in inline]), tmp_path,
                                    "--whole-mask", name="inline")
    assert code2 == 0, err2
    assert plan["stats"]["cells_blocked"] == plan2["stats"]["cells_blocked"] > 0


def test_pcd_with_extra_fields_ascii_and_binary(qrtplan, tmp_path):
    pts = np.array([[0.6, 0.0, 0.0], [0.0, 0.6, 0.2]], np.float32)
    rows = b"".join(struct.pack("<f3fI", 1.5, *p, 7) for p in pts)
    binary = pcd_header(2, fields="intensity x y z label", size="4 4 4 4 4",
                        type_="F F F F U", count="1 1 1 1 1") + rows
    ascii_ = pcd_header(2, "ascii", fields="x y z rgb", size="4 4 4 4",
                        type_="F F F F", count="1 1 1 1") + \
        b"".join(b"%r %r %r 0.5\n" % tuple(float(v) for v in p) for p in pts)
    for payload in (binary, ascii_):
        write(tmp_path, payload, "cloud.pcd")
        code, plan, err = plan_scene(
            with_(points=None, points_file="cloud.pcd"), tmp_path)
        assert code == 0, err
        assert plan["stats"]["points"] == 2


def test_empty_cloud_plans_in_free_space(qrtplan, tmp_path):
    code, plan, err = plan_scene(with_(points=[]), tmp_path)
    assert code == 0 and plan["status"] == "ok", (err, plan)
    assert plan["waypoints_deg"][0] == [-100, 0, 0]
    assert plan["waypoints_deg"][-1] == [100, 0, 0]


def test_start_and_goal_blocked(qrtplan, tmp_path):
    on_start = [0.96 * math.cos(math.radians(-100)), 0.96 * math.sin(math.radians(-100)), 0]
    code, plan, _ = plan_scene(with_(points=[on_start]), tmp_path)
    assert code == 0 and plan["status"] == "start_blocked"
    code, plan, _ = plan_scene(with_(points=[[-on_start[0], -on_start[1], 0]]), tmp_path)
    # (-x, -y) of alpha -100 lies at alpha 80, not on the goal at 100
    assert plan["status"] == "ok"
    on_goal = [0.96 * math.cos(math.radians(100)), 0.96 * math.sin(math.radians(100)), 0]
    code, plan, _ = plan_scene(with_(points=[on_goal]), tmp_path)
    assert code == 0 and plan["status"] == "goal_blocked"
    assert "waypoints_deg" not in plan


def test_unreachable_goal_point(qrtplan, tmp_path):
    code, plan, _ = plan_scene(with_(goal={"xyz_m": [2.0, 0, 0]}), tmp_path)
    assert code == 0 and plan["status"] == "unreachable"
    code, plan, _ = plan_scene(with_(goal={"xyz_m": [0, 0, 5]}), tmp_path)
    assert plan["status"] == "unreachable"


def test_no_path_when_walled_in(qrtplan, tmp_path):
    # walls across link 1's circle at alpha 45 and 135: alpha 90 and 0 are cut
    # off from each other whatever the other joints do
    wall = [[r * math.cos(a), r * math.sin(a), z]
            for a in (math.pi / 4, 3 * math.pi / 4)
            for r in np.arange(0.05, 0.151, 0.01) for z in np.arange(-0.04, 0.041, 0.01)]
    code, plan, _ = plan_scene(with_(points=wall, start={"joints_deg": [90, 0, 0]},
                                     goal={"joints_deg": [0, 0, 0]}), tmp_path)
    assert code == 0 and plan["status"] == "no_path", plan


def test_huge_cloud_is_quantised_or_refused_never_overflows(qrtplan, tmp_path):
    rng = np.random.default_rng(1)
    # 3 million points: a dense shell that fits as voxels ...
    u = rng.normal(size=(3_000_000, 3)).astype(np.float32)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    shell = u * np.float32(0.15) + np.float32([0.0, -0.6, 0.3])
    write(tmp_path, pcd_header(len(shell)) + shell.tobytes(), "cloud.pcd")
    code, plan, err = plan_scene(with_(points=None, points_file="cloud.pcd"), tmp_path)
    assert code == 0, err
    assert plan["stats"]["voxel_m"] > 0 and plan["stats"]["points_dropped"] == 0
    assert plan["status"] in ("ok", "no_path")
    # ... and one filling the whole reach, which no voxel size can hold: a
    # 7 m cube has 1.3 million voxels of 64 mm, and 2 million points take
    # most of them, more than even the host profile's table (2^18)
    cube = rng.uniform(-3.5, 3.5, size=(2_000_000, 3)).astype(np.float32)
    write(tmp_path, pcd_header(len(cube)) + cube.tobytes(), "cloud.pcd")
    code, plan, err = plan_scene(with_(points=None, points_file="cloud.pcd",
                                       arm={"links_m": [0.09, 3.0, 3.0]}), tmp_path)
    assert code == 0, err
    assert plan["status"] == "capacity" and plan["stats"]["points_dropped"] > 0
    assert str(plan["stats"]["points_dropped"]) in plan["detail"]


def test_help_and_usage(qrtplan):
    r = run_cli(["--help"])
    assert r.returncode == 0 and r.stderr == ""
    # the overview: every command's usage and where each command's options are
    for words in ("qrtplan plan SCENE.json", "qrtplan mask SCENE.json",
                  "qrtplan gen [--spheres N]", "COMMAND --help",
                  "Exit status"):
        assert words in r.stdout, words
    assert "--no-simplify  " not in r.stdout  # options are the commands' own
    r = run_cli(["frobnicate"])
    assert r.returncode == 2
    r = run_cli(["plan"])
    assert r.returncode == 2 and r.stderr.count("\n") == 1


# each command's own text: its usage, its options, its exit status, and
# not the other commands' usage or options
COMMAND_HELP = {
    "plan": ["usage: qrtplan plan SCENE.json", "-o PLAN.json", "--dijkstra",
             "--no-simplify", "--whole-mask", "--as-read", "--max-memory",
             "1 GiB", "Exit status"],
    "mask": ["usage: qrtplan mask SCENE.json", "-o MASK.json", "--max-memory",
             "1 GiB", "Exit status"],
    "gen": ["usage: qrtplan gen", "--spheres N", "--points K", "--radius R",
            "--distance D", "--height Z", "--phase DEG", "--start A,S,E",
            "--goal A,S,E", "--pcd FILE", "--pcd-ascii FILE", "-o SCENE.json",
            "Exit status"],
}


@pytest.mark.parametrize("command", sorted(COMMAND_HELP))
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_each_command_has_its_own_help(qrtplan, command, flag):
    for args in ([command, flag], [command, "scene.json", flag]):
        r = run_cli(args)
        assert r.returncode == 0 and r.stderr == "", (args, r.stderr)
        for words in COMMAND_HELP[command]:
            assert words in r.stdout, (args, words)
        assert r.stdout.count("usage: ") == 1, args
        for other in set(COMMAND_HELP) - {command}:
            assert f"qrtplan {other} " not in r.stdout, (args, other)
        assert "--whole-mask" not in r.stdout or command == "plan"


@pytest.mark.parametrize("program", ["qrtplan", "qrtplan-exec", "qrtpland",
                                     "servo_sim"])
@pytest.mark.parametrize("flag", ["--help", "--version"])
def test_help_that_cannot_be_written_is_an_error(qrtplan, program, flag):
    # `prog --help > /dev/full` used to exit 0, having printed nothing
    path = qrtplan.parent / program
    r = subprocess.run([str(path), flag], capture_output=True, text=True,
                       timeout=30)
    assert r.returncode == 0, r.stderr
    if flag == "--version":
        assert r.stdout.startswith(f"{program} 0.") and r.stdout.count("\n") == 1
    else:
        assert "usage" in r.stdout and "--version" in r.stdout
    with open("/dev/full", "w") as full:
        r = subprocess.run([str(path), flag], stdout=full,
                           stderr=subprocess.PIPE, text=True, timeout=30)
    assert r.returncode == 2
    assert r.stderr == f"{program}: stdout: write failed\n"


def test_scene_from_standard_input_and_plan_to_standard_output(qrtplan,
                                                              tmp_path):
    """'-' as the scene reads standard input (a points_file then relative to
    the working directory); '-o -' writes standard output."""
    write(tmp_path, pcd_header(1) + struct.pack("<3f", 0.6, 0.0, 0.0),
          "cloud.pcd")
    scene = json.dumps(with_(points=None, points_file="cloud.pcd"))
    by_file = run_cli(["plan", write(tmp_path, scene)])
    assert by_file.returncode == 0, by_file.stderr

    def piped(*args, text=scene, cwd=tmp_path):
        return subprocess.run([str(qrtplan), *args], input=text, cwd=cwd,
                              capture_output=True, text=True, timeout=60)

    def untimed(out):
        plan = json.loads(out)
        del plan["stats"]["time_us"]
        return plan

    for args in (["plan", "-"], ["plan", "-", "-o", "-"], ["plan", "-o", "-", "-"]):
        r = piped(*args)
        assert r.returncode == 0, (args, r.stderr)
        assert untimed(r.stdout) == untimed(by_file.stdout), args
    assert untimed(by_file.stdout)["stats"]["points"] == 1
    r = piped("mask", "-", "-o", "-")
    assert r.returncode == 0 and json.loads(r.stdout)["blocked"], r.stderr
    # elsewhere the points_file is not there, and the message says whose
    r = piped("plan", "-", cwd=tmp_path.parent)
    assert r.returncode == 2 and r.stderr.startswith(
        "qrtplan: standard input: ") and "cloud.pcd" in r.stderr, r.stderr
    r = piped("plan", "-", text="")
    assert r.returncode == 2 and r.stderr == (
        "qrtplan: standard input: malformed JSON at byte 0: unexpected end "
        "of input\n"), r.stderr
    r = piped("plan", "-", "-")
    assert r.returncode == 2 and "unexpected argument" in r.stderr
