"""On small lattices the planner's lattice cost equals networkx's shortest
path on the same free lattice (built from `qrtplan mask`), for A* and for
plain Dijkstra."""
import itertools
import json
import math

import networkx as nx
import numpy as np
import pytest

import scenes
from conftest import run_cli


def lattice_graph(mask):
    na, ns, ne = mask["n"]
    blocked = set(mask["blocked"])
    g = nx.Graph()
    steps = [d for d in itertools.product((-1, 0, 1), repeat=3) if any(d)]
    for a, s, e in itertools.product(range(na), range(ns), range(ne)):
        i = (a * ns + s) * ne + e
        if i in blocked:
            continue
        g.add_node(i)
        for da, ds, de in steps:
            a2, s2, e2 = a + da, s + ds, e + de
            if mask["alpha_wraps"]:
                a2 %= na
            if not (0 <= a2 < na and 0 <= s2 < ns and 0 <= e2 < ne):
                continue
            j = (a2 * ns + s2) * ne + e2
            if j in blocked:
                continue
            w = mask["grid_deg"] * math.sqrt(abs(da) + abs(ds) + abs(de))
            g.add_edge(i, j, weight=w)
    return g


def node_joints(mask, i):
    na, ns, ne = mask["n"]
    a, rest = divmod(i, ns * ne)
    s, e = divmod(rest, ne)
    return [mask["lo_deg"][k] + v * mask["grid_deg"] for k, v in enumerate((a, s, e))]


@pytest.mark.parametrize("grid,seed", [(20, 1), (20, 2), (20, 3), (10, 4),
                                       (10, 5), (20, 6), (10, 7), (20, 8)])
def test_lattice_cost_matches_networkx(qrtplan, tmp_path, grid, seed):
    rng = np.random.default_rng(seed)
    scene = scenes.make_scene(["spheres", "boxes", "walls", "shelf"][seed % 4], seed)
    scene["grid_deg"] = grid
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    r = run_cli(["mask", path])
    assert r.returncode == 0, r.stderr
    mask = json.loads(r.stdout)
    assert mask["cells_blocked"] == len(mask["blocked"]) > 0
    graph = lattice_graph(mask)
    free = sorted(graph.nodes)
    compared = 0
    for _ in range(4):
        s, g = (int(x) for x in rng.choice(free, 2, replace=False))
        scene["start"] = {"joints_deg": node_joints(mask, s)}
        scene["goal"] = {"joints_deg": node_joints(mask, g)}
        path.write_text(json.dumps(scene))
        try:
            expect = nx.dijkstra_path_length(graph, s, g)
        except nx.NetworkXNoPath:
            expect = None
        for flags in (["--no-simplify"], ["--no-simplify", "--dijkstra"], []):
            r = run_cli(["plan", path, *flags])
            assert r.returncode == 0, r.stderr
            plan = json.loads(r.stdout)
            if expect is None:
                assert plan["status"] == "no_path", plan["status"]
                continue
            assert plan["status"] == "ok", plan
            if flags:
                assert plan["stats"]["lattice_cost_deg"] == pytest.approx(expect, abs=1e-3)
                assert plan["cost_deg"] == pytest.approx(expect, abs=1e-3)
            else:  # shortcuts (or the straight motion) only ever shorten it
                assert plan["cost_deg"] <= expect + 1e-6
        compared += 1
    assert compared == 4
