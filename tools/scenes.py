"""Seeded random scenes for qrtplan's tests: spheres, boxes, walls, and
confined scenes (the arm inside a box with openings, a tunnel through a wall,
a shelf). Every scene is a dict in the scene format of docs/spec.md §Scene."""
import math

import numpy as np

LIMITS = ((-180.0, 180.0), (-40.0, 180.0), (-180.0, 140.0))


def sphere_points(c, r, spacing=0.02):
    k = max(6, int(math.ceil(math.pi * r / spacing)))
    t1 = np.linspace(-math.pi, math.pi, 2 * k, endpoint=False)
    t2 = np.linspace(-math.pi / 2, math.pi / 2, k)
    a, b = np.meshgrid(t1, t2)
    p = np.stack([np.cos(a) * np.cos(b), np.sin(a) * np.cos(b), np.sin(b)], -1)
    return np.asarray(c) + r * p.reshape(-1, 3)


def rect_points(origin, u, v, spacing=0.02):
    """Points on the parallelogram origin + s*u + t*v, s, t in [0, 1]."""
    u, v = np.asarray(u, float), np.asarray(v, float)
    nu = max(2, int(math.ceil(np.linalg.norm(u) / spacing)) + 1)
    nv = max(2, int(math.ceil(np.linalg.norm(v) / spacing)) + 1)
    s, t = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv))
    return (np.asarray(origin, float) + s.reshape(-1, 1) * u +
            t.reshape(-1, 1) * v)


def box_points(centre, size, yaw=0.0, spacing=0.02):
    c, (sx, sy, sz) = np.asarray(centre, float), size
    ca, sa = math.cos(yaw), math.sin(yaw)
    ex = np.array([ca, sa, 0.0]) * sx
    ey = np.array([-sa, ca, 0.0]) * sy
    ez = np.array([0.0, 0.0, sz])
    o = c - (ex + ey + ez) / 2
    faces = [(o, ex, ey), (o + ez, ex, ey), (o, ex, ez), (o + ey, ex, ez),
             (o, ey, ez), (o + ex, ey, ez)]
    return np.vstack([rect_points(f[0], f[1], f[2], spacing) for f in faces])


def holed_rect(origin, u, v, hole_c, hole_r, spacing=0.02):
    p = rect_points(origin, u, v, spacing)
    keep = np.linalg.norm(p - np.asarray(hole_c), axis=1) > hole_r
    return p[keep]


def random_joints(rng, limits=LIMITS):
    return [float(rng.uniform(lo, hi)) for lo, hi in limits]


def tip(q):
    a, s, e = np.radians(q)
    l1, l2, l3 = 0.090, 0.332, 0.538
    r = l1 + l2 * math.cos(s) + l3 * math.cos(s + e)
    return [r * math.cos(a), r * math.sin(a), l2 * math.sin(s) + l3 * math.sin(s + e)]


def targets(rng, limits=LIMITS):
    """A start as joints and a goal as joints or as an end-effector point."""
    start = {"joints_deg": random_joints(rng, limits)}
    if rng.uniform() < 0.5:
        goal = {"joints_deg": random_joints(rng, limits)}
    else:
        goal = {"xyz_m": tip(random_joints(rng, limits))}
    return start, goal


def random_spheres(rng):
    pts = []
    for _ in range(rng.integers(1, 6)):
        rho, phi = rng.uniform(0.25, 0.95), rng.uniform(-math.pi, math.pi)
        c = [rho * math.cos(phi), rho * math.sin(phi), rng.uniform(-0.4, 0.6)]
        pts.append(sphere_points(c, rng.uniform(0.04, 0.15)))
    return np.vstack(pts)


def random_boxes(rng):
    pts = []
    for _ in range(rng.integers(1, 4)):
        rho, phi = rng.uniform(0.3, 0.9), rng.uniform(-math.pi, math.pi)
        c = [rho * math.cos(phi), rho * math.sin(phi), rng.uniform(-0.4, 0.5)]
        size = rng.uniform(0.05, 0.3, 3)
        pts.append(box_points(c, size, rng.uniform(0, math.pi), spacing=0.025))
    return np.vstack(pts)


