"""Conversions: points (a numpy array or a PCD file) to a scene that
`qrtplan plan` reads, and a plan to a CSV of timed joint set-points (the CAN
master's synchronised profile, from `qrtplan setpoints`).

    from qrtplan.convert import scene_from_points, scene_from_pcd, setpoints
    scene_from_points(xyz, start=[-100, 0, 0], goal=[100, 0, 0],
                      path="scene.json")          # + scene.pcd if large
    rows = setpoints("plan.json", speed=20, period_ms=10)   # (n, 4) array

Command line (docs/convert.md):

    python -m qrtplan.convert scene POINTS.npy|POINTS.pcd --start A,S,E
        --goal A,S,E [--margin-m M] [--arm ARM.json] -o SCENE.json
    python -m qrtplan.convert setpoints PLAN.json [qrtplan setpoints' options]

Points are metres in the arm's base frame. Inline points are written as
the float64 numbers given (JSON keeps every bit); a PCD file holds float32
(what the Point Cloud Library and most tools write) unless pcd_dtype is
"float64": with float32 the scene's points are the given ones rounded to
float32, and a value beyond float32's range is refused.
"""
from __future__ import annotations

import argparse
import io
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

__all__ = ["ConversionError", "scene_from_points", "scene_from_pcd",
           "write_pcd", "read_points", "setpoints", "qrtplan_binary",
           "INLINE_MAX"]

# up to this many points a scene carries them inline; beyond, in a binary
# PCD file beside it (a JSON text of 10,000 points is ~0.5 MB)
INLINE_MAX = 10000


class ConversionError(ValueError):
    """Input that cannot become a scene or a CSV; the message says why."""


def _as_points(points) -> np.ndarray:
    try:
        a = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ConversionError(f"points must be numbers: {e}") from None
    if a.ndim == 2 and a.shape[0] == 0 and a.shape[1] in (0, 3):
        return a.reshape(0, 3)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ConversionError(
            f"points must have shape (N, 3) (x, y, z in metres), got "
            f"{a.shape}")
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ConversionError(
            f"points[{i}] = {a[i].tolist()} is not finite ({int(bad.sum())} "
            f"such point(s)); drop them first, e.g. "
            f"points[np.isfinite(points).all(axis=1)]")
    return a


def _joints(value, what: str) -> list:
    try:
        q = [float(v) for v in value]
    except (TypeError, ValueError):
        raise ConversionError(f"{what} must be three numbers") from None
    if len(q) != 3 or not all(math.isfinite(v) for v in q):
        raise ConversionError(f"{what} must be three finite numbers, got "
                              f"{list(value)}")
    return q


def _target(value, what: str) -> dict:
    """[a, s, e] joints in degrees, or a scene target object as is (its
    numbers checked): {"joints_deg": ...} or {"xyz_m": ..., "ik": ...,
    "aim": ...}."""
    if isinstance(value, dict):
        keys = set(value) & {"joints_deg", "xyz_m"}
        if len(keys) != 1:
            raise ConversionError(
                f"{what} must have exactly one of joints_deg and xyz_m")
        out = dict(value)
        key = keys.pop()
        out[key] = _joints(value[key], f"{what}.{key}")
        return out
    return {"joints_deg": _joints(value, what)}


def _arm(arm):
    """None, a scene's arm object (dict), or an object with to_scene()
    giving one (e.g. qrtplan.kinematics.Arm where it has it)."""
    if arm is None or isinstance(arm, dict):
        return arm
    to_scene = getattr(arm, "to_scene", None)
    if callable(to_scene):
        return to_scene()
    raise ConversionError("arm must be a scene's arm object (a dict: "
                          "links_m, link_radius_m, limits_deg, tool)")


