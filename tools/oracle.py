#!/usr/bin/env python3
"""Independent safety oracle for qrtplan plans.

Shares no code with the planner: forward kinematics from docs/spec.md
§Kinematics, exact point-to-segment distances in numpy, and the path sampled
at no more than 0.1 degree per joint between waypoints (alpha the short way
round, its step taken in (-180, 180]). A configuration collides when any
point is closer than link_radius + margin to a link (strict <), or, for an
arm with a tool, closer than tool radius + margin to the tool's segment
from the end effector Pe to the tip Pe + length * unit(Pe - P2). An end
given as xyz_m must be reached (by the tip when its "aim" is "tool_tip"),
in the IK branch its "ik" asks for, and a branch the plan reports
(start_ik, goal_ik) must be the one measured.

    python tools/oracle.py SCENE.json PLAN.json   # exit 0 safe, 1 not

Exit 2, with one line on stderr, when a file cannot be read or is not the
scene or plan it should be: nothing was checked, so nothing is called safe.
"""
import json
import math
import numbers
import os
import struct
import sys

import numpy as np

DEFAULT_LINKS = (0.090, 0.332, 0.538)
DEFAULT_RADII = (0.02, 0.02, 0.02)
DEFAULT_LIMITS = ((-180.0, 180.0), (-40.0, 180.0), (-180.0, 140.0))
STEP_DEG = 0.1


class Arm:
    def __init__(self, scene):
        arm = scene.get("arm", {})
        self.links = tuple(arm.get("links_m", DEFAULT_LINKS))
        self.radii = np.array(arm.get("link_radius_m", DEFAULT_RADII), float)
        self.limits = tuple(tuple(l) for l in arm.get("limits_deg", DEFAULT_LIMITS))
        self.margin = float(scene.get("margin_m", 0.01))
        self.alpha_wraps = tuple(self.limits[0]) == (-180.0, 180.0)
        tool = arm.get("tool", {"length_m": 0.0, "radius_m": 0.0})
        self.tool_length = float(tool["length_m"])
        self.tool_radius = float(tool["radius_m"])

    def capsules(self, q):
        """(N, 3) joint angles -> segment ends (N, K, 2, 3) and radii (K,):
        the three links and, with a tool, the tool from Pe to its tip."""
        p = self.joints(q)
        ends = [p[:, k:k + 2, :] for k in range(3)]
        radii = list(self.radii)
        if self.tool_length > 0.0:
            ends.append(np.stack([p[:, 3, :], self.tips(p)], axis=1))
            radii.append(self.tool_radius)
        return np.stack(ends, axis=1), np.asarray(radii, float)

    def tips(self, p):
        """(N, 4, 3) joint positions -> (N, 3) tool tips (Pe without a tool):
        Pe + length * unit(Pe - P2)."""
        d = p[:, 3, :] - p[:, 2, :]
        n = np.linalg.norm(d, axis=1)[:, None]
        return p[:, 3, :] + self.tool_length * d / np.where(n > 0, n, 1.0)

    def tip(self, q):
        """The tool tip of one configuration (Pe without a tool)."""
        return self.tips(self.joints(q))[0]

    def joints(self, q):
        """(N, 3) joint angles in degrees -> (N, 4, 3) joint positions."""
        q = np.radians(np.atleast_2d(np.asarray(q, float)))
        a, s, e = q[:, 0], q[:, 1], q[:, 2]
        l1, l2, l3 = self.links
        u = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
        p0 = np.zeros_like(u)
        p1 = l1 * u
        p2 = p1 + l2 * np.cos(s)[:, None] * u
        p2[:, 2] = l2 * np.sin(s)
        p3 = p2 + l3 * np.cos(s + e)[:, None] * u
        p3[:, 2] = p2[:, 2] + l3 * np.sin(s + e)
        return np.stack([p0, p1, p2, p3], axis=1)


