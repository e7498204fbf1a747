#!/usr/bin/env python3
"""`qrtplan plan` on the dense confined family beside the same scenes
thinned to 10^4 points: time, path length, how the plan was found, and
whether the thinned scene's path is safe against the dense points.

Each scene of tools/dense_scenes.py (5e4-3e5 points, ends in the tight
places) is planned as is and as a random 10^4-point subset (the same start
and goal), each --repeats times in turn; the figures are medians of the
plan's own time_us.total. The oracle (tools/oracle.py) checks every ok path
against the dense points: a path planned on the thinned cloud may pass
through gaps that only the dense cloud shows. Writes dense.csv and prints a
summary; part of `make bench`.

    python tools/bench_dense.py [--seeds A:B] [--repeats N] [--out DIR]
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import dense_scenes  # noqa: E402
import oracle  # noqa: E402

REPO = os.path.dirname(HERE)
BIN = os.environ.get("QRTPLAN_BIN", os.path.join(REPO, "build", "bin", "qrtplan"))
THIN = 10_000


def plan(path, repeats):
    runs = []
    for _ in range(repeats):
        r = subprocess.run([BIN, "plan", path], capture_output=True, text=True,
                           timeout=600, check=True)
        runs.append(json.loads(r.stdout))
    p = runs[-1]
    p["median_ms"] = statistics.median(q["stats"]["time_us"]["total"]
                                       for q in runs) / 1000.0
    return p


def thinned(scene_path, scene, pts, rng, out):
    keep = np.sort(rng.choice(len(pts), size=min(THIN, len(pts)), replace=False))
    name = os.path.splitext(os.path.basename(scene_path))[0] + "-thin"
    dense_scenes.write_pcd(os.path.join(out, name + ".pcd"), pts[keep])
    thin = dict(scene, name=name, points_file=name + ".pcd")
    path = os.path.join(out, name + ".json")
    with open(path, "w") as f:
        json.dump(thin, f)
    return path


def row(family, seed, kind, n, p, scene, dense_pts):
    ok = p["status"] == "ok"
    verdict = ""
    if ok:
        verdict = "safe" if oracle.check_path(scene, p, dense_pts).safe else "UNSAFE"
    return {"scene": f"{family}-{seed}", "cloud": kind, "points": n,
            "status": p["status"],
            "found_by": ("" if not ok else
                         "sampling" if "sampling" in p["detail"] else "lattice"),
            "cost_deg": f"{p['cost_deg']:.2f}" if ok else "",
            "median_ms": f"{p['median_ms']:.1f}",
            "against_dense_points": verdict}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="0:2", help="A:B, seeds A..B-1 per family")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench"))
    args = ap.parse_args()
    a, b = (int(x) for x in args.seeds.split(":"))
    os.makedirs(args.out, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for family in sorted(dense_scenes.FAMILIES):
            for seed in range(a, b):
                made = dense_scenes.make(family, seed, d)
                if made is None:
                    continue
                path, scene, pts, _ = made
                thin_path = thinned(path, scene, pts,
                                    np.random.default_rng(seed), d)
                dense_plan = plan(path, args.repeats)
                thin_plan = plan(thin_path, args.repeats)
                rows.append(row(family, seed, "dense", len(pts), dense_plan,
                                scene, pts))
                rows.append(row(family, seed, "thinned", min(THIN, len(pts)),
                                thin_plan, scene, pts))
                print(f"{family}-{seed}: {rows[-2]} | {rows[-1]}", flush=True)
    table = os.path.join(args.out, "dense.csv")
    with open(table, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    dense = [r for r in rows if r["cloud"] == "dense"]
    thin = [r for r in rows if r["cloud"] == "thinned"]
    print(f"dense family, {len(dense)} scenes (qrtplan plan, median of "
          f"{args.repeats}): dense clouds median "
          f"{statistics.median(float(r['median_ms']) for r in dense):.1f} ms, "
          f"{sum(r['status'] == 'ok' for r in dense)} ok "
          f"({sum(r['found_by'] == 'sampling' for r in dense)} by sampling), "
          f"{sum(r['against_dense_points'] == 'UNSAFE' for r in dense)} unsafe; "
          f"thinned to {THIN} points median "
          f"{statistics.median(float(r['median_ms']) for r in thin):.1f} ms, "
          f"{sum(r['status'] == 'ok' for r in thin)} ok, "
          f"{sum(r['against_dense_points'] == 'UNSAFE' for r in thin)} of them "
          f"colliding with the dense points ({table})")


if __name__ == "__main__":
    main()
