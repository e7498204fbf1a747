#!/usr/bin/env bash
# Builds the bare-metal Cortex-M7 images (ports/mps2-an500) for both
# profiles, runs them on `qemu-system-arm -M mps2-an500` with semihosting,
# and checks that
#   - every core unit test passes on the board (paper profile),
#   - the Table 4 plan on the board equals the host's plan of the same
#     profile bit for bit (status, blocked cells, expansions and every
#     waypoint; the cost to the 1e-6 degree the host's JSON gives), for the
#     paper (5 deg) and the small (10 deg) profile;
#     the small image links into 512 KiB of RAM with its stack, or fails;
#   - the servo side's unit tests (the CANopen codec, the drive firmware
#     and the CiA 402 master driving three drives on a bus in memory) pass
#     on the board and print what the host's print, figure for figure.
# Usage: ports/mps2-an500/run.sh [HOST_QRTPLAN]   (default build/bin/qrtplan)
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
cd "$repo"
host=${1:-build/bin/qrtplan}
out=build-mps2
gen=$(command -v ninja >/dev/null && echo "-G Ninja" || true)
qemu=qemu-system-arm
failed=0
mkdir -p "$out"
command -v "$qemu" >/dev/null || { echo "mps2: $qemu not installed"; exit 1; }

# test_raster, the longest image, took 344 s under qemu's emulation in CI on
# this project's 2-core machines: the limit leaves a loaded CI host 4x that
run_image() { # elf log -> exit status of the program
    timeout "${QRT_MPS2_TIMEOUT:-1400}" "$qemu" -M mps2-an500 -nographic \
        -monitor none -serial none \
        -semihosting-config enable=on,target=native -kernel "$1" >"$2" 2>&1
}

# The servo side's tests run whole on the board, so they must print what
# the host's print (the master's measured distances and speeds included);
# the core's run a twentieth of their cases there and are not compared.
same_as_host() { # name log
    case $1 in test_can_codec | test_servo_drive | test_master) ;; *) return 0 ;; esac
    local host_test
    host_test="$(dirname "$host")/$1"
    [ -x "$host_test" ] || { echo "mps2: no host $host_test to compare with"; return 1; }
    "$host_test" 2>&1 | diff - "$2" >"$2.diff" ||
        { echo "mps2 $1: the board's output differs from the host's:"; cat "$2.diff"; return 1; }
}

# the host's plans: the paper profile with the main build, the small one
# with a host build of the same compile-time sizes
cmake -S . -B "$out/host-small" $gen -DQRT_GRID_DEG_MIN=10 -DQRT_MAX_POINTS=1024 \
    -DQRT_PYTHON_TESTS=OFF >/dev/null &&
    cmake --build "$out/host-small" --target qrtplan_cli >"$out/host-small.log" 2>&1 ||
    { tail -20 "$out/host-small.log"; exit 1; }
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
s = json.load(open("scenes/table4_one_sphere.json"))
for name, grid in (("paper", 5), ("small", 10)):
    t = dict(s, grid_deg=grid)
    json.dump(t, open(f"{out}/table4_{name}.json", "w"))
PY

