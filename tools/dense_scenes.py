#!/usr/bin/env python3
"""Dense confined scenes, as a depth camera sees a real cell: slots between
walls, shelves, closed cells with pillars and walls with a window, their
surfaces sampled 5-12 mm apart with 1 mm of sensor noise, 5e4-3e5 points.

Each scene is a scene file (docs/spec.md §Scene) with its points in a binary
PCD beside it (points_file). The start and goal are in the tight places (in
the slot, in a shelf compartment, through the window) and clear of every
point by at least --clear (2 mm) beyond the margin, as the independent
oracle (tools/oracle.py) measures them.

    python tools/dense_scenes.py OUT_DIR [--family F]... [--seeds A:B]
        [--points N]

writes OUT_DIR/<family>-<seed>.json and .pcd and prints one line each.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import oracle  # noqa: E402
import scenes  # noqa: E402

SPACING_M = (0.005, 0.012)  # a depth camera's return spacing at 0.5-1.5 m
POINTS = (50_000, 300_000)
NOISE_M = 0.001
CLEAR_M = 0.002  # ends at least this far beyond the margin, by the oracle
FLOOR_Z = -0.45


class Surfaces:
    """Rectangles (origin, u, v) sampled together at one spacing."""

    def __init__(self):
        self.rects = []

    def add(self, origin, u, v, hole=None):
        """hole: (centre, half_u, half_v) in the rectangle's own u, v
        directions, a rectangular opening left without points."""
        self.rects.append((np.asarray(origin, float), np.asarray(u, float),
                           np.asarray(v, float), hole))

    def area(self):
        return sum(np.linalg.norm(np.cross(u, v)) for _, u, v, _ in self.rects)

    def sample(self, rng, n_target):
        spacing = math.sqrt(self.area() / n_target)
        spacing = min(max(spacing, SPACING_M[0]), SPACING_M[1])
        parts = []
        for o, u, v, hole in self.rects:
            p = scenes.rect_points(o, u, v, spacing)
            if hole is not None:
                c, hu, hv = hole
                d = p - np.asarray(c, float)
                inside = ((np.abs(d @ (u / np.linalg.norm(u))) < hu) &
                          (np.abs(d @ (v / np.linalg.norm(v))) < hv))
                p = p[~inside]
            parts.append(p)
        p = np.vstack(parts)
        p += np.clip(rng.normal(0.0, NOISE_M, p.shape), -3 * NOISE_M, 3 * NOISE_M)
        return p, spacing


def frame(phi):
    """The radial and tangential unit vectors at bearing phi."""
    return (np.array([math.cos(phi), math.sin(phi), 0.0]),
            np.array([-math.sin(phi), math.cos(phi), 0.0]))


def floor(s, half=1.0):
    s.add([-half, -half, FLOOR_Z], [2 * half, 0, 0], [0, 2 * half, 0])


def slot(rng):
    """Two walls along a bearing, a slot 15-24 cm wide between them (the
    links are 4 cm thick, 6 cm with the margins), over a floor."""
    phi = rng.uniform(-math.pi, math.pi)
    n, t = frame(phi)
    w = rng.uniform(0.15, 0.24)
    s = Surfaces()
    for side in (-1, 1):
        s.add(0.22 * n + side * w / 2 * t + [0, 0, FLOOR_Z], 0.8 * n,
              [0, 0, 1.1])
    floor(s)
    inside = lambda tip: ((np.abs(tip @ t) < w / 2 - 0.05) &  # noqa: E731
                          (tip @ n > 0.35) & (tip[:, 2] > FLOOR_Z + 0.1))
    return s, inside, inside


def shelves(rng):
    """A shelf unit facing the arm: boards, sides and a back; the start in
    one compartment, the goal in another."""
    phi = rng.uniform(-math.pi, math.pi)
    n, t = frame(phi)
    d, depth, width = rng.uniform(0.42, 0.55), 0.35, rng.uniform(0.7, 0.9)
    gap = rng.uniform(0.22, 0.3)
    levels = FLOOR_Z + 0.15 + gap * np.arange(4)
    s = Surfaces()
    for z in levels:
        s.add(d * n - width / 2 * t + [0, 0, z], depth * n, width * t)
    for side in (-1, 1):
        s.add(d * n + side * width / 2 * t + [0, 0, FLOOR_Z], depth * n,
              [0, 0, levels[-1] - FLOOR_Z])
    s.add((d + depth) * n - width / 2 * t + [0, 0, FLOOR_Z], width * t,
          [0, 0, levels[-1] - FLOOR_Z])
    floor(s)
    a, b = rng.choice(3, 2, replace=False)

    def compartment(k):
        def inside(tip):
            r = tip @ n
            return ((r > d + 0.08) & (r < d + depth - 0.05) &
                    (np.abs(tip @ t) < width / 2 - 0.06) &
                    (tip[:, 2] > levels[k] + 0.06) &
                    (tip[:, 2] < levels[k + 1] - 0.06))
        return inside
    return s, compartment(a), compartment(b)


def cell(rng):
    """The arm closed in a cell: floor, ceiling, four walls inside its reach
    and two or three pillars; the ends anywhere clear."""
    h, top = rng.uniform(0.6, 0.8), rng.uniform(0.5, 0.75)
    s = Surfaces()
    floor(s, h)
    s.add([-h, -h, top], [2 * h, 0, 0], [0, 2 * h, 0])
    for k in range(4):
        n, t = frame(k * math.pi / 2)
        s.add(h * n - h * t + [0, 0, FLOOR_Z], 2 * h * t, [0, 0, top - FLOOR_Z])
    for _ in range(rng.integers(2, 4)):
        n, t = frame(rng.uniform(-math.pi, math.pi))
        c = rng.uniform(0.4, h - 0.12) * n
        e = rng.uniform(0.05, 0.1)
        for a, b in ((n, t), (t, -n), (-n, -t), (-t, n)):
            s.add(c + e * a - e * b + [0, 0, FLOOR_Z], 2 * e * b,
                  [0, 0, top - FLOOR_Z])
    anywhere = lambda tip: tip[:, 2] > FLOOR_Z + 0.1  # noqa: E731
    return s, anywhere, anywhere


def window(rng):
    """A wall before the arm with a window 16-24 cm square: the goal is
    behind it, through the window."""
    phi = rng.uniform(-math.pi, math.pi)
    n, t = frame(phi)
    d, size = rng.uniform(0.4, 0.55), rng.uniform(0.16, 0.24)
    zc = rng.uniform(0.0, 0.3)
    s = Surfaces()
    o = d * n - 0.7 * t + [0, 0, FLOOR_Z]
    s.add(o, 1.4 * t, [0, 0, 1.2], hole=(d * n + [0, 0, zc], size / 2, size / 2))
    floor(s)
    before = lambda tip: (tip @ n < d - 0.1) & (tip[:, 2] > FLOOR_Z + 0.1)  # noqa: E731

    def behind(tip):
        return ((tip @ n > d + 0.1) & (np.abs(tip @ t) < 0.3) &
                (tip[:, 2] > FLOOR_Z + 0.1))
    return s, before, behind


FAMILIES = {"slot": slot, "shelves": shelves, "cell": cell, "window": window}


def clear_end(rng, arm, points, where, clear_m, tries=4000):
    """Joints in the limits whose end-effector point `where` accepts and
    whose clearance (oracle) is at least clear_m; None if none found."""
    lo = np.array([l[0] for l in arm.limits])
    hi = np.array([l[1] for l in arm.limits])
    q = rng.uniform(lo, hi, (tries, 3))
    q = q[where(arm.joints(q)[:, 3, :])]
    for cand in q[:60]:
        if oracle.clearances(arm, cand[None, :], points)[0] >= clear_m:
            return [round(float(x), 4) for x in cand]
    return None


def write_pcd(path, pts):
    pts = np.asarray(pts, "<f4")
    header = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
              "TYPE F F F\nCOUNT 1 1 1\n"
              f"WIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
              f"POINTS {len(pts)}\nDATA binary\n")
    with open(path, "wb") as f:
        f.write(header.encode() + pts.tobytes())


def make(family, seed, out_dir, n_points=None, clear_m=CLEAR_M):
    """Writes the scene and its PCD, its ends clear_m beyond the margin;
    returns (scene path, scene, points, spacing), or None when no such start
    and goal were found."""
    rng = np.random.default_rng(seed)
    surfaces, start_in, goal_in = FAMILIES[family](rng)
    n = n_points or int(math.exp(rng.uniform(*np.log(POINTS))))
    pts, spacing = surfaces.sample(rng, n)
    # the oracle reads the PCD's float32 coordinates: check against those
    pts = pts.astype("<f4").astype(float)
    name = f"{family}-{seed}"
    scene = {"version": 1, "name": name, "points_file": name + ".pcd"}
    arm = oracle.Arm(scene)
    start = clear_end(rng, arm, pts, start_in, clear_m)
    goal = clear_end(rng, arm, pts, goal_in, clear_m)
    if start is None or goal is None:
        return None
    scene["start"] = {"joints_deg": start}
    scene["goal"] = {"joints_deg": goal}
    write_pcd(os.path.join(out_dir, name + ".pcd"), pts)
    path = os.path.join(out_dir, name + ".json")
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
    return path, scene, pts, spacing


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--family", action="append", choices=sorted(FAMILIES))
    ap.add_argument("--seeds", default="0:2", help="A:B, seeds A..B-1")
    ap.add_argument("--points", type=int, help="points per scene (default: "
                    f"log-uniform in {POINTS[0]}..{POINTS[1]})")
    ap.add_argument("--clear", type=float, default=CLEAR_M,
                    help="metres the ends keep beyond the margin")
    args = ap.parse_args()
    a, b = (int(x) for x in args.seeds.split(":"))
    os.makedirs(args.out_dir, exist_ok=True)
    for fam in args.family or sorted(FAMILIES):
        for seed in range(a, b):
            made = make(fam, seed, args.out_dir, args.points, args.clear)
            if made is None:
                print(f"{fam}-{seed}: no clear start and goal found")
                continue
            path, scene, pts, spacing = made
            print(f"{path}: {len(pts)} points, {spacing * 1000:.1f} mm apart")


if __name__ == "__main__":
    main()