def segment_distances(points, a, b):
    """Distances from each of M points to each of N segments a[n]-b[n]: (N, M)."""
    ab = b - a
    len2 = np.einsum("ij,ij->i", ab, ab)
    ap = points[None, :, :] - a[:, None, :]
    t = np.einsum("nmj,nj->nm", ap, ab) / np.where(len2 > 0, len2, 1.0)[:, None]
    t = np.clip(t, 0.0, 1.0)
    closest = a[:, None, :] + t[:, :, None] * ab[:, None, :]
    return np.linalg.norm(points[None, :, :] - closest, axis=2)


def clearances(arm, qs, points, batch=48, reach=0.05):
    """Smallest (distance - radius - margin) per configuration: (N,).

    Exact below `reach` metres; beyond it a configuration may report any
    value >= reach. Consecutive configurations are taken in batches, and only
    the points inside the bounding box of a batch's link segments (grown by
    radius + margin + reach) are measured: a point outside it is farther
    than that from every segment."""
    qs = np.atleast_2d(np.asarray(qs, float))
    out = np.full(len(qs), np.inf)
    if len(points) == 0:
        return out
    for start in range(0, len(qs), batch):
        seg, radii = arm.capsules(qs[start:start + batch])
        best = np.full(len(seg), np.inf)
        for k in range(len(radii)):
            a, b = seg[:, k, 0, :], seg[:, k, 1, :]
            grow = radii[k] + arm.margin + reach
            lo = np.minimum(a.min(axis=0), b.min(axis=0)) - grow
            hi = np.maximum(a.max(axis=0), b.max(axis=0)) + grow
            near = points[np.all((points >= lo) & (points <= hi), axis=1)]
            if len(near) == 0:
                best = np.minimum(best, reach)
                continue
            d = segment_distances(near, a, b)
            best = np.minimum(best, d.min(axis=1) - radii[k] - arm.margin)
        out[start:start + batch] = best
    return out


def wrap180(x):
    r = math.fmod(x, 360.0)
    if r <= -180.0:
        r += 360.0
    elif r > 180.0:
        r -= 360.0
    return r


def wrap180_array(a):
    """wrap180 elementwise, into [-180, 180) (only -180 differs from it)."""
    return (np.asarray(a, float) + 180.0) % 360.0 - 180.0


def sample_path(arm, waypoints, step=STEP_DEG):
    """Configurations every <= step degrees per joint along the path."""
    samples = [np.asarray(waypoints[0], float)]
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        d = np.asarray(b, float) - np.asarray(a, float)
        if arm.alpha_wraps:
            d[0] = wrap180(d[0])
        n = max(1, int(math.ceil(np.max(np.abs(d)) / step)))
        t = np.arange(1, n + 1)[:, None] / n
        samples.append(np.asarray(a, float)[None, :] + t * d[None, :])
    q = np.vstack(samples)
    if arm.alpha_wraps:
        q[:, 0] = wrap180_array(q[:, 0])
    return q


def path_length(arm, waypoints):
    total = 0.0
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        d = np.asarray(b, float) - np.asarray(a, float)
        if arm.alpha_wraps:
            d[0] = wrap180(d[0])
        total += float(np.linalg.norm(d))
    return total


def read_pcd(path):
    with open(path, "rb") as f:
        data = f.read()
    header, pos = {}, 0
    while True:
        end = data.index(b"\n", pos)
        line = data[pos:end].decode().strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, _, rest = line.partition(" ")
        header[key] = rest.split()
        if key == "DATA":
            break
    fields, sizes = header["FIELDS"], [int(s) for s in header["SIZE"]]
    types = header["TYPE"]
    counts = [int(c) for c in header.get("COUNT", ["1"] * len(fields))]
    n = int(header["POINTS"][0])
    if header["DATA"][0] == "ascii":
        rows = np.loadtxt(data[pos:].decode().splitlines(), ndmin=2)
        cols, col = {}, 0
        for f_, c in zip(fields, counts):
            cols[f_] = col
            col += c
        return rows[:n, [cols["x"], cols["y"], cols["z"]]].astype(float)
    fmt = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2",
           ("I", 4): "i4", ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2",
           ("U", 4): "u4", ("U", 8): "u8"}
    dtype = np.dtype([(f_, "<" + fmt[(t, s)], (c,)) for f_, t, s, c in
                      zip(fields, types, sizes, counts)])
    if header["DATA"][0] == "binary_compressed":
        # liblzf's own decoder (python-neo-lzf), not the planner's; the
        # rows come field by field: every point's first field, then the next
        import lzf
        if len(data) < pos + 8:
            raise ValueError(f"{path}: binary_compressed data without its sizes")
        packed, unpacked = struct.unpack_from("<II", data, pos)
        raw = lzf.decompress(data[pos + 8:pos + 8 + packed], unpacked)
        if raw is None or len(raw) != unpacked or unpacked != n * dtype.itemsize:
            raise ValueError(f"{path}: binary_compressed data does not decode")
        cols, at = {}, 0
        for name in dtype.names:
            width = dtype[name].itemsize * n
            cols[name] = np.frombuffer(raw[at:at + width], dtype=dtype[name])
            at += width
        return np.stack([cols[a][:, 0] for a in "xyz"], axis=1).astype(float)
    rec = np.frombuffer(data, dtype=dtype, count=n, offset=pos)
    return np.stack([rec["x"][:, 0], rec["y"][:, 0], rec["z"][:, 0]], axis=1).astype(float)


