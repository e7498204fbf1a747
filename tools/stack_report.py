#!/usr/bin/env python3
"""Worst-case stack of the public functions, from GCC's call graph.

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

usage: stack_report.py [--limit BYTES] [--markdown] [--public PREFIX ...]
                       DIR_WITH_CI_FILES [DIR ...]
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
# The drive firmware (firmware_sim/drive.c) calls its board's CAN driver
# through struct can_driver (send, receive, now_us), from whichever of its
# functions the compiler leaves them in: those calls leave the graph, and
# count as a leaf of BOARD_FRAME bytes, to be checked on the board as libm
# is. No other unit may call through a pointer to the board.
BOARD = "<board's can_driver>"
BOARD_UNITS = {"drive.c"}
LIBC = {"acos", "asin", "atan2", "cos", "sin", "sincos", "floor", "ceil",
        "fmod", "hypot", "sqrt", "memset", "memcpy"}
LIBC_FRAME = 64
BOARD_FRAME = 64
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


def read_graph(directories):
    frames, quals, calls, defined_as, clashes = {}, {}, {}, {}, []
    unit = {}
    files = []
    for directory in directories:
        found = sorted(glob.glob(os.path.join(directory, "**", "*.ci"),
                                 recursive=True))
        if not found:
            sys.exit(f"stack_report: no .ci files under {directory}")
        files += found
    for path in files:
        with open(path) as f:
            text = f.read()
        for title, label in NODE.findall(text):
            m = FRAME.search(label)
            if m:  # a function defined in this unit
                name = short(title)
                # statics of the same name in two units would merge into
                # one node here, and the worst path could miss one of them
                if defined_as.setdefault(name, title) != title:
                    clashes.append(f"two functions named {name}: "
                                   f"{defined_as[name]} and {title}")
                frames[name] = int(m.group(1))
                quals[name] = m.group(2)
                # drive.c.ci (GCC) or drive.c.obj.ci / drive.c.o.ci
                unit[name] = os.path.basename(path).split(".c")[0] + ".c"
                calls.setdefault(name, set())
        for src, dst in EDGE.findall(text):
            calls.setdefault(short(src), set()).add(short(dst))
    return frames, quals, calls, unit, len(files), clashes


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir", nargs="+")
    ap.add_argument("--limit", type=int, default=0,
                    help="fail if a public function needs more stack")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--public", action="append",
                    help="prefix of the entry points (default qrt_; "
                         "may be given more than once)")
    args = ap.parse_args()
    frames, quals, calls, unit, nfiles, problems = read_graph(args.dir)
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
        if name == BOARD:
            return (BOARD_FRAME, [name + " (assumed)"])
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
                if not targets and unit.get(name) in BOARD_UNITS:
                    targets = [BOARD]
                if not targets:
                    problems.append(f"{name}: indirect call not listed")
            for t in targets:
                d = depth(t)
                if d[0] > best[0]:
                    best = d
        visiting.discard(name)
        worst[name] = (frames[name] + best[0], [name] + best[1])
        return worst[name]

    prefixes = tuple(args.public or ["qrt_"])
    public = sorted(n for n in frames if n.startswith(prefixes))
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
