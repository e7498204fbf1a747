#!/usr/bin/env python3
"""qrtplan against OMPL (RRTConnect, PRM, RRT*) on the same scenes.

Makes the scenes (the paper's Eq. 13 family with `qrtplan gen`; confined
scenes, a tunnel, a shelf and dense random clutter with tools/scenes.py),
runs build/bin/bench_ompl on them (the two sides interleaved repetition by
repetition in one process), checks every returned path with the independent
oracle (tools/oracle.py, 0.1 degree sampling), and writes
build/bench/ompl_compare.csv, ompl_summary.csv (per family),
ompl_per_scene.csv (per scene, qrtplan against RRTConnect),
ompl_compare.png (per family) and ompl_per_scene.png (each scene's speed-up
beside the 1x and 10x lines).

With --replanning, each planner first plans the scan before (the same scene,
every coordinate moved by up to 2 mm) untimed, as in a loop that replans on
every scan (bench_ompl's header says what the default regime leaves each
planner with), and the files are named ompl_*_replanning.*. With --cold,
every planner's timed run starts after 256 MiB have been written and read
back (its code and data evicted, and neither side left the points the other
read), and the files are named ompl_*_cold.*.

    .venv/bin/python tools/bench_compare.py [--repeats R] [--seeds N] [--replanning | --cold]
    .venv/bin/python tools/bench_compare.py --smoke      # a few seconds, for make test
"""
import argparse
import csv
import json
import os
import subprocess
import sys
from collections import defaultdict

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "tools"))
import oracle  # noqa: E402
import scenes  # noqa: E402

PLANNERS = ["qrtplan", "RRTConnect", "PRM", "RRTstar"]


def make_scenes(out, seeds, qrtplan, smoke):
    os.makedirs(out, exist_ok=True)
    made = []  # (family, path)
    paper = [(1, 16), (3, 361)] if smoke else [(1, 1444), (3, 1444), (10, 1444)]
    for n, k in paper:
        path = os.path.join(out, f"paper_{n}x{k}.json")
        args = [qrtplan, "gen", "--spheres", str(n), "--points", str(k), "-o", path]
        if n > 1:  # the Table 5 layout (tools/bench_table5.c's scene_for)
            args += ["--phase", str(90 - 180 / n), "--start",
                     f"{90 - 360 * (n // 2) / n},0,0", "--goal", "90,0,0"]
        subprocess.run(args, check=True)
        made.append(("paper Eq. 13", path))
    families = {"confined box": "box", "tunnel": "tunnel", "shelf": "shelf",
                "clutter": "spheres"}
    for label, fam in families.items():
        kept, seed = 0, 0
        while kept < (1 if smoke else seeds):
            sc = scenes.make_scene(fam, 1000 + seed)
            if label == "clutter":  # dense: five times the random spheres
                more = [scenes.make_scene(fam, 5000 + 7 * seed + i)["points"]
                        for i in range(4)]
                sc["points"] = sc["points"] + sum(more, [])
            seed += 1
            # a race needs a start and a goal that are free; the random
            # families draw them blind, so the oracle says which are
            why = unposed(sc)
            if why:
                print(f"{label}: seed {seed - 1} left out: {why}", file=sys.stderr)
                continue
            path = os.path.join(out, f"{fam}_{seed - 1}.json")
            with open(path, "w") as f:
                json.dump(sc, f)
            made.append((label, path))
            kept += 1
        if smoke:
            break
    return made


def ik_branches(arm, xyz):
    """Every joint solution (degrees, within the limits) that puts the tip
    at xyz: alpha toward the point or away from it, the elbow either way
    (docs/spec.md §Kinematics), each confirmed by the oracle's own kinematics."""
    l1, l2, l3 = arm.links
    x, y, z = xyz
    out = []
    for flip in (0.0, np.pi):
        a = np.arctan2(y, x) + flip
        u = np.hypot(x, y) * (1.0 if flip == 0.0 else -1.0) - l1
        c = (u * u + z * z - l2 * l2 - l3 * l3) / (2 * l2 * l3)
        if abs(c) > 1.0:
            continue
        for e in (np.arccos(c), -np.arccos(c)):
            s = np.arctan2(z, u) - np.arctan2(l3 * np.sin(e), l2 + l3 * np.cos(e))
            q = [oracle.wrap180(np.degrees(v)) for v in (a, s, e)]
            if not all(lo <= v <= hi for v, (lo, hi) in zip(q, arm.limits)):
                continue
            if np.linalg.norm(arm.joints(q)[0, -1] - np.asarray(xyz)) < 1e-6:
                out.append(q)
    return out