def scene_points(scene, scene_dir="."):
    pts = [np.asarray(scene.get("points", []), float).reshape(-1, 3)]
    if "points_file" in scene:
        pts.append(read_pcd(os.path.join(scene_dir, scene["points_file"])))
    return np.vstack(pts)


class Result:
    def __init__(self):
        self.problems = []
        self.samples = 0
        self.min_clearance = math.inf

    @property
    def safe(self):
        return not self.problems

    def __str__(self):
        if self.safe:
            return (f"safe: {self.samples} samples, min clearance "
                    f"{self.min_clearance:.4f} m")
        return "; ".join(self.problems)


def ik_branch(arm, q, tol=1e-9, tool_tip=False):
    """The IK branch of configuration q (docs/spec.md §Kinematics, Branches)
    measured on its joint positions: (facing, elbow). Facing: the tip ahead
    of the base axis along alpha (front) or behind it (back), both within
    tol of the axis. Elbow: P2 above the line P1-Pe at P2's horizontal place
    (up) or below it (down), both within tol of the line or when the line is
    vertical. tool_tip: the target is the tool tip's, which stands for Pe
    (the tip arm's end effector)."""
    p = arm.joints(q)[0]
    if tool_tip:
        p[3] = arm.tip(q)
    a = math.radians(q[0])
    h = np.array([math.cos(a), math.sin(a), 0.0])
    if math.hypot(p[3][0], p[3][1]) <= tol:
        facing = "both"
    else:
        facing = "front" if float(p[3] @ h) > 0 else "back"
    u2, z2 = float((p[2] - p[1]) @ h), float(p[2][2] - p[1][2])
    ue, ze = float((p[3] - p[1]) @ h), float(p[3][2] - p[1][2])
    above = z2 - ze * u2 / ue if abs(ue) > tol else 0.0
    elbow = "both" if abs(above) <= tol else "up" if above > 0 else "down"
    return facing, elbow


def aims_tool_tip(target):
    """An xyz_m target's aim (docs/spec.md §Scene): the tool tip or Pe."""
    aim = target.get("aim", "end_effector")
    if aim not in ("end_effector", "tool_tip"):
        raise ValueError(f"aim {aim!r} is neither end_effector nor tool_tip")
    return aim == "tool_tip"


def check_branch(arm, name, target, q_end, reported, problems):
    """An xyz_m end: the branch its target's ik asks for, and the one the
    plan reports (when it does), against the branch measured at q_end."""
    measured = ik_branch(arm, q_end, tool_tip=aims_tool_tip(target))
    asked = target.get("ik", {})
    for i, key in enumerate(("facing", "elbow")):
        want = asked.get(key, "any")
        if want != "any" and measured[i] not in (want, "both"):
            problems.append(f"path {name} {q_end} is {key} {measured[i]}, "
                            f"asked {want}")
        if reported is None:
            continue  # a plan that does not say (plan_t's own numbers)
        told = reported.get(key)
        if measured[i] != "both" and told != measured[i]:
            problems.append(f"plan says {name} {key} {told}, measured "
                            f"{measured[i]}")


