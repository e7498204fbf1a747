#!/usr/bin/env bash
# What `cmake --install` gives a stranger, built against as examples/ says:
#   1. the full install (this build): the core, the CAN codec and master,
#      the .lcm files and the generated C/C++ message types, with libm
#      named (-lm, m), never by this machine's path; examples/ built with
#      find_package(qrtplan) plans Table 4 as `qrtplan plan` does, and a
#      program links the CAN and LCM targets (CMake and pkg-config);
#   2. a QRT_CORE_ONLY build of the same source, installed: the core alone,
#      examples/ built with find_package and with the pkg-config line of
#      examples/table4.c, the same plan; the CAN component is not there.
#   install_examples.sh BUILD_DIR QRTPLAN_BIN
set -euo pipefail
build=$(cd "$1" && pwd)
cli=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
root=$(cd "$(dirname "$0")/.." && pwd)
work=$build/install-examples
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
setting() { sed -n "s/^$1:[A-Z]*=//p" "$build/CMakeCache.txt"; }

# the Table 4 plan as printed by examples/table4.c against the CLI's
check_plan() { # program
    local out
    out=$("$1") || fail "$1 exited $?: $out"
    "$cli" plan "$root/scenes/table4_one_sphere.json" -o "$work/cli_plan.json"
    python3 - "$work/cli_plan.json" <<PY || fail "$1: not the CLI's plan"
import json, sys
plan = json.load(open(sys.argv[1]))
lines = """$out""".splitlines()
assert lines[0] == "status ok", lines
wps = [[float(v) for v in l.split()[1:]] for l in lines if l.startswith("waypoint ")]
assert len(wps) == len(plan["waypoints_deg"]) >= 2, (wps, plan["waypoints_deg"])
for a, b in zip(wps, plan["waypoints_deg"]):
    assert all(abs(x - y) < 1e-6 for x, y in zip(a, b)), (a, b)
cost = [float(l.split()[1]) for l in lines if l.startswith("cost_deg ")]
assert abs(cost[0] - plan["cost_deg"]) < 1e-6, (cost, plan["cost_deg"])
PY
    echo "$1: the CLI's Table 4 plan, ${out//$'\n'/; }"
}

no_machine_paths() { # prefix
    if grep -rE "/[^ ;\"]*libm\.(so|a)" "$1/lib/cmake" "$1/lib/pkgconfig"; then
        fail "$1: libm by path in the package files"
    fi
    grep -q 'INTERFACE_LINK_LIBRARIES "m"' "$1/lib/cmake/qrtplan/qrtplanTargets.cmake" ||
        fail "$1: qrtplan::qrtplan does not link m by name"
    PKG_CONFIG_PATH=$1/lib/pkgconfig pkg-config --libs qrtplan | grep -qw -- -lm ||
        fail "$1: qrtplan.pc without -lm"
}

# --- 1. the full install --------------------------------------------------
full=$work/full
cmake --install "$build" --prefix "$full" >/dev/null
for f in lib/libqrtplan.a include/qrtplan/qrtplan.h lib/cmake/qrtplan/qrtplanConfig.cmake \
    lib/pkgconfig/qrtplan.pc bin/qrtplan lib/libqrtcan.a lib/libqrtcan_master.a \
    include/qrtcan/qrtcan.h include/qrtcan/master.h lib/cmake/qrtplan/qrtcanTargets.cmake \
    lib/pkgconfig/qrtcan.pc; do
    [ -e "$full/$f" ] || fail "full install: no $f"