for profile in paper small; do
    grid=5; hostbin=$host
    [ $profile = small ] && grid=10 && hostbin=$out/host-small/bin/qrtplan
    mkdir -p "$out/$profile"
    python3 "$here/embed_scene.py" "$out/table4_$profile.json" $grid \
        "$out/$profile/table4_scene.h"
    if ! cmake -S "$here" -B "$out/$profile" $gen -DPROFILE=$profile \
        -DCMAKE_TOOLCHAIN_FILE="$repo/cmake/toolchains/cortex-m7.cmake" \
        -DSCENE_HEADER="$repo/$out/$profile/table4_scene.h" >/dev/null ||
        ! cmake --build "$out/$profile" >"$out/$profile/build.log" 2>&1; then
        tail -30 "$out/$profile/build.log"
        echo "FAIL mps2 $profile: build"
        failed=$((failed + 1))
        continue
    fi
    arm-none-eabi-size "$out/$profile"/*.elf | sed "s|$out/$profile/||" |
        awk -v p=$profile 'NR == 1 || /table4/ {print "  " p ": " $0}'
    # the board's plan against the host's
    start=$(date +%s.%N)
    run_image "$out/$profile/table4.elf" "$out/$profile/table4.log"
    rc=$?
    # the board builds the whole mask: its blocked-cell count is compared
    "$hostbin" plan "$out/table4_$profile.json" --whole-mask \
        -o "$out/$profile/host_plan.json"
    if python3 - "$out/$profile/table4.log" "$out/$profile/host_plan.json" <<'PY'
import json, sys
board = {}
wps, now_wps = [], []
for line in open(sys.argv[1]):
    k, _, v = line.strip().partition(" ")
    if k == "waypoint":
        wps.append([float(x) for x in v.split()])
    elif k == "now_waypoint":
        now_wps.append([float(x) for x in v.split()])
    elif k in ("status", "cells_blocked", "nodes_expanded", "cost_deg",
               "now_status", "now_nodes_expanded", "now_cost_deg",
               "stack_used"):
        board[k] = v
host = json.load(open(sys.argv[2]))
same = (board.get("status") == host["status"] and
        int(board["cells_blocked"]) == host["stats"]["cells_blocked"] and
        int(board["nodes_expanded"]) == host["stats"]["nodes_expanded"] and
        # the host's JSON gives the cost to 1e-6 degree; the waypoints it
        # is the length of are compared exactly
        round(float(board["cost_deg"]), 6) == host["cost_deg"] and
        wps == host["waypoints_deg"] and
        # qrt_planner_plan_now on the board: the same plan
        board.get("now_status") == host["status"] and
        int(board.get("now_nodes_expanded", -1)) == host["stats"]["nodes_expanded"] and
        board.get("now_cost_deg") == board["cost_deg"] and now_wps == wps)
# the deepest the stack went (painted at reset), with 1 KiB to spare
used, _, size = board.get("stack_used", "0 of 0").partition(" of ")
stack_ok = 0 < int(used) <= int(size) - 1024
print(f"    board: stack {used} of {size} B used"
      f"{'' if stack_ok else ' (too close to the end, or not measured)'}; "
      f"qrt_planner_plan_now: {board.get('now_status')}, {len(now_wps)} waypoints")
same = same and stack_ok
print(f"    board: {board.get('status')}, {board.get('cells_blocked')} blocked, "
      f"{len(wps)} waypoints {wps}")
print(f"    host:  {host['status']}, {host['stats']['cells_blocked']} blocked, "
      f"{len(host.get('waypoints_deg', []))} waypoints")
sys.exit(0 if same else 1)
PY
    then
        echo "ok   mps2 $profile: Table 4 plan on the board = the host's, bit for bit" \
            "($(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')") s)"
    else
        echo "FAIL mps2 $profile: Table 4 plan differs from the host's (exit $rc)"
        cat "$out/$profile/table4.log"
        failed=$((failed + 1))
    fi
    [ $profile = paper ] || continue
    for elf in "$out/$profile"/test_*.elf; do
        name=$(basename "$elf" .elf)
        start=$(date +%s.%N)
        if run_image "$elf" "$out/$profile/$name.log" &&
            same_as_host "$name" "$out/$profile/$name.log"; then
            echo "ok   mps2 $name: $(tail -1 "$out/$profile/$name.log")" \
                "($(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')") s)"
        else
            echo "FAIL mps2 $name"
            tail -20 "$out/$profile/$name.log"
            failed=$((failed + 1))
        fi
    done
done
[ "$failed" -eq 0 ] && echo "mps2-an500: all passed" || echo "mps2-an500: $failed failed"
[ "$failed" -eq 0 ]