def unposed(sc):
    """Why the scene's start or goal is no race (both collide or lie out of
    reach for every branch), or None."""
    arm = oracle.Arm(sc)
    pts = np.asarray(sc["points"], float)
    for end in ("start", "goal"):
        t = sc[end]
        qs = [t["joints_deg"]] if "joints_deg" in t else ik_branches(arm, t["xyz_m"])
        if not qs:
            return f"the {end} is out of reach"
        c = oracle.clearances(arm, qs, pts)
        if c.max() < 0.0:
            return (f"the {end} collides (oracle clearance "
                    f"{1000 * c.max():.1f} mm)")
    return None


def check_oracle(scene_path, waypoints, cache={}):
    if scene_path not in cache:
        with open(scene_path) as f:
            sc = json.load(f)
        cache[scene_path] = (sc, oracle.scene_points(sc, os.path.dirname(scene_path)))
    sc, pts = cache[scene_path]
    arm = oracle.Arm(sc)
    q = oracle.sample_path(arm, waypoints)
    c = oracle.clearances(arm, q, pts)
    inside = all(lo - 1e-9 <= v <= hi + 1e-9 for j, (lo, hi) in enumerate(arm.limits)
                 if not (j == 0 and arm.alpha_wraps) for v in q[:, j])
    return bool(c.min() >= 0.0 and inside)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--time-limit", type=float, default=5.0)
    ap.add_argument("--smoke", action="store_true")
    ap.add_argument("--bench-ompl", default=os.path.join(REPO, "build", "bin", "bench_ompl"))
    ap.add_argument("--qrtplan", default=None)
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench"))
    regimes = ap.add_mutually_exclusive_group()
    regimes.add_argument("--replanning", action="store_true",
                         help="each planner first plans the scan before, untimed")
    regimes.add_argument("--cold", action="store_true",
                         help="each planner's timed run starts with the caches evicted")
    args = ap.parse_args()
    if args.replanning:
        suffix, flag = "_replanning", ["--replanning"]
        regime = "replanning: each planner right after its own plan of the scan before"
    elif args.cold:
        suffix, flag = "_cold", ["--cold"]
        regime = "cold: each planner after 256 MiB written (caches evicted)"
    else:
        suffix, flag = "", []
        regime = "in turn: each planner right after the others"
    print(f"regime: {regime}")
    qrtplan = args.qrtplan or os.path.join(os.path.dirname(args.bench_ompl), "qrtplan")
    if args.smoke:
        args.repeats, args.time_limit = 1, 2.0
    made = make_scenes(os.path.join(args.out, "ompl_scenes"), args.seeds, qrtplan,
                       args.smoke)
    family_of = {p: fam for fam, p in made}
    raw = os.path.join(args.out, f"ompl_compare{suffix}.csv")
    subprocess.run([args.bench_ompl, "--repeats", str(args.repeats), "--time-limit",
                    str(args.time_limit), "--csv", raw] + flag
                   + [p for _, p in made], check=True)
    rows = list(csv.DictReader(open(raw)))
    assert rows, "bench_ompl wrote no rows"
    stats = defaultdict(lambda: {"time": [], "len": [], "ok": 0, "n": 0, "safe": 0})
    problems = []
    for r in rows:
        assert r["planner"] in PLANNERS, r["planner"]
        key = (family_of[r["scene"]], r["planner"])
        s = stats[key]
        s["n"] += 1
        if r["success"] != "1":
            continue
        wps = json.loads(r["path"])
        assert len(wps) == int(r["waypoints"]) >= 1, r
        safe = check_oracle(r["scene"], wps) if len(wps) >= 2 else True
        s["ok"] += 1
        s["safe"] += safe
        s["time"].append(float(r["time_ms"]))
        s["len"].append(float(r["length_deg"]))
        if r["planner"] == "qrtplan" and not safe:
            problems.append(f"qrtplan path on {r['scene']} fails the oracle")
    fams = list(dict.fromkeys(f for f, _ in made))
    summary = os.path.join(args.out, f"ompl_summary{suffix}.csv")
    lines = []
    with open(summary, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["family", "planner", "runs", "success_rate", "median_ms",
                    "median_length_deg", "oracle_pass_rate"])
        for fam in fams:
            for pl in PLANNERS:
                s = stats.get((fam, pl))
                if not s or s["n"] == 0:
                    continue
                med = float(np.median(s["time"])) if s["time"] else float("nan")
                ln = float(np.median(s["len"])) if s["len"] else float("nan")
                w.writerow([fam, pl, s["n"], s["ok"] / s["n"], med, ln,
                            s["safe"] / s["ok"] if s["ok"] else float("nan")])
                lines.append((fam, pl, s["n"], s["ok"] / s["n"], med, ln,
                              s["safe"] / s["ok"] if s["ok"] else float("nan")))
    print(f"{'family':14} {'planner':11} {'runs':>4} {'success':>8} {'median ms':>10} "
          f"{'length deg':>10} {'oracle ok':>9}")
    for fam, pl, n, succ, med, ln, safe in lines:
        print(f"{fam:14} {pl:11} {n:4d} {succ:8.0%} {med:10.2f} {ln:10.1f} {safe:9.0%}")
    for fam in fams:
        ours = stats.get((fam, "qrtplan"))
        rrt = stats.get((fam, "RRTConnect"))
        if ours and rrt and ours["time"] and rrt["time"]:
            ratio = np.median(rrt["time"]) / np.median(ours["time"])
            who = (f"qrtplan {ratio:.1f}x faster than RRTConnect" if ratio >= 1
                   else f"RRTConnect {1 / ratio:.1f}x faster than qrtplan")
            print(f"{fam}: {who} in median time to a path; median length "
                  f"{np.median(ours['len']):.0f} (qrtplan) vs "
                  f"{np.median(rrt['len']):.0f} deg (RRTConnect)")
    speedups = per_scene(rows, family_of, made,
                         os.path.join(args.out, f"ompl_per_scene{suffix}.csv"))
    # drawn in the smoke run too, so that make test runs the plotting code
    plot(lines, fams, os.path.join(args.out, f"ompl_compare{suffix}.png"), regime)
    plot_per_scene(speedups, fams, os.path.join(args.out, f"ompl_per_scene{suffix}.png"),
                   regime)
    for p in problems:
        print("FAIL", p)
    return 1 if problems else 0