def write_pcd(path, points, dtype="float32") -> None:
    """points (N, 3) to a binary PCD file (FIELDS x y z, SIZE 4 or 8)."""
    a = _as_points(points)
    dt = np.dtype(dtype)
    if dt not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise ConversionError("pcd dtype must be float32 or float64")
    with np.errstate(over="ignore"):
        b = a.astype(dt.newbyteorder("<"))
    if not np.isfinite(b).all():
        i = int(np.flatnonzero(~np.isfinite(b).all(axis=1))[0])
        raise ConversionError(f"points[{i}] = {a[i].tolist()} is beyond "
                              f"float32's range; use pcd_dtype='float64'")
    n = len(b)
    header = ("# .PCD v0.7 - written by qrtplan.convert\nVERSION 0.7\n"
              f"FIELDS x y z\nSIZE {dt.itemsize} {dt.itemsize} "
              f"{dt.itemsize}\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\n"
              f"HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.ascontiguousarray(b).tobytes())


def read_points(path) -> np.ndarray:
    """(N, 3) float64 points of a .npy file (shape (N, 3)) or a PCD file
    (x, y, z fields; ascii, binary or binary_compressed, through pypcd4)."""
    path = Path(path)
    if path.suffix.lower() == ".npy":
        try:
            a = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as e:
            raise ConversionError(f"{path}: {e}") from None
        return _as_points(a)
    if path.suffix.lower() == ".pcd":
        try:
            from pypcd4 import PointCloud
        except ImportError:
            raise ConversionError("reading PCD files needs pypcd4 (pip "
                                  "install pypcd4)") from None
        try:
            pc = PointCloud.from_path(path)
            xyz = pc.numpy(("x", "y", "z"))
        except Exception as e:  # pypcd4 raises several kinds
            raise ConversionError(f"{path}: not a PCD file with x, y, z "
                                  f"fields: {e}") from None
        return _as_points(xyz)
    raise ConversionError(f"{path}: points must be a .npy or .pcd file")


def _scene(start, goal, arm, margin_m, name) -> dict:
    scene = {"version": 1}
    if name is not None:
        scene["name"] = name
    arm = _arm(arm)
    if arm is not None:
        scene["arm"] = arm
    if margin_m is not None:
        m = float(margin_m)
        if not 0.0 <= m <= 10.0:
            raise ConversionError(f"margin_m must be in 0..10 metres, got "
                                  f"{margin_m}")
        scene["margin_m"] = m
    scene["start"] = _target(start, "start")
    scene["goal"] = _target(goal, "goal")
    return scene


def _points_file_name(pcd: Path, scene_path: Path | None) -> str:
    """How a scene at scene_path names pcd (qrtplan resolves a relative
    name against the scene's folder)."""
    pcd = pcd.resolve()
    if scene_path is None:
        return str(pcd)
    try:
        return os.path.relpath(pcd, scene_path.resolve().parent)
    except ValueError:  # another drive
        return str(pcd)


def _write_json(scene: dict, path: Path) -> None:
    """One member a line, a point a line; numbers as json writes them (the
    shortest text that reads back as the same float64)."""
    lines = []
    for key, value in scene.items():
        if key == "points" and value:
            pts = ",\n    ".join(json.dumps(p, allow_nan=False)
                                 for p in value)
            lines.append(f'  "points": [\n    {pts}\n  ]')
        else:
            lines.append(f"  {json.dumps(key)}: "
                         f"{json.dumps(value, allow_nan=False)}")
    path.write_text("{\n" + ",\n".join(lines) + "\n}\n")


def scene_from_points(points, start, goal, arm=None, margin_m=None,
                      path=None, *, name=None, inline_max=INLINE_MAX,
                      pcd_path=None, pcd_dtype="float32") -> dict:
    """A scene of obstacle points (N, 3) in metres and a start and goal
    (each [alpha, sigma, eta] degrees, or a scene target such as
    {"xyz_m": [x, y, z], "ik": {"elbow": "up"}}); arm is a scene's arm
    object (default the paper's arm), margin_m the workspace margin
    (default: the planner's, 0.01).

    With path the scene is written there: up to inline_max points inline
    (exact float64), more in a binary PCD file (pcd_path, default the
    scene's name with .pcd; float32 unless pcd_dtype="float64") that the
    scene names. Returns the scene (a dict)."""
    a = _as_points(points)
    scene = _scene(start, goal, arm, margin_m, name)
    target = Path(path) if path is not None else None
    if target is None or len(a) <= inline_max:
        # the JSON text keeps every bit of a float64 (shortest repr)
        body = {"points": a.tolist()}
    else:
        pcd = Path(pcd_path) if pcd_path else target.with_suffix(".pcd")
        if pcd.resolve() == target.resolve():
            raise ConversionError("the PCD file would overwrite the scene")
        write_pcd(pcd, a, pcd_dtype)
        body = {"points_file": _points_file_name(pcd, target)}
    # points before start and goal, as qrtplan gen writes them
    scene = {**{k: v for k, v in scene.items() if k not in ("start", "goal")},
             **body, "start": scene["start"], "goal": scene["goal"]}
    if target is not None:
        _write_json(scene, target)
    return scene


def scene_from_pcd(pcd_path, start, goal, arm=None, margin_m=None,
                   path=None, *, name=None, check=True) -> dict:
    """A scene whose points_file is the PCD file at pcd_path (not copied:
    named relative to the scene's folder, or absolute without path). With
    check its points are read first (pypcd4) and refused if any is not
    finite or it has no x, y, z (qrtplan would refuse it too, later)."""
    pcd = Path(pcd_path)
    if not pcd.is_file():
        raise ConversionError(f"{pcd}: not a regular file")
    if check:
        read_points(pcd)
    scene = _scene(start, goal, arm, margin_m, name)
    target = Path(path) if path is not None else None
    scene = {**{k: v for k, v in scene.items() if k not in ("start", "goal")},
             "points_file": _points_file_name(pcd, target),
             "start": scene["start"], "goal": scene["goal"]}
    if target is not None:
        _write_json(scene, target)
    return scene


def qrtplan_binary() -> str:
    """The C command line: $QRTPLAN_BIN, else a qrtplan beside this package
    (bin/qrtplan), else on PATH, else a source checkout's build/bin."""
    env = os.environ.get("QRTPLAN_BIN")
    if env:
        return env
    here = Path(__file__).resolve().parent
    for cand in (here / "bin" / "qrtplan",
                 shutil.which("qrtplan"),
                 here.parents[1] / "build" / "bin" / "qrtplan"):
        if cand and Path(cand).is_file() and os.access(cand, os.X_OK):
            return str(cand)
    raise ConversionError("the qrtplan program was not found (set "
                          "QRTPLAN_BIN, or put it on PATH)")


def setpoints(plan, path=None, *, speed=None, accel=None, period_ms=None,
              limits_deg=None, wrap_alpha=False) -> np.ndarray:
    """A plan (a dict as `qrtplan plan` writes it, or its file) as timed
    joint set-points, rows of (t_s, alpha_deg, sigma_deg, eta_deg): the
    CAN master's synchronised trapezoids, computed by `qrtplan setpoints`
    (the same C function the master runs). speed, accel: deg/s, deg/s^2,
    one number or three (defaults 30, 60, as qrtpland's); period_ms
    (default 10); wrap_alpha: alpha in (-180, 180] instead of continuous.
    With path the CSV is written there too."""
    def per_joint(v, what):
        v = [v] if np.isscalar(v) else list(v)
        if len(v) not in (1, 3):
            raise ConversionError(f"{what}: one number or three")
        return ",".join(repr(float(x)) for x in v)

    args = [qrtplan_binary(), "setpoints"]
    stdin = None
    if isinstance(plan, dict):
        args.append("-")
        stdin = json.dumps(plan)
    else:
        args.append(str(plan))
    if speed is not None:
        args += ["--speed", per_joint(speed, "speed")]
    if accel is not None:
        args += ["--accel", per_joint(accel, "accel")]
    if period_ms is not None:
        args += ["--period-ms", repr(float(period_ms))]
    if limits_deg is not None:
        lim = np.asarray(limits_deg, dtype=float).reshape(-1)
        if lim.shape != (6,):
            raise ConversionError("limits_deg: three [lo, hi] pairs")
        args += ["--limits-deg", ",".join(repr(float(x)) for x in lim)]
    if wrap_alpha:
        args.append("--wrap-alpha")
    r = subprocess.run(args, input=stdin, capture_output=True, text=True)
    if r.returncode != 0:
        raise ConversionError(r.stderr.strip() or
                              f"qrtplan setpoints exited {r.returncode}")
    if path is not None:
        Path(path).write_text(r.stdout)
    return np.loadtxt(io.StringIO(r.stdout), delimiter=",", skiprows=1,
                      ndmin=2)


def _main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m qrtplan.convert",
        description="Points to a qrtplan scene; a plan to timed joint "
                    "set-points (docs/convert.md).")
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("scene", help="a .npy (N, 3) or PCD file of points, "
                       "in metres, to a scene")
    s.add_argument("points", help="POINTS.npy or POINTS.pcd")
    s.add_argument("--start", required=True, metavar="A,S,E",
                   help="start joints in degrees")
    s.add_argument("--goal", required=True, metavar="A,S,E",
                   help="goal joints in degrees")
    s.add_argument("--margin-m", type=float, help="workspace margin (0.01)")
    s.add_argument("--arm", metavar="ARM.json",
                   help="the arm object of a scene (links_m, ...), as a "
                   "file")
    s.add_argument("--name", help="the scene's name")
    s.add_argument("--inline-max", type=int, default=INLINE_MAX,
                   help=f"most points written inline ({INLINE_MAX}); more "
                   "go to a binary PCD beside the scene")
    s.add_argument("--pcd-dtype", choices=("float32", "float64"),
                   default="float32")
    s.add_argument("--reference", action="store_true",
                   help="a PCD input is named by the scene, not copied")
    s.add_argument("-o", "--output", required=True, metavar="SCENE.json")
    t = sub.add_parser("setpoints", help="a plan to a CSV of timed joint "
                       "set-points (runs `qrtplan setpoints`)")
    t.add_argument("rest", nargs=argparse.REMAINDER,
                   help="PLAN.json and qrtplan setpoints' options")
    a = p.parse_args(argv)
    try:
        if a.command == "setpoints":
            r = subprocess.run([qrtplan_binary(), "setpoints", *a.rest])
            return r.returncode

        def joints(text, what):
            try:
                return [float(v) for v in text.split(",")]
            except ValueError:
                raise ConversionError(f"{what}: three numbers A,S,E") from None

        start, goal = joints(a.start, "--start"), joints(a.goal, "--goal")
        arm = None
        if a.arm:
            try:
                arm = json.loads(Path(a.arm).read_text())
            except (OSError, ValueError) as e:
                raise ConversionError(f"{a.arm}: {e}") from None
        if a.reference and Path(a.points).suffix.lower() == ".pcd":
            scene_from_pcd(a.points, start, goal, arm, a.margin_m, a.output,
                           name=a.name)
        else:
            scene_from_points(read_points(a.points), start, goal, arm,
                              a.margin_m, a.output, name=a.name,
                              inline_max=a.inline_max,
                              pcd_dtype=a.pcd_dtype)
    except ConversionError as e:
        print(f"qrtplan.convert: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(_main())
