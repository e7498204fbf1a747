#!/usr/bin/env python3
"""The benchmark tables of docs/benchmarks.md from several runs: Table 5 and the OMPL race.

One run of either benchmark moves with the machine's load (Table 5's cells by
10-30 %, RRTConnect's medians by up to 1.5x), so docs/benchmarks.md quotes several
runs, alternated: for each run, build/bin/bench_table5, then
tools/bench_compare.py in turn, with --replanning and with --cold. Then it
prints (and writes to OUT/summary.md) the tables as docs/benchmarks.md gives them:

* Table 5: each cell's median over the runs of its median time, and the
  speed-up over the paper's seconds;
* OMPL: for each family and regime, the median over the runs of qrtplan's and
  RRTConnect's family medians, and qrtplan's lead as the lowest to highest
  run (in turn and replanning in one table, cold in a second); PRM's range;
  the median path lengths (in turn); whether every path of every planner
  passed the oracle; and the scenes where RRTConnect was ahead
  or level (qrtplan less than 1.2x ahead) in any run.

    .venv/bin/python tools/bench_runs.py [--runs 3] [--repeats 15] [--seeds 3]
    .venv/bin/python tools/bench_runs.py --summarise-only   # the runs in OUT

About 4–5 minutes a run on the project's machines.
"""
import argparse
import csv
import math
import os
import statistics
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REGIMES = [("turn", ""), ("replan", "_replanning"), ("cold", "_cold")]
MAIN_TABLE = ("turn", "replan")  # the cold regime has a table of its own
REGIME_FLAGS = {"turn": [], "replan": ["--replanning"], "cold": ["--cold"]}
LARGEST = "**10 × 1,444** (largest cell)"  # the paper's largest cell, in bold
TABLE5_ROWS = [(1, 16, "1 × 16"), (1, 1444, "1 × 1,444 (Table 4 scene)"),
               (3, 1444, "3 × 1,444"), (10, 100, "10 × 100"),
               (10, 1444, LARGEST),
               (10, 10000, "10 × 10⁴"), (10, 100000, "10 × 10⁵"),
               (10, 1000000, "10 × 10⁶ (10 million points)")]
LEVEL = 1.2  # a scene where qrtplan is less than this far ahead is listed


def run_logged(name, args, log_path):
    """Run args with its output in log_path; stop, naming the log, if it fails."""
    with open(log_path, "w") as log:
        try:
            rc = subprocess.run(args, stdout=log, stderr=log).returncode
        except OSError as e:
            sys.exit(f"bench_runs: cannot run {name}: {e} (run `make` first)")
    if rc != 0:
        sys.exit(f"bench_runs: {name} failed (exit {rc}); its output: {log_path}")


def run_all(out, runs, repeats, seeds):
    for i in range(1, runs + 1):
        print(f"run {i} of {runs}: Table 5", file=sys.stderr)
        args = [os.path.join(REPO, "build", "bin", "bench_table5"), "--repeats",
                str(repeats), "--csv", os.path.join(out, f"table5_{i}.csv")]
        run_logged("bench_table5", args, os.path.join(out, f"table5_{i}.txt"))
        for regime, _ in REGIMES:
            print(f"run {i} of {runs}: OMPL, {regime}", file=sys.stderr)
            args = [sys.executable, os.path.join(REPO, "tools", "bench_compare.py"),
                    "--repeats", str(repeats), "--seeds", str(seeds),
                    "--out", os.path.join(out, f"{regime}_{i}")]
            args += REGIME_FLAGS[regime]
            run_logged("bench_compare.py", args, os.path.join(out, f"{regime}_{i}.log"))


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def run_numbers(out, stem, ext=""):
    """The run numbers i for which OUT/<stem>_<i><ext> exists, in order."""
    found = []
    for name in os.listdir(out):
        if ext and not name.endswith(ext):
            continue
        head, _, tail = name[:len(name) - len(ext)].rpartition("_")
        if head == stem and tail.isdigit():
            found.append(int(tail))
    return sorted(found)


