#!/usr/bin/env python3
"""The Python package's overhead over its C call (issue 38's benchmark), on
the paper's 10 spheres x 1444 points (scenes/ten_spheres.json, the scene of
bench_table5 and bench_daemon), in one process.

One Planner, the points an (N, 3) float64 array made once; every call of
Planner.plan is timed around it (time.perf_counter) and, inside the C
layer, around the C work (clock_gettime: points replaced, the plan, the
result copied out; PlanResult.stats["c_seconds"]). The overhead is what the
Python call adds: argument checks (shape, dtype; the core checks the
points' finiteness), the ctypes call, the result's arrays. Prints the medians of both,
the median of the per-call differences and its ratio to the C median;
writes OUT/python_overhead.csv (--out, default build/bench). --check: exit 1 above --limit.

    .venv/bin/python tools/bench_python.py [--calls N] [--whole-mask]

Uses the installed package, or python/ with the build tree
(QRTPLAN_BUILD_DIR, default build/) when none is installed.
"""
import argparse
import csv
import json
import os
import platform
import statistics
import sys
import time

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
try:
    import qrtplan
    qrtplan.Planner  # noqa: B018  (the generated lcm package has none)
except (ImportError, AttributeError):
    for m in [m for m in sys.modules if m == "qrtplan" or m.startswith("qrtplan.")]:
        del sys.modules[m]
    sys.path.insert(0, os.path.join(REPO, "python"))
    import qrtplan


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--calls", type=int, default=400)
    ap.add_argument("--whole-mask", action="store_true")
    ap.add_argument("--scene", default=os.path.join(REPO, "scenes", "ten_spheres.json"))
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench"))
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--limit", type=float, default=0.10)
    args = ap.parse_args()
    scene = json.load(open(args.scene))
    pts = np.asarray(scene["points"], dtype=np.float64)
    planner = qrtplan.Planner(whole_mask=args.whole_mask)
    start, goal = scene["start"]["joints_deg"], scene["goal"]["joints_deg"]
    for _ in range(20):  # warm up: caches, pages of the planner's state
        planner.plan(pts, start, goal)
    py, c = [], []
    for _ in range(args.calls):
        t0 = time.perf_counter()
        r = planner.plan(pts, start, goal)
        py.append(time.perf_counter() - t0)
        c.append(r.stats["c_seconds"])
    diff = [a - b for a, b in zip(py, c)]
    mp, mc, md = statistics.median(py), statistics.median(c), statistics.median(diff)
    ratio = md / mc
    print(f"{os.path.basename(args.scene)} ({len(pts)} points, "
          f"{'whole mask' if args.whole_mask else 'as read'}), {args.calls} calls, "
          f"{platform.python_implementation()} {platform.python_version()}, "
          f"numpy {np.__version__}, {qrtplan.__file__}")
    print(f"median Python call {mp * 1e3:.3f} ms, C call {mc * 1e3:.3f} ms, "
          f"overhead {md * 1e6:.1f} us = {100 * ratio:.1f} % of the C call")
    out = args.out
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "python_overhead.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["python_s", "c_s"])
        w.writerows(zip(py, c))
    if args.check and ratio > args.limit:
        print(f"overhead above {100 * args.limit:.0f} %", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
