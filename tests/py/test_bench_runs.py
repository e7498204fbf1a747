"""tools/bench_runs.py summarises runs into docs/benchmarks.md's tables: its medians,
ranges, oracle verdict and scene list must be the runs' own, on made-up runs
whose answers are known."""
import csv
import math
import subprocess
import sys

import pytest

import bench_runs

SUMMARY = ["family", "planner", "runs", "success_rate", "median_ms",
           "median_length_deg", "oracle_pass_rate"]
PER_SCENE = ["family", "scene", "qrtplan_median_ms", "rrtconnect_median_ms",
             "speedup", "qrtplan_length_deg", "rrtconnect_length_deg"]
TABLE5 = ["spheres", "points_per_sphere", "points", "status", "median_ms", "min_ms",
          "whole_mask_median_ms", "convert_ms", "search_ms", "cells_blocked",
          "nodes_expanded", "paper_s", "speedup"]


def write(path, header, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def make_runs(tmp_path, oracle_fail_in=None, qrtplan_lost_in=None):
    """Three runs a regime. qrtplan's box median is 2, 3 and 5 ms in turn
    against RRTConnect's 8, 9 and 16 (a mean would not be the median), half
    that replanning; cold, qrtplan's is twice and RRTConnect's four times
    the figure in turn. box_1 is level in run 2 only."""
    for regime, suffix, scale, rrt_scale in (("turn", "", 1.0, 1.0),
                                             ("replan", "_replanning", 0.5, 0.5),
                                             ("cold", "_cold", 2.0, 4.0)):
        for i, (q, c) in enumerate(((2.0, 8.0), (3.0, 9.0), (5.0, 16.0)), start=1):
            c *= rrt_scale / scale
            d = tmp_path / f"{regime}_{i}"
            oracle = 0.9 if (regime, i) == oracle_fail_in else 1.0
            if (regime, i) == qrtplan_lost_in:  # what bench_compare writes then
                q, ok, rate, length = math.nan, 0.0, math.nan, math.nan
            else:
                ok, rate, length = 1.0, 1.0, 333.0
            write(d / f"ompl_summary{suffix}.csv", SUMMARY, [
                ["confined box", "qrtplan", 45, ok, q * scale, length, rate],
                ["confined box", "RRTConnect", 45, 1.0, c * scale, 500.0 + i, oracle],
                ["confined box", "PRM", 45, 1.0, 100.0 * i, 400.0, 1.0],
                ["confined box", "RRTstar", 3, 1.0 if i != 3 else 2 / 3, 1000.0, 340.0, 1.0],
            ])
            write(d / f"ompl_per_scene{suffix}.csv", PER_SCENE, [
                ["confined box", "box_4", q * scale, c * scale, c / q, 333.0, 500.0],
                ["confined box", "box_1", 10.0, 10.5 if i == 2 else 30.0, 0, 400.0, 600.0],
            ])
    for i, ms in enumerate((0.9, 0.8, 1.3), start=1):
        write(tmp_path / f"table5_{i}.csv", TABLE5, [
            [1, 16, 16, "ok", 0.01 * i, 0, 0, 0, 0, 0, 0, 0.563, 0],
            [10, 1444, 14440, "ok", ms, 0, 0, 0, 0, 0, 0, 126.5, 0],
            [10, 10000, 100000, "ok", 4.0 + i, 0, 0, 0, 0, 0, 0, "", 0],
        ])
        (tmp_path / f"table5_{i}.txt").write_text("not a csv\n")
    (tmp_path / "turn_1.log").write_text("a log, not a run\n")


def ids(tmp_path):
    return {r: bench_runs.run_numbers(tmp_path, r) for r, _ in bench_runs.REGIMES}


def test_runs_are_found_by_number_only(tmp_path):
    make_runs(tmp_path)
    assert ids(tmp_path) == {"turn": [1, 2, 3], "replan": [1, 2, 3], "cold": [1, 2, 3]}
    assert bench_runs.run_numbers(tmp_path, "table5", ".csv") == [1, 2, 3]


def test_family_medians_and_lead_ranges(tmp_path):
    make_runs(tmp_path)
    box = bench_runs.ompl_summary(tmp_path, ids(tmp_path))["confined box"]
    assert box["turn"]["q"] == [2.0, 3.0, 5.0]
    assert box["turn"]["lead"] == [4.0, 3.0, 3.2]
    assert box["replan"]["c"] == [4.0, 4.5, 8.0]
    assert box["all_pass"]
    assert box["cold"]["q"] == [4.0, 6.0, 10.0]
    assert box["cold"]["lead"] == [8.0, 6.0, 6.4]
    assert box["lost"] == [("turn", 3, "RRTstar", 2 / 3), ("replan", 3, "RRTstar", 2 / 3),
                           ("cold", 3, "RRTstar", 2 / 3)]
    table = bench_runs.render([], {"confined box": box}, {})
    row = next(line for line in table.splitlines() if line.startswith("| confined box"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1:8] == ["**3 ms**", "9 ms", "3.0–4.0×", "**1.5 ms**", "4.5 ms",
                          "3.0–4.0×", "100–300 ms"]
    assert cells[8] == "333° / 502° / 340°"
    assert cells[9] == "all pass"
    assert "RRTstar 67% in turn run 3" in table
    # the cold regime in a table of its own, under the first
    cold = next(line for line in table.splitlines()
                if line.startswith("| confined box") and line != row)
    assert table.index("| family | qrtplan, cold |") < table.index(cold)
    assert [c.strip() for c in cold.strip("|").split("|")] == [
        "confined box", "**6 ms**", "36 ms", "6.0–8.0×"]


def test_an_oracle_failure_in_any_run_shows(tmp_path):
    make_runs(tmp_path, oracle_fail_in=("replan", 2))
    fams = bench_runs.ompl_summary(tmp_path, ids(tmp_path))
    assert not fams["confined box"]["all_pass"]
    assert "**not all pass**" in bench_runs.render([], fams, {})


def test_level_scenes_are_listed_and_clear_ones_are_not(tmp_path):
    make_runs(tmp_path)
    level = bench_runs.scene_exceptions(tmp_path, ids(tmp_path))
    assert list(level) == ["box_1"]
    text = bench_runs.render([], {}, level)
    assert "`box_1`: turn 1.05–3.00×, replan 1.05–3.00×, cold 1.05–3.00×" in text


def test_table5_medians_and_speed_up(tmp_path):
    make_runs(tmp_path)
    rows = bench_runs.table5_summary(
        [tmp_path / f"table5_{i}.csv" for i in (1, 2, 3)])
    by_label = {r[0]: r for r in rows}
    largest = by_label["**10 × 1,444** (largest cell)"]
    assert largest[2] == [0.9, 0.8, 1.3] and largest[3] == 0.9
    assert round(largest[4]) == 140556  # 126.5 s / 0.9 ms
    assert by_label["10 × 10⁴"][1] is None and by_label["10 × 10⁴"][3] == 6.0
    assert "3 × 1,444" not in by_label  # not in the runs: left out, not invented
    text = bench_runs.render(rows, {}, {})
    assert "| **10 × 1,444** (largest cell) | 126.500 s | **0.9 ms** | **140,556×** |" in text
    assert "10 × 1,444 in each run: 0.90, 0.80, 1.30 ms." in text


def test_summarise_only_on_an_empty_directory_fails_clearly(tmp_path):
    r = subprocess.run([sys.executable, bench_runs.__file__, "--summarise-only",
                        "--out", str(tmp_path)], capture_output=True, text=True)
    assert r.returncode != 0 and "no runs found" in r.stderr


def test_a_run_without_a_path_is_named_not_averaged(tmp_path):
    make_runs(tmp_path, qrtplan_lost_in=("turn", 2))
    fams = bench_runs.ompl_summary(tmp_path, ids(tmp_path))
    box = fams["confined box"]
    assert ("turn", 2, "qrtplan", 0.0) in box["lost"]
    table = bench_runs.render([], fams, bench_runs.scene_exceptions(tmp_path, ids(tmp_path)))
    row = next(line for line in table.splitlines() if line.startswith("| confined box"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1:4] == ["**3.5 ms**", "9 ms", "3.2–4.0×"]  # runs 1 and 3
    assert cells[8] == "333° / 502° / 340°"
    assert "qrtplan 0% in turn run 2" in table
    assert "`box_4`: turn 3.20–4.00× (no path in 1 run), replan 3.00–4.00×" in table


def test_a_failing_benchmark_stops_the_runs_and_names_its_log(tmp_path):
    log = tmp_path / "x.log"
    with pytest.raises(SystemExit) as e:
        bench_runs.run_logged("x", [sys.executable, "-c", "import sys; sys.exit(3)"], log)
    assert str(e.value) == f"bench_runs: x failed (exit 3); its output: {log}"
    with pytest.raises(SystemExit) as e:
        bench_runs.run_logged("y", [str(tmp_path / "no-such-binary")], log)
    assert "cannot run y" in str(e.value) and "run `make` first" in str(e.value)


def test_each_regime_runs_with_its_own_flag(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(bench_runs, "run_logged", lambda name, args, log: calls.append(args))
    bench_runs.run_all(str(tmp_path), 1, 2, 1)
    compare = [a for a in calls if a[1].endswith("bench_compare.py")]
    flags = {a[a.index("--out") + 1].rsplit("/", 1)[1]:
             [x for x in a if x in ("--replanning", "--cold")] for a in compare}
    assert flags == {"turn_1": [], "replan_1": ["--replanning"], "cold_1": ["--cold"]}
    assert calls[0][0].endswith("bench_table5") and len(calls) == 4