def table5_summary(csv_paths):
    """[(label, paper_s or None, [ms per run], median ms, speed-up or None)],
    for the cells of TABLE5_ROWS that the runs have."""
    runs = [read_csv(p) for p in csv_paths]
    rows = []
    for spheres, points, label in TABLE5_ROWS:
        ms, paper = [], None
        for run in runs:
            for r in run:
                if (int(r["spheres"]), int(r["points_per_sphere"])) == (spheres, points):
                    ms.append(float(r["median_ms"]))
                    paper = float(r["paper_s"]) if r["paper_s"] else None
        if not ms:
            continue
        med = statistics.median(ms)
        rows.append((label, paper, ms, med, paper * 1e3 / med if paper else None))
    return rows


def ompl_summary(out, run_ids):
    """Per family, per regime: medians over the runs and the leads' range."""
    fams = {}
    for regime, suffix in REGIMES:
        for i in run_ids[regime]:
            rows = read_csv(os.path.join(out, f"{regime}_{i}", f"ompl_summary{suffix}.csv"))
            by = {}
            for r in rows:
                by.setdefault(r["family"], {})[r["planner"]] = r
            for fam, planners in by.items():
                f = fams.setdefault(fam, {"all_pass": True, "lost": []})
                for name, r in planners.items():
                    if float(r["oracle_pass_rate"]) < 1.0:
                        f["all_pass"] = False
                    if float(r["success_rate"]) < 1.0:
                        f["lost"].append((regime, i, name, float(r["success_rate"])))
                q = float(planners["qrtplan"]["median_ms"])
                c = float(planners["RRTConnect"]["median_ms"])
                f.setdefault(regime, {"q": [], "c": [], "lead": [], "prm": [],
                                      "len": {}})
                g = f[regime]
                g["q"].append(q)
                g["c"].append(c)
                g["lead"].append(c / q)
                if "PRM" in planners:
                    g["prm"].append(float(planners["PRM"]["median_ms"]))
                for name, r in planners.items():
                    g["len"].setdefault(name, []).append(float(r["median_length_deg"]))
    return fams


def scene_exceptions(out, run_ids):
    """Scenes where, in some run, qrtplan was less than LEVEL ahead."""
    per = {}
    for regime, suffix in REGIMES:
        for i in run_ids[regime]:
            for r in read_csv(os.path.join(out, f"{regime}_{i}", f"ompl_per_scene{suffix}.csv")):
                per.setdefault(r["scene"], {}).setdefault(regime, []).append(
                    (float(r["qrtplan_median_ms"]), float(r["rrtconnect_median_ms"])))
    return {s: v for s, v in per.items()
            if any(not c / q >= LEVEL for runs in v.values() for q, c in runs)}


def finite(values):
    """A run where a planner found no path has NaN medians: left out of the
    figures, and named in the table's line on lost runs instead."""
    return [x for x in values if math.isfinite(x)]


def span(values, fmt, unit=""):
    """Lowest to highest of the finite values, with unit; "–" if none is."""
    values = finite(values)
    if not values:
        return "–"
    lo, hi = fmt.format(min(values)), fmt.format(max(values))
    return (lo if lo == hi else lo + "–" + hi) + unit


def median(values):
    values = finite(values)
    return statistics.median(values) if values else math.nan


def ms(x):
    return f"{x:.3g} ms" if math.isfinite(x) else "–"


def bold(text, on=True):
    return f"**{text}**" if on else text


def race_cells(f, regimes):
    """A family's qrtplan median, RRTConnect median and lead range for each
    regime, the lead in bold where every run reached the 10x target."""
    cells = []
    for regime in regimes:
        g = f.get(regime)
        if g is None:
            cells += ["–", "–", "–"]
            continue
        leads = finite(g["lead"])
        cells += [bold(ms(median(g["q"]))), ms(median(g["c"])),
                  bold(span(leads, "{:.1f}", "×"), bool(leads) and min(leads) >= 10)]
    return cells