# How far a plan's clearance_m may lie below the least clearance at the
# samples: the planner's bound is within 4 mm of the true least clearance
# (docs/spec.md section Clearance), and between samples 0.1 degrees apart
# the arm moves at most ~1.8 mm a metre of reach, half of which the true
# least clearance may lie below the least sample.
CLEARANCE_BELOW_M = 0.005


def refined_least(arm, q, pts, claim, around=4, finer=100):
    """The least clearance along the sampled path q (margin subtracted):
    the samples' least, then the motion between the neighbours of the
    `around` least samples sampled `finer` times more densely, so that a
    bound which misses a dip between its own samples is caught."""
    c = clearances(arm, q, pts, reach=claim + 0.05)
    least = float(c.min())
    for i in np.argsort(c)[:around]:
        lo, hi = max(i - 1, 0), min(i + 1, len(q) - 1)
        if hi == lo:
            continue
        d = q[hi] - q[lo]
        if arm.alpha_wraps:
            d[0] = wrap180(d[0])
        t = np.linspace(0.0, 1.0, 2 * finer + 1)[:, None]
        fine = clearances(arm, q[lo][None, :] + t * d[None, :], pts,
                          reach=claim + 0.05)
        least = min(least, float(fine.min()))
    return least


def check_clearance(arm, q, pts, sampled, plan, problems):
    """A plan's clearance_m (margin not subtracted) is a lower bound on the
    least clearance along the path and at least the margin. Where the
    points are exact, it is within CLEARANCE_BELOW_M of the least clearance
    to the points the planner keeps (|p| <= the arm's reach plus its
    largest radius plus the margin), or of the bound it gives the others
    (their least |p| less the arm's reach plus its largest radius), which
    ever is less (docs/spec.md section Clearance). null only when no point
    is given."""
    claim = plan["clearance_m"]
    if claim is None:
        if len(pts):
            problems.append("clearance_m is null but the scene has points")
        return
    if not (isinstance(claim, numbers.Real) and math.isfinite(claim)):
        problems.append(f"clearance_m {claim!r} is not a finite number")
        return
    if not claim >= arm.margin:
        problems.append(f"clearance_m {claim} is below the margin {arm.margin}")
    if not len(pts):
        problems.append(f"clearance_m {claim} but the scene has no points")
        return
    least = refined_least(arm, q, pts, claim) + arm.margin
    if claim > least + 1e-6:
        problems.append(f"clearance_m {claim:.6f} is above the least "
                        f"clearance along the path, {least:.6f} m")
    if plan.get("stats", {}).get("voxel_m", 0) != 0:
        return  # merged points: a bound, how close is not promised
    length = (sum(arm.links) + arm.tool_length +
              max(*arm.radii, arm.tool_radius))
    norms = np.linalg.norm(pts, axis=1)
    kept = pts[norms <= length + arm.margin]
    promised = math.inf
    if len(kept):
        c = clearances(arm, q, kept, reach=claim + 0.05)
        promised = float(c.min()) + arm.margin
    if (norms > length + arm.margin).any():
        promised = min(promised,
                       float(norms[norms > length + arm.margin].min()) - length)
    if claim < promised - CLEARANCE_BELOW_M:
        problems.append(f"clearance_m {claim:.6f} is more than "
                        f"{CLEARANCE_BELOW_M * 1000:g} mm below {promised:.6f} "
                        f"m (the least clearance along the path, its kept "
                        f"points or the far points' bound)")