def random_walls(rng):
    pts = []
    for _ in range(rng.integers(1, 3)):
        phi = rng.uniform(-math.pi, math.pi)
        d = rng.uniform(0.35, 0.9)
        n = np.array([math.cos(phi), math.sin(phi), 0.0])
        t = np.array([-math.sin(phi), math.cos(phi), 0.0])
        o = d * n - 0.5 * t + np.array([0, 0, rng.uniform(-0.6, -0.2)])
        pts.append(rect_points(o, t * rng.uniform(0.4, 1.0),
                               [0, 0, rng.uniform(0.3, 1.0)], spacing=0.025))
    if rng.uniform() < 0.5:  # a table under the arm
        z = rng.uniform(-0.45, -0.15)
        pts.append(rect_points([-0.9, -0.9, z], [1.8, 0, 0], [0, 1.8, 0], 0.05))
    return np.vstack(pts)


def confined_box(rng):
    """The arm inside a box with one or two round openings."""
    h = rng.uniform(0.75, 0.95)
    lo, hi = -0.5, rng.uniform(0.5, 0.9)
    # 5 cm spacing: still closer than a link's 6 cm diameter
    pts = [rect_points([-h, -h, lo], [2 * h, 0, 0], [0, 2 * h, 0], 0.05),
           rect_points([-h, -h, hi], [2 * h, 0, 0], [0, 2 * h, 0], 0.05)]
    for w in range(4):
        phi = w * math.pi / 2
        n = np.array([math.cos(phi), math.sin(phi), 0.0])
        t = np.array([-math.sin(phi), math.cos(phi), 0.0])
        o = h * n - h * t + [0, 0, lo]
        hole = h * n + [0, 0, rng.uniform(-0.1, 0.3)]
        r = rng.uniform(0.1, 0.2) if w < rng.integers(1, 3) else 0.0
        pts.append(holed_rect(o, 2 * h * t, [0, 0, hi - lo], hole, r, 0.05))
    return np.vstack(pts)


def tunnel(rng):
    """A wall in front of the arm with a hole to reach through."""
    phi = rng.uniform(-math.pi, math.pi)
    d = rng.uniform(0.45, 0.7)
    n = np.array([math.cos(phi), math.sin(phi), 0.0])
    t = np.array([-math.sin(phi), math.cos(phi), 0.0])
    hole = d * n + [0, 0, rng.uniform(-0.1, 0.25)]
    wall = holed_rect(d * n - 0.6 * t + [0, 0, -0.5], 1.2 * t, [0, 0, 1.2],
                      hole, rng.uniform(0.09, 0.16), 0.02)
    return wall


def shelf(rng):
    phi = rng.uniform(-math.pi, math.pi)
    n = np.array([math.cos(phi), math.sin(phi), 0.0])
    t = np.array([-math.sin(phi), math.cos(phi), 0.0])
    pts = []
    for z in np.arange(rng.uniform(-0.4, -0.2), 0.7, rng.uniform(0.22, 0.35)):
        pts.append(rect_points(0.4 * n - 0.4 * t + [0, 0, z], 0.4 * n,
                               0.8 * t, 0.03))
    return np.vstack(pts)


def limits_within(rng, lo, hi, min_span):
    a = rng.uniform(lo, hi - min_span)
    return [float(a), float(rng.uniform(a + min_span, hi))]


def varied_arm(rng):
    """Spheres with the arm's settings varied: radii, margins, grid, C-space
    margin and narrower joint limits (alpha then stops wrapping)."""
    scene_extra = {
        "arm": {"link_radius_m": rng.uniform(0.01, 0.05, 3).round(4).tolist(),
                "limits_deg": [[-180.0, 180.0] if rng.uniform() < 0.5 else
                               limits_within(rng, -180, 180, 90),
                               limits_within(rng, -40, 180, 80),
                               limits_within(rng, -180, 140, 120)]},
        "margin_m": float(rng.uniform(0.0, 0.03)),
        "grid_deg": float(rng.choice([5, 10, 20])),
        "cspace_margin_deg": float(rng.choice([0.0, 1.0, 3.0])),
    }
    return random_spheres(rng), scene_extra


FAMILIES = {"spheres": random_spheres, "boxes": random_boxes,
            "walls": random_walls, "box": confined_box, "tunnel": tunnel,
            "shelf": shelf, "varied": varied_arm}


def make_scene(family, seed):
    rng = np.random.default_rng(seed)
    made = FAMILIES[family](rng)
    pts, extra = made if isinstance(made, tuple) else (made, {})
    scene = {"version": 1, "name": f"{family}-{seed}", **extra,
             "points": np.round(pts, 6).tolist()}
    scene["start"], scene["goal"] = targets(rng, scene_limits(scene))
    return scene


def scene_limits(scene):
    return scene.get("arm", {}).get("limits_deg", LIMITS)