def render(t5, fams, exceptions):
    lines = []
    if t5:
        lines += ["| spheres × points/sphere | paper | qrtplan | speed-up |",
                  "| --- | --- | --- | --- |"]
        for label, paper, _, med, speedup in t5:
            largest = label == LARGEST
            lines.append(f"| {label} | {f'{paper:.3f} s' if paper else '–'} | "
                         f"{bold(ms(med), largest)} | "
                         f"{bold(f'{speedup:,.0f}×', largest) if speedup else '–'} |")
        largest = [row for row in t5 if row[0] == LARGEST]
        if largest:
            runs = ", ".join(f"{x:.2f}" for x in largest[0][2])
            lines += ["", f"10 × 1,444 in each run: {runs} ms."]
        lines.append("")
    if fams:
        lines += ["| family | qrtplan, in turn | RRTConnect, in turn | lead | "
                  "qrtplan, replanning | RRTConnect, replanning | lead | PRM, in turn | "
                  "path: qrtplan / RRTConnect / RRT\\* (1 s) | oracle |",
                  "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- |"]
        for fam, f in fams.items():
            cells = [fam] + race_cells(f, MAIN_TABLE)
            turn = f.get("turn") or f.get("replan") or f.get("cold")
            cells.append(span(turn["prm"], "{:.3g}", " ms"))
            cells.append(" / ".join(
                f"{median(turn['len'][n]):.0f}°" if finite(turn["len"].get(n, [])) else "–"
                for n in ("qrtplan", "RRTConnect", "RRTstar")))
            cells.append("all pass" if f["all_pass"] else "**not all pass**")
            lines.append("| " + " | ".join(cells) + " |")
        if any("cold" in f for f in fams.values()):
            lines += ["", "| family | qrtplan, cold | RRTConnect, cold | lead |",
                      "| --- | ---: | ---: | ---: |"]
            for fam, f in fams.items():
                lines.append("| " + " | ".join([fam] + race_cells(f, ("cold",))) + " |")
        lost = [f"{fam}: {name} {rate:.0%} in {regime} run {i}"
                for fam, f in fams.items() for regime, i, name, rate in f["lost"]]
        lines += ["", "Runs where a planner did not always find a path: " +
                  ("; ".join(lost) if lost else "none") + "."]
    if exceptions:
        lines += ["", f"Scenes where qrtplan was less than {LEVEL}× ahead in some run "
                  "(RRTConnect / qrtplan, lowest to highest run):"]
        for scene, v in exceptions.items():
            parts = []
            for regime, _ in REGIMES:
                if regime not in v:
                    continue
                leads = [c / q for q, c in v[regime]]
                lost = len(leads) - len(finite(leads))
                parts.append(f"{regime} " + span(leads, "{:.2f}", "×") +
                             (f" (no path in {lost} run{'s' if lost > 1 else ''})"
                              if lost else ""))
            lines.append(f"* `{scene}`: " + ", ".join(parts))
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench", "runs"))
    ap.add_argument("--summarise-only", action="store_true",
                    help="only summarise the runs already in --out")
    a = ap.parse_args()
    if a.runs < 1:
        ap.error("--runs must be at least 1")
    os.makedirs(a.out, exist_ok=True)
    if not a.summarise_only:
        run_all(a.out, a.runs, a.repeats, a.seeds)
    t5 = table5_summary([os.path.join(a.out, f"table5_{i}.csv")
                         for i in run_numbers(a.out, "table5", ".csv")])
    ids = {regime: run_numbers(a.out, regime) for regime, _ in REGIMES}
    fams = ompl_summary(a.out, ids)
    if not t5 and not fams:
        sys.exit(f"bench_runs: no runs found in {a.out}")
    text = render(t5, fams, scene_exceptions(a.out, ids))
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write(text)
    sys.stdout.write(text)


if __name__ == "__main__":
    main()