def per_scene(rows, family_of, made, path):
    """A family's median can hide a scene where RRTConnect is ahead: print
    and write each scene's medians (successful runs), and name those.
    Returns [(family, scene name, speed-up)]."""
    times, lens = defaultdict(list), defaultdict(list)
    for r in rows:
        if r["success"] == "1" and r["planner"] in ("qrtplan", "RRTConnect"):
            times[(r["scene"], r["planner"])].append(float(r["time_ms"]))
            lens[(r["scene"], r["planner"])].append(float(r["length_deg"]))
    behind, speedups = [], []
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["family", "scene", "qrtplan_median_ms", "rrtconnect_median_ms",
                    "speedup", "qrtplan_length_deg", "rrtconnect_length_deg"])
        print(f"{'scene':22} {'qrtplan ms':>10} {'RRTConnect ms':>13} {'speed-up':>8}")
        for _, scene in made:
            ours, rrt = times[(scene, "qrtplan")], times[(scene, "RRTConnect")]
            if not ours or not rrt:
                continue
            ratio = float(np.median(rrt) / np.median(ours))
            name = os.path.splitext(os.path.basename(scene))[0]
            w.writerow([family_of[scene], name, np.median(ours), np.median(rrt), ratio,
                        np.median(lens[(scene, "qrtplan")]),
                        np.median(lens[(scene, "RRTConnect")])])
            print(f"{name:22} {np.median(ours):10.2f} {np.median(rrt):13.2f} "
                  f"{ratio:7.1f}x")
            speedups.append((family_of[scene], name, ratio))
            if ratio < 1:
                behind.append(f"{name} ({1 / ratio:.2f}x)")
    print("RRTConnect ahead in median time on: " + (", ".join(behind) or "no scene"))
    return speedups