def check_path(scene, plan, points):
    """Check an ok plan against its scene. Returns a Result."""
    arm = Arm(scene)
    res = Result()
    wps = plan.get("waypoints_deg")
    if plan.get("status") != "ok" or not wps or len(wps) < 2:
        res.problems.append("not an ok plan with at least 2 waypoints")
        return res
    for i, w in enumerate(wps):
        if (not isinstance(w, (list, tuple)) or len(w) != 3 or
                not all(isinstance(x, numbers.Real) and not isinstance(x, bool)
                        and math.isfinite(x) for x in w)):
            res.problems.append(f"waypoint {i} is not three finite numbers: {w!r}")
            return res
    # a NaN distance compares false with everything: it would pass
    pts = np.asarray(points, float).reshape(-1, 3)
    if not np.isfinite(pts).all():
        res.problems.append("the scene has points that are not finite")
        return res
    arm_numbers = [*arm.links, *arm.radii, arm.margin, *np.ravel(arm.limits),
                   arm.tool_length, arm.tool_radius]
    if not np.isfinite(np.asarray(arm_numbers, float)).all():
        res.problems.append("the arm's lengths, radii, margin, limits or tool "
                            "are not finite")
        return res
    q = sample_path(arm, wps)
    res.samples = len(q)
    for j, (lo, hi) in enumerate(arm.limits):
        bad = np.nonzero((q[:, j] < lo - 1e-9) | (q[:, j] > hi + 1e-9))[0]
        if j == 0 and arm.alpha_wraps:
            continue
        if len(bad):
            res.problems.append(f"joint {j} outside [{lo}, {hi}] at sample "
                                f"{bad[0]}: {q[bad[0]].tolist()}")
    c = clearances(arm, q, points)
    res.min_clearance = float(c.min()) if len(c) else math.inf
    hit = np.nonzero(~(c >= 0.0))[0]  # a NaN clearance is a hit
    if len(hit):
        res.problems.append(f"collision at sample {hit[0]} {q[hit[0]].tolist()}: "
                            f"clearance {c[hit[0]]:.5f} m")
    if "clearance_m" in plan:
        check_clearance(arm, q, pts, res.min_clearance, plan, res.problems)
    start, goal = scene["start"], scene["goal"]
    for name, target, q_end in (("start", start, wps[0]), ("goal", goal, wps[-1])):
        if "joints_deg" in target:
            d = np.asarray(q_end, float) - np.asarray(target["joints_deg"], float)
            d[0] = wrap180(d[0])
            if not np.max(np.abs(d)) <= 1e-6:  # NaN fails too
                res.problems.append(f"path {name} {q_end} is not {target}")
        else:
            tip = (arm.tip(q_end) if aims_tool_tip(target)
                   else arm.joints(q_end)[0, 3])
            if not np.linalg.norm(tip - np.asarray(target["xyz_m"], float)) <= 1e-6:
                res.problems.append(f"path {name} tip {tip.tolist()} misses {target}")
            check_branch(arm, name, target, q_end, plan.get(f"{name}_ik"),
                         res.problems)
    cost = path_length(arm, wps)
    cost_deg = plan.get("cost_deg", -1.0)
    if not (isinstance(cost_deg, numbers.Real) and abs(cost - cost_deg) <= 1e-4):
        res.problems.append(f"cost_deg {plan.get('cost_deg')} but path length {cost}")
    return res


def read_json_object(path):
    """The JSON object in path; ValueError (why) for anything else."""
    try:
        with open(path) as f:
            doc = json.load(f)
    except OSError as e:
        raise ValueError(f"{path}: cannot read: {e.strerror}") from None
    except ValueError as e:  # JSONDecodeError, bad UTF-8
        raise ValueError(f"{path}: not JSON: {e}") from None
    if not isinstance(doc, dict):
        raise ValueError(f"{path}: not a JSON object")
    return doc


def main(argv):
    if len(argv) != 3:
        print("usage: python tools/oracle.py SCENE.json PLAN.json   "
              "# exit 0 safe, 1 not, 2 cannot check", file=sys.stderr)
        return 2
    try:
        scene = read_json_object(argv[1])
        plan = read_json_object(argv[2])
        if plan.get("status") != "ok":
            print(f"plan status {plan.get('status')}: nothing to check")
            return 0
        points = scene_points(scene, os.path.dirname(argv[1]))
        res = check_path(scene, plan, points)
    except (ValueError, KeyError, TypeError, IndexError) as e:
        # a scene the planner would refuse: nothing checked, nothing safe
        why = e if isinstance(e, ValueError) else f"{type(e).__name__} {e}"
        print(f"oracle: cannot check: {why}", file=sys.stderr)
        return 2
    print(res)
    return 0 if res.safe else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
