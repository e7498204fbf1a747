#!/usr/bin/env python3
"""Pictures of a plan, like the paper's Figs 16, 18 and 19.

    plot_plan.py SCENE.json PLAN.json MASK.json OUTPREFIX

writes OUTPREFIX_cspace.png (the blocked lattice nodes and the path in joint
space, with an alpha-sigma slice) and OUTPREFIX_arm.png (the obstacle points
and the arm moving along the path in 3-D). MASK.json is `qrtplan mask`'s
output for the same scene."""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import oracle  # noqa: E402


def blocked_nodes(mask):
    na, ns, ne = mask["n"]
    idx = np.asarray(mask["blocked"], int)
    a, rest = np.divmod(idx, ns * ne)
    s, e = np.divmod(rest, ne)
    g, lo = mask["grid_deg"], mask["lo_deg"]
    return np.stack([lo[0] + a * g, lo[1] + s * g, lo[2] + e * g], axis=1)


def split_at_wrap(q):
    """Pieces of a sampled path that do not jump across alpha = +-180."""
    cut = np.nonzero(np.abs(np.diff(q[:, 0])) > 180.0)[0]
    return np.split(q, cut + 1)


def plot_cspace(scene, plan, mask, out):
    arm = oracle.Arm(scene)
    nodes = blocked_nodes(mask)
    fig = plt.figure(figsize=(13, 5.8))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.scatter(nodes[:, 0], nodes[:, 1], nodes[:, 2], s=2, c="tab:red",
               alpha=0.08, depthshade=False, label="blocked node")
    title = f"{scene.get('name', 'scene')}: {plan['status']}"
    if plan["status"] == "ok":
        q = oracle.sample_path(arm, plan["waypoints_deg"], step=0.5)
        for k, piece in enumerate(split_at_wrap(q)):
            ax.plot(piece[:, 0], piece[:, 1], piece[:, 2], c="tab:blue", lw=2.5,
                    label="path" if k == 0 else None)
        w = np.asarray(plan["waypoints_deg"])
        ax.scatter(*w[0], c="tab:green", s=60, label="start")
        ax.scatter(*w[-1], c="magenta", s=60, label="goal")
        title += f", {len(w)} waypoints, {plan['cost_deg']:.1f} deg"
    ax.set_xlabel("alpha (deg)")
    ax.set_ylabel("sigma (deg)")
    ax.set_zlabel("eta (deg)")
    ax.set_xlim(-180, 180)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title("C-space: " + title, fontsize=10)

    ax2 = fig.add_subplot(1, 2, 2)
    na, ns, ne = mask["n"]
    g, lo = mask["grid_deg"], mask["lo_deg"]
    grid = np.zeros((ns, na))
    ai = np.round((nodes[:, 0] - lo[0]) / g).astype(int)
    si = np.round((nodes[:, 1] - lo[1]) / g).astype(int)
    np.add.at(grid, (si, ai), 1.0 / ne)
    im = ax2.imshow(grid, origin="lower", aspect="auto", cmap="Reds",
                    extent=[lo[0] - g / 2, lo[0] + (na - 0.5) * g,
                            lo[1] - g / 2, lo[1] + (ns - 0.5) * g])
    fig.colorbar(im, ax=ax2, label="share of eta values blocked")
    if plan["status"] == "ok":
        for piece in split_at_wrap(q):
            ax2.plot(piece[:, 0], piece[:, 1], c="tab:blue", lw=2)
        ax2.plot(*w[0][:2], "o", c="tab:green")
        ax2.plot(*w[-1][:2], "o", c="magenta")
    ax2.set_xlabel("alpha (deg)")
    ax2.set_ylabel("sigma (deg)")
    ax2.set_title("alpha-sigma projection (path in blue)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_arm(scene, plan, points, out):
    arm = oracle.Arm(scene)
    fig = plt.figure(figsize=(8, 7))
    ax = fig.add_subplot(projection="3d")
    if len(points):
        ax.scatter(points[:, 0], points[:, 1], points[:, 2], s=1, c="grey",
                   alpha=0.35, label="obstacle points")
    if plan["status"] == "ok":
        q = oracle.sample_path(arm, plan["waypoints_deg"], step=0.25)
        poses = q[np.linspace(0, len(q) - 1, 14).astype(int)]
        colours = plt.cm.cool(np.linspace(0, 1, len(poses)))
        for k, (pose, c) in enumerate(zip(poses, colours)):
            p = arm.joints(pose)[0]
            ax.plot(p[:, 0], p[:, 1], p[:, 2], "-o", c=c, lw=2.5, ms=3)
        tips = arm.joints(q)[:, 3]
        ax.plot(tips[:, 0], tips[:, 1], tips[:, 2], c="k", lw=0.8,
                label="tool tip")
        start, goal = arm.joints(q[0])[0], arm.joints(q[-1])[0]
        ax.plot(start[:, 0], start[:, 1], start[:, 2], "-o", c="tab:green",
                lw=3, label="start")
        ax.plot(goal[:, 0], goal[:, 1], goal[:, 2], "-o", c="magenta", lw=3,
                label="goal")
    r = 1.0
    ax.set_xlim(-r, r)
    ax.set_ylim(-r, r)
    ax.set_zlim(-r, r)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"{scene.get('name', 'scene')}: arm along the path "
                 f"(cyan to magenta)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main(argv):
    if len(argv) != 5:
        print(__doc__, file=sys.stderr)
        return 2
    with open(argv[1]) as f:
        scene = json.load(f)
    with open(argv[2]) as f:
        plan = json.load(f)
    with open(argv[3]) as f:
        mask = json.load(f)
    points = oracle.scene_points(scene, os.path.dirname(argv[1]))
    plot_cspace(scene, plan, mask, argv[4] + "_cspace.png")
    plot_arm(scene, plan, points, argv[4] + "_arm.png")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