def plot_per_scene(speedups, fams, path, regime):
    """Each scene's speed-up over RRTConnect on a log axis, coloured by
    family, with the 1x (level) and 10x (the issue's target) lines: the
    picture of where qrtplan is ahead and by how much."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if not speedups:
        return
    colours = {fam: plt.get_cmap("tab10")(i) for i, fam in enumerate(fams)}
    fig, ax = plt.subplots(figsize=(8, 0.32 * len(speedups) + 1.4))
    y = np.arange(len(speedups))[::-1]
    ratios = [r for _, _, r in speedups]
    # bars grow from the level line: right where qrtplan is ahead, left
    # where RRTConnect is
    ax.barh(y, [r - 1.0 for r in ratios], left=1.0,
            color=[colours[f] for f, _, _ in speedups])
    for yi, r in zip(y, ratios):
        ax.text(r * 1.05 if r >= 1 else r / 1.05, yi, f"{r:.2f}x", va="center",
                ha="left" if r >= 1 else "right", fontsize=8)
    ax.set_yticks(y, [n for _, n, _ in speedups], fontsize=8)
    ax.set_xscale("log")
    ax.set_xlim(min(0.3, min(ratios) / 1.8), max(20.0, max(ratios) * 1.5))
    ticks = [t for t in (0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100)
             if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
    ax.set_xticks(ticks, [f"{t:g}x" for t in ticks])
    ax.axvline(1.0, color="black", lw=1)
    ax.axvline(10.0, color="grey", lw=1, ls="--")
    ax.text(1.02, y[0] + 0.7, "level", fontsize=8)
    ax.text(10.2, y[0] + 0.7, "10x target", fontsize=8, color="grey")
    ax.set_xlabel("RRTConnect median time / qrtplan median time (log; > 1: qrtplan ahead)")
    ax.set_title(f"speed-up over RRTConnect, scene by scene\n({regime})", fontsize=10)
    handles = [plt.Rectangle((0, 0), 1, 1, color=colours[f]) for f in fams]
    # outside the axes: inside, it covered the labels of the last bars
    ax.legend(handles, fams, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(axis="x", alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")


def plot(lines, fams, path, regime):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    width = 0.2
    x = np.arange(len(fams))
    for i, pl in enumerate(PLANNERS):
        t = [next((m for f, p, _, _, m, _, _ in lines if f == fam and p == pl), np.nan)
             for fam in fams]
        ln = [next((l for f, p, _, _, _, l, _ in lines if f == fam and p == pl), np.nan)
              for fam in fams]
        ax[0].bar(x + (i - 1.5) * width, t, width, label=pl)
        ax[1].bar(x + (i - 1.5) * width, ln, width, label=pl)
    # the target: a dash across qrtplan's bar at a tenth of
    # RRTConnect's median (the bar below the dash: 10x ahead)
    target = [next((m / 10.0 for f, p, _, _, m, _, _ in lines
                    if f == fam and p == "RRTConnect"), np.nan) for fam in fams]
    ax[0].hlines(target, x - 2.5 * width, x - 0.5 * width, colors="black", lw=2,
                 label="RRTConnect / 10 (the 10x target)")
    ax[0].set_yscale("log")
    low = np.nanmin([m for _, _, _, _, m, _, _ in lines] + target)
    if np.isfinite(low) and low > 0:  # room under the shortest bar and dash
        ax[0].set_ylim(bottom=low / 3.0)
    ax[0].set_ylabel("median time to a path, ms (log)")
    ax[1].set_ylabel("median joint-space path length, degrees")
    for a in ax:
        a.set_xticks(x, fams, rotation=15)
        a.grid(axis="y", alpha=0.3)
    ax[0].set_title("time to first path (RRT*: 1 s budget)")
    ax[1].set_title("path length")
    fig.suptitle(regime, fontsize=10)
    # one legend for both panels, under them: inside, it covered the bars
    handles, labels = ax[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="upper center", ncol=len(labels),
               bbox_to_anchor=(0.5, 0.02))
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    sys.exit(main())
