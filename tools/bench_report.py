#!/usr/bin/env python3
"""Plots of bench_table5's CSV: speed-up over the paper per Table 5 cell,
and run time against obstacles and points (the paper's Figs 21-22).

    bench_report.py table5.csv OUTDIR"""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(argv):
    if len(argv) != 3 or argv[1].startswith("-"):
        print(__doc__.strip().splitlines()[-1].strip(), file=sys.stderr)
        return 2
    try:
        with open(argv[1]) as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        print(f"bench_report: {argv[1]}: {e.strerror}", file=sys.stderr)
        return 2
    out = Path(argv[2])
    out.mkdir(parents=True, exist_ok=True)
    table = [r for r in rows if r["paper_s"]]
    spheres = sorted({int(r["spheres"]) for r in table})
    points = sorted({int(r["points_per_sphere"]) for r in table})
    ours = np.zeros((len(spheres), len(points)))
    paper = np.zeros_like(ours)
    for r in table:
        i, j = spheres.index(int(r["spheres"])), points.index(int(r["points_per_sphere"]))
        ours[i, j] = float(r["median_ms"]) / 1e3
        paper[i, j] = float(r["paper_s"])

    fig, ax = plt.subplots(figsize=(9, 5.5))
    im = ax.imshow(np.log10(paper / ours), origin="lower", cmap="viridis",
                   aspect="auto")
    for i in range(len(spheres)):
        for j in range(len(points)):
            ax.text(j, i, f"{paper[i, j] / ours[i, j]:,.0f}", ha="center",
                    va="center", fontsize=7, color="w")
    ax.set_xticks(range(len(points)), points)
    ax.set_yticks(range(len(spheres)), spheres)
    ax.set_xlabel("inspection points per sphere")
    ax.set_ylabel("spheres")
    fig.colorbar(im, label="log10 speed-up (paper s / ours s)")
    ax.set_title("Speed-up over the paper's Table 5 (median end-to-end plan)")
    fig.tight_layout()
    fig.savefig(out / "table5_speedup.png", dpi=110)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8))
    for j, k in enumerate(points):
        if k in (16, 100, 1444):
            a1.plot(spheres, paper[:, j], "--o", ms=3, label=f"paper, {k} pts")
            a1.plot(spheres, ours[:, j], "-o", ms=3, label=f"qrtplan, {k} pts")
    a1.set_yscale("log")
    a1.set_xlabel("number of spheres")
    a1.set_ylabel("run time (s)")
    a1.set_title("Run time vs obstacles (paper Fig. 21)")
    a1.legend(fontsize=7)
    for i, n in enumerate(spheres):
        if n in (1, 3, 10):
            many = f"{n} sphere" + ("s" if n > 1 else "")
            a2.plot(points, paper[i], "--o", ms=3, label=f"paper, {many}")
            a2.plot(points, ours[i], "-o", ms=3, label=f"qrtplan, {many}")
    big = [r for r in rows if not r["paper_s"]]
    if big:
        a2.plot([int(r["points_per_sphere"]) for r in big],
                [float(r["median_ms"]) / 1e3 for r in big], "-s", ms=4,
                label="qrtplan, 10 spheres, large clouds")
    a2.set_xscale("log")
    a2.set_yscale("log")
    a2.set_xlabel("inspection points per sphere")
    a2.set_ylabel("run time (s)")
    a2.set_title("Run time vs points per obstacle (paper Fig. 22)")
    a2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "scaling.png", dpi=110)
    plt.close(fig)
    # the paper's C-space figures: T-space vs C-space points (Fig. 23), free
    # nodes vs obstacles (Fig. 24), search time vs nodes (Figs. 25-26)
    total_nodes = 72 * 45 * 65  # the 5 degree lattice
    grid = [r for r in rows if r["paper_s"]]
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    for k in (16, 100, 361, 1444):
        sel = [r for r in grid if int(r["points_per_sphere"]) == k]
        if not sel:
            continue
        pts = [int(r["points"]) for r in sel]
        blocked = [int(r["cells_blocked"]) for r in sel]
        ax[0].plot(pts, blocked, "-o", ms=3, label=f"{k} pts/sphere")
        ax[1].plot([int(r["spheres"]) for r in sel],
                   [total_nodes - b for b in blocked], "-o", ms=3,
                   label=f"{k} pts/sphere")
    ax[0].set_xscale("log")
    ax[0].set_xlabel("T-space inspection points")
    ax[0].set_ylabel("C-space blocked nodes (of 210,600)")
    ax[0].set_title("T-space vs C-space points (paper Fig. 23)")
    ax[1].set_xlabel("number of spheres")
    ax[1].set_ylabel("free lattice nodes")
    ax[1].set_title("Free nodes vs obstacles (paper Fig. 24)")
    dots = ax[2].scatter([int(r["nodes_expanded"]) for r in grid],
                         [float(r["search_ms"]) for r in grid], s=10,
                         c=[int(r["spheres"]) for r in grid], cmap="viridis")
    fig.colorbar(dots, ax=ax[2], label="spheres")
    ax[2].set_xlabel("nodes expanded by the search")
    ax[2].set_ylabel("search + shortcut time (ms)")
    ax[2].set_title("Search time vs nodes (paper Figs. 25-26)")
    for a in ax[:2]:
        a.legend(fontsize=7)
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "scaling_cspace.png", dpi=110)
    plt.close(fig)
    print(f"plots: {out / 'table5_speedup.png'}, {out / 'scaling.png'}, "
          f"{out / 'scaling_cspace.png'}")


if __name__ == "__main__":
    sys.exit(main(sys.argv))
