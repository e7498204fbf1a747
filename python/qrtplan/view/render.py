"""A picture of a qrtplan-view recording, drawn from the MCAP file alone
(what a Foxglove 3D panel shows, for the README where no Foxglove app runs):

  python -m qrtplan.view.render session.mcap session.png [--at S]

Left: the arm's capsules at the joint state at --at seconds (default: the
middle of the motion), the newest ok plan's tool path and ghost arms, the
newest obstacle cloud of each sensor. Right: the plan's status, the drives'
states and the joints over time."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from .recording import read


def _capsule_ends(entity):
    """(p0, p1) of each capsule of a SceneEntity: its spheres in pairs."""
    s = [(p.pose.position.x, p.pose.position.y, p.pose.position.z)
         for p in entity.spheres]
    return [(np.array(s[i]), np.array(s[i + 1])) for i in range(0, len(s) - 1, 2)]


def _before(msgs, t):
    """The last message logged at or before t (the first if none)."""
    best = msgs[0] if msgs else None
    for lt, m in msgs:
        if lt > t:
            break
        best = (lt, m)
    return best[1] if best else None


def render(mcap_path, png_path, at_s=None, dpi=80):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rec = read(mcap_path)
    js = rec.messages.get("/qrtplan/joint_state", [])
    if not js:
        raise SystemExit(f"{mcap_path}: no joint states recorded")
    t0 = js[0][0]
    times = np.array([(lt - t0) / 1e9 for lt, _ in js])
    q = np.array([m["joints_deg"] for _, m in js])
    if at_s is None:
        moving = [i for i, (_, m) in enumerate(js) if m["moving"]]
        i = moving[len(moving) // 2] if moving else len(js) - 1
    else:
        i = int(np.clip(np.searchsorted(times, at_s), 0, len(js) - 1))
    t = js[i][0]

    fig = plt.figure(figsize=(10, 5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    seen = []  # every point drawn, for the axes' limits
    for topic, msgs in rec.messages.items():
        if topic.startswith("/obstacles/") and msgs:
            cloud = _before(msgs, t)
            p = np.frombuffer(cloud.data, "<f4").reshape(-1, 3)
            if len(p) > 4000:  # enough to see; keeps the PNG small
                p = p[np.linspace(0, len(p) - 1, 4000).astype(int)]
            seen.append(p)
            n = len(cloud.data) // max(cloud.point_stride, 1)
            ax.scatter(p[:, 0], p[:, 1], p[:, 2], s=2, c="crimson",
                       label=f"{topic} ({n} points)")
    plan = None
    for lt, m in rec.messages.get("/plan", []):
        if lt > t:
            break
        ents = {e.id: e for e in m.entities}
        if "tool_path" in ents and ents["tool_path"].lines:
            plan = ents
    if plan:
        line = plan["tool_path"].lines[0].points
        seen.append(np.array([[p.x, p.y, p.z] for p in line]))
        ax.plot([p.x for p in line], [p.y for p in line], [p.z for p in line],
                color="darkorange", lw=2, label="planned tool path")
        for a, b in _capsule_ends(plan["ghosts"]):
            ax.plot(*zip(a, b), color="grey", alpha=0.35, lw=3)
    arm = _before(rec.messages["/arm"], t).entities[0]
    for k, (a, b) in enumerate(_capsule_ends(arm)):
        seen.append(np.array([a, b]))
        ax.plot(*zip(a, b), color="royalblue", lw=7, solid_capstyle="round",
                label="arm (measured joints)" if k == 0 else None)
    allp = np.vstack(seen + [np.zeros((1, 3))])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    c, h = (lo + hi) / 2, (hi - lo).max() / 2 * 1.1 + 0.05
    for setlim, k in ((ax.set_xlim, 0), (ax.set_ylim, 1), (ax.set_zlim, 2)):
        setlim(c[k] - h, c[k] + h)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.view_init(elev=28, azim=-60)
    ax.legend(loc="upper left", fontsize=7)
    ax.set_title(f"{mcap_path.split('/')[-1]} at t = {times[i]:.1f} s",
                 fontsize=9)

    ax2 = fig.add_subplot(2, 2, 2)
    for k, name in enumerate(("alpha", "sigma", "eta")):
        y = q[:, k].copy()
        if k == 0:
            y[1:][np.abs(np.diff(y)) > 180] = np.nan
        ax2.plot(times, y, label=name)
    ax2.axvline(times[i], color="k", lw=0.8)
    ax2.set_xlabel("time (s)", fontsize=8)
    ax2.set_ylabel("joints (deg)", fontsize=8)
    ax2.legend(fontsize=7)
    ax2.tick_params(labelsize=7)
    ax3 = fig.add_subplot(2, 2, 4)
    ax3.axis("off")
    ps = _before(rec.messages.get("/plan/status", []), t)
    dr = _before(rec.messages.get("/drives", []), t)
    st = _before(rec.messages.get("/qrtplan/status", []), t)
    lines = []
    if ps:
        lines += [f"plan {ps['request_id']}: {ps['status']}, "
                  f"{ps['n_waypoints']} waypoints, {ps['cost_deg']:.1f} deg",
                  f"points {ps['points']}, total {ps['total_us'] / 1e3:.1f} ms"]
    lines.append(f"drives: {js[i][1]['drive_state']}"
                 f"{' (moving)' if js[i][1]['moving'] else ''}")
    if dr and dr.get("can_state"):
        lines.append(f"CAN: {dr['can_state'][:60]}")
    if st:
        lines.append(f"scans {st['scans_received']}, plans "
                     f"{st['plans_published']}, lcm input {st['lcm_input']}")
    ax3.text(0, 1, "\n".join(lines), va="top", fontsize=8, family="monospace")
    fig.tight_layout()
    fig.savefig(png_path, dpi=dpi)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m qrtplan.view.render",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("mcap")
    p.add_argument("png")
    p.add_argument("--at", type=float, metavar="S",
                   help="seconds after the first joint state")
    p.add_argument("--dpi", type=int, default=80)
    a = p.parse_args(argv)
    render(a.mcap, a.png, a.at, a.dpi)
    return 0


if __name__ == "__main__":
    sys.exit(main())
