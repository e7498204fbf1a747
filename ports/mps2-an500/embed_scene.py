#!/usr/bin/env python3
"""Writes a scene (points, start, goal, grid) as a C header, so that the
bare-metal image plans it with no file system: embed_scene.py SCENE.json
GRID_DEG OUT.h. Numbers are written with repr(), which C reads back to the
same doubles."""
import json
import sys

scene_path, grid, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
scene = json.load(open(scene_path))
pts = scene["points"]
with open(out, "w") as f:
    f.write(f"/* generated from {scene_path} by embed_scene.py: do not edit */\n")
    f.write(f"#define SCENE_GRID_DEG {grid!r}\n")
    f.write(f"#define SCENE_N_POINTS {len(pts)}\n")
    for name in ("start", "goal"):
        j = scene[name]["joints_deg"]
        f.write(f"static const double scene_{name}[3] = {{{', '.join(repr(float(v)) for v in j)}}};\n")
    f.write("static const double scene_points[SCENE_N_POINTS][3] = {\n")
    for p in pts:
        f.write("    {" + ", ".join(repr(float(v)) for v in p) + "},\n")
    f.write("};\n")
