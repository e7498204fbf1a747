#!/usr/bin/env python3
"""Worst-case stack of the core's public functions, from GCC's call graph.

Reads the .ci files that `gcc -fcallgraph-info=su` writes beside each object
(every function's frame size and whom it calls), and prints, for every public
entry point (qrt_*), the deepest call chain and its total stack in bytes.

Fails (exit 1) when the core
  - recurses (a cycle in the call graph: the stack would have no bound),
  - has a frame of unbounded dynamic size (a VLA or alloca),
  - calls through a function pointer that is not listed in INDIRECT below,
  - or needs more than --limit bytes on its worst path.

Calls to libm, memset and libgcc's helpers are leaves of unknown depth in a hosted libc; the
report counts them as LIBC_FRAME bytes each, a figure to check on the
target's own libm.

usage: stack_report.py [--limit BYTES] [--markdown] DIR_WITH_CI_FILES
"""
import argparse
import glob
import os
import re
import sys

# The only function pointer in the core: qrt_cluster_points calls back its
# caller's visitor, which in the planner is raster_cluster.
INDIRECT = {"qrt_cluster_points": ["raster_cluster", "keep_cluster"],
            "walk": ["node_blocked"]}
LIBC = {"acos", "asin", "atan2", "cos", "sin", "sincos", "floor", "ceil",
        "fmod", "hypot", "sqrt", "memset", "memcpy"}
LIBC_FRAME = 64
# the compiler's arithmetic helpers (__aeabi_idiv on 32-bit ARM, __divdi3...)
RUNTIME = re.compile(r"^__(aeabi_[a-z0-9_]+|[a-z]+[0-9])$")

NODE = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
EDGE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
FRAME = re.compile(r"\\n(\d+) bytes \(([a-z,]+)\)")


def short(title):
    return title.rsplit(":", 1)[-1]


def base(name):
    """A function's source name: GCC's clones (walk.constprop.0,
    raster.isra.0, link2_rows.part.0) are the function they were made of."""
    return name.split(".", 1)[0]


def read_graph(directory):
    frames, quals, calls = {}, {}, {}
    files = sorted(glob.glob(os.path.join(directory, "**", "*.ci"),
                         recursive=True))
    if not files:
        sys.exit(f"stack_report: no .ci files under {directory}")
    for path in files:
        with open(path) as f:
            text = f.read()
        for title, label in NODE.findall(text):
            m = FRAME.search(label)
            if m:  # a function defined in this unit
                name = short(title)
                frames[name] = int(m.group(1))
                quals[name] = m.group(2)
                calls.setdefault(name, set())
        for src, dst in EDGE.findall(text):
            calls.setdefault(short(src), set()).add(short(dst))
    return frames, quals, calls, len(files)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--limit", type=int, default=0,
                    help="fail if a public function needs more stack")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    frames, quals, calls, nfiles = read_graph(args.dir)
    problems = []
    for name, q in quals.items():
        if "dynamic" in q and "bounded" not in q:
            problems.append(f"{name}: unbounded dynamic stack ({q})")

    worst = {}  # name -> (bytes, chain)
    visiting = set()

    def depth(name):
        if name in worst:
            return worst[name]
        if name in visiting:
            problems.append(f"recursion through {name}")
            return (0, [name])
        if name not in frames:
            if name == "__indirect_call":
                problems.append("indirect call not listed in INDIRECT")
                return (0, [name])
            if name.lstrip("_").replace("builtin_", "") in LIBC:
                return (LIBC_FRAME, [name + " (libc, assumed)"])
            if RUNTIME.match(name):
                return (LIBC_FRAME, [name + " (libgcc, assumed)"])
            problems.append(f"call to unknown function {name}")
            return (0, [name])
        visiting.add(name)
        best = (0, [])
        for callee in sorted(calls.get(name, ())):
            targets = [callee]
            if callee == "__indirect_call":
                # a listed target, or every clone GCC made of it
                targets = [c for t in INDIRECT.get(base(name), [])
                           for c in (sorted(f for f in frames
                                            if base(f) == t) or [t])]
                if not targets:
                    problems.append(f"{name}: indirect call not listed")
            for t in targets:
                d = depth(t)
                if d[0] > best[0]:
                    best = d
        visiting.discard(name)
        worst[name] = (frames[name] + best[0], [name] + best[1])
        return worst[name]

    public = sorted(n for n in frames if n.startswith("qrt_"))
    rows = [(n, *depth(n)) for n in public]
    total = max(r[1] for r in rows)
    if args.markdown:
        print("| entry point | worst stack (B) | deepest chain |")
        print("|---|---:|---|")
        for n, b, chain in sorted(rows, key=lambda r: -r[1]):
            if n.startswith("qrt_planner_"):
                print(f"| `{n}` | {b} | {' → '.join(chain[1:])} |")
    else:
        print(f"{len(frames)} functions in {nfiles} units; worst stack of "
              f"each public function (libm/memset counted as {LIBC_FRAME} B):")
        for n, b, chain in sorted(rows, key=lambda r: -r[1]):
            print(f"  {b:6d} B  {n}: {' -> '.join(chain)}")
        print(f"worst path: {total} bytes")
    if args.limit and total > args.limit:
        problems.append(f"worst path {total} B exceeds the limit "
                        f"{args.limit} B")
    for p in sorted(set(problems)):
        print("FAIL:", p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