done
for t in "$root"/lcm/*.lcm; do
    [ -f "$full/share/qrtplan/lcm/$(basename "$t")" ] || fail "full install: no $(basename "$t")"
done
lcm=0
if [ -d "$build/lcmtypes" ]; then # the daemon was built: lcm-gen's types
    lcm=1
    for t in "$root"/lcm/*.lcm; do
        n=$(basename "$t" .lcm)
        for f in "include/qrtplan_$n.h" "include/qrtplan/$n.hpp" \
            "share/qrtplan/python/qrtplan/$n.py"; do
            [ -f "$full/$f" ] || fail "full install: no $f"
        done
    done
    [ -f "$full/lib/libqrtplan_lcmtypes.a" ] || fail "full install: no libqrtplan_lcmtypes.a"
fi
no_machine_paths "$full"
cmake -S "$root/examples" -B "$work/ex-full" -DCMAKE_PREFIX_PATH="$full" \
    -DCMAKE_C_FLAGS="-Wall -Wextra -Werror -pedantic" >/dev/null
cmake --build "$work/ex-full" >/dev/null
check_plan "$work/ex-full/table4"

# a program on the CAN targets (and the C message types when built)
mkdir -p "$work/can-src"
components=can
libs="qrtplan::qrtcan_master"
cat >"$work/can-src/main.c" <<'C'
#include <stdio.h>

#include "qrtcan/qrtcan.h"
#include "qrtcan/master.h"
#ifdef WITH_LCM
#include "qrtplan_plan_t.h"
#endif

int main(void)
{
    struct qrtcan_frame f;
    struct qrtcan_master_config cfg;
    qrtcan_master_config_default(&cfg);
    if (qrtcan_nmt_encode(QRTCAN_NMT_START, 1, &f) != 0)
        return 1;
    printf("NMT start: id %u, %u bytes\n", (unsigned)f.id, (unsigned)f.dlc);
#ifdef WITH_LCM
    {
        char none[1] = "";
        qrtplan_plan_t plan = {0};
        plan.status = plan.detail = none;
        printf("plan_t: %d bytes encoded\n", qrtplan_plan_t_encoded_size(&plan));
    }
#endif
    return f.id == 0 && f.dlc == 2 ? 0 : 1;
}
C
if [ $lcm = 1 ]; then
    components="can lcm"
    libs="$libs qrtplan::lcmtypes"
fi
cat >"$work/can-src/CMakeLists.txt" <<CM
cmake_minimum_required(VERSION 3.25)
project(can_consumer C)
find_package(qrtplan REQUIRED COMPONENTS $components)
add_executable(can_consumer main.c)
target_link_libraries(can_consumer PRIVATE $libs)
if(TARGET qrtplan::lcmtypes)
  target_compile_definitions(can_consumer PRIVATE WITH_LCM)
endif()
CM
cmake -S "$work/can-src" -B "$work/can-build" -DCMAKE_PREFIX_PATH="$full" >/dev/null
cmake --build "$work/can-build" >/dev/null
"$work/can-build/can_consumer"
cc -std=c99 -Wall -Werror "$work/can-src/main.c" \
    $(PKG_CONFIG_PATH=$full/lib/pkgconfig pkg-config --cflags --libs qrtcan) -o "$work/can-pc"
"$work/can-pc" >/dev/null
echo "full install: the CAN targets link (CMake: $components; pkg-config: qrtcan)"

# --- 2. the core alone ----------------------------------------------------
core=$work/core
cmake -S "$root" -B "$work/core-build" -DQRT_CORE_ONLY=ON \
    -DCMAKE_C_COMPILER="$(setting CMAKE_C_COMPILER)" \
    -DQRT_GRID_DEG_MIN="$(setting QRT_GRID_DEG_MIN)" \
    -DQRT_MAX_POINTS="$(setting QRT_MAX_POINTS_USED)" >/dev/null
cmake --build "$work/core-build" -j 2 >/dev/null
cmake --install "$work/core-build" --prefix "$core" >/dev/null
for f in lib/libqrtplan.a include/qrtplan/qrtplan.h include/qrtplan/planner.h \
    lib/cmake/qrtplan/qrtplanConfig.cmake lib/cmake/qrtplan/qrtplanConfigVersion.cmake \
    lib/pkgconfig/qrtplan.pc; do
    [ -e "$core/$f" ] || fail "core-only install: no $f"
done
for f in lib/libqrtcan.a include/qrtcan bin/qrtplan; do
    [ ! -e "$core/$f" ] || fail "core-only install: $f is not the core's"
done
no_machine_paths "$core"
cmake -S "$root/examples" -B "$work/ex-core" -DCMAKE_PREFIX_PATH="$core" \
    -DCMAKE_C_FLAGS="-Wall -Wextra -Werror -pedantic" >/dev/null
cmake --build "$work/ex-core" >/dev/null
check_plan "$work/ex-core/table4"
# the one line of examples/table4.c
line=$(sed -n 's/^ \*   \(cc .*\)$/\1/p' "$root/examples/table4.c")
[ -n "$line" ] || fail "examples/table4.c: no pkg-config line"
(cd "$root/examples" && PKG_CONFIG_PATH=$core/lib/pkgconfig \
    eval "${line/-o table4/-o $work/table4-pc}")
check_plan "$work/table4-pc"
if out=$(cmake -S "$work/can-src" -B "$work/can-core" -DCMAKE_PREFIX_PATH="$core" 2>&1) ||
    [[ "$out" != *"qrtplan_FOUND to FALSE"* ]]; then
    echo "$out"
    fail "core-only install: find_package(qrtplan COMPONENTS can) did not say it is missing"
fi
echo "core-only install: the core alone, the CAN component refused"
