#!/usr/bin/env bash
# `make bench`: the paper's Table 5 grid and larger clouds timed end to end
# (build/bench/table5.csv, plots), and the instruction count of one plan of
# the largest Table 5 cell under callgrind, a figure that does not depend on
# how busy the machine is.
set -euo pipefail
cd "$(dirname "$0")/.."
out=build/bench
mkdir -p "$out"
build/bin/bench_table5 --repeats "${QRT_BENCH_REPEATS:-15}" --csv "$out/table5.csv" |
    tee "$out/table5.txt"
.venv/bin/python tools/bench_report.py "$out/table5.csv" "$out"
if command -v valgrind >/dev/null; then
    # count only the end-to-end plan, not building the points; the clock
    # reads inside it are a few hundred instructions
    count() { # function to toggle on -> instructions inside it
        valgrind --tool=callgrind --callgrind-out-file="$out/callgrind.$1.out" \
            --collect-atstart=no --toggle-collect="$1" \
            build/bin/bench_table5 --single 10 1444 --repeats 1 >/dev/null 2>&1
        callgrind_annotate "$out/callgrind.$1.out" 2>/dev/null |
            awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1}'
    }
    total=$(count plan_end_to_end)
    whole=$(count plan_whole_mask)
    echo "callgrind, 10 spheres x 1444 points, one end-to-end plan (init," \
        "points, plan asking the nodes it reads): $total instructions;" \
        "with the whole mask first: $whole" | tee -a "$out/table5.txt"
fi

# qrtpland: scan-to-plan latency over LCM (issue 4), 10 x 1444 at 20 Hz
if [ -x build/bin/qrtpland ]; then
    .venv/bin/python tools/bench_daemon.py --scans "${QRT_BENCH_DAEMON_SCANS:-1000}" \
        --out "$out" | tee -a "$out/table5.txt"
fi

# the dense confined family beside the same scenes thinned to 10^4 points:
# time, path length, and the thinned paths checked against the dense points
.venv/bin/python tools/bench_dense.py --out "$out" | tail -1 | tee -a "$out/table5.txt"

# the Python package's overhead over its C call (issue 38), 10 x 1444
.venv/bin/python tools/bench_python.py --out "$out" | tee -a "$out/table5.txt"

# what authenticated LCM costs (issue 35): keyed and unkeyed daemons in turn
if [ -x build/bin/qrtpland ]; then
    .venv/bin/python tools/bench_auth.py --pairs "${QRT_BENCH_AUTH_PAIRS:-300}" \
        --out "$out" | tee -a "$out/table5.txt"
fi

# scan that blocks the executing path -> quick-stop frame on the bus, in the
# SocketCAN VM (issue 5); skipped with a message where there is no vcan
if [ -x build/bin/qrtpland ] && [ -x build/bin/servo_sim ]; then
    tools/vm/run.sh -- .venv/bin/python tests/canlink/test_daemon_can_vm.py \
        --daemon build/bin/qrtpland --servo-sim build/bin/servo_sim \
        --dbc can/qrtplan.dbc --lcmtypes build/lcmtypes/python \
        --trials "${QRT_BENCH_STOP_TRIALS:-200}" --out "$out/stop_latency" |
        grep -E "quick-stop frame|failures" | tee -a "$out/table5.txt" || true
fi

# what stops the arm when the daemon dies (SIGKILL: the drives' heartbeat
# consumers) or a required sensor goes silent (the guard's evidence timer),
# in the SocketCAN VM: tests/canlink/test_failsafe_vm.py measuring, N trials
# each; skipped with a message where there is no vcan
if [ -x build/bin/qrtpland ] && [ -x build/bin/servo_sim ]; then
    for scenario in kill sensor_silent; do
        rc=0
        tools/vm/run.sh -- .venv/bin/python tests/canlink/test_failsafe_vm.py \
            --scenario "$scenario" --trials "${QRT_BENCH_FAILSAFE_TRIALS:-5}" \
            --daemon build/bin/qrtpland --servo-sim build/bin/servo_sim \
            --lcmtypes build/lcmtypes/python --out "$out/failsafe" \
            >"$out/failsafe_$scenario.log" 2>&1 || rc=$?
        if [ "$rc" -eq 77 ]; then
            echo "failsafe: $scenario skipped: no vcan0 on this host and no" \
                "VM to make one (tools/vm/run.sh)" | tee -a "$out/table5.txt"
        elif ! grep -E "^failsafe: " "$out/failsafe_$scenario.log" |
            tee -a "$out/table5.txt"; then
            echo "failsafe: $scenario measured nothing (exit $rc; see" \
                "$out/failsafe_$scenario.log)" | tee -a "$out/table5.txt"
        fi
    done
fi

# qrtplan against OMPL (issue 6): the same scenes, interleaved, oracle-checked;
# in turn (each planner after the others), replanning (each planner after its
# own plan of the scan before), and cold (each planner after the caches are
# evicted)
if [ -x build/bin/bench_ompl ]; then
    for regime in "" replanning cold; do
        .venv/bin/python tools/bench_compare.py --repeats "${QRT_BENCH_OMPL_REPEATS:-15}" \
            ${regime:+--$regime} --out "$out" |
            tee "$out/ompl_summary${regime:+_$regime}.txt"
    done
fi
