#!/usr/bin/env bash
# Install the core into a scratch prefix and build a separate project
# against it twice: with find_package(qrtplan) and with pkg-config. Then
# compile programs against it with other settings than the library's and
# check that qrt_planner_init refuses them (QRT_E_ABI, a sentence naming the
# settings) instead of letting the library overrun their smaller planner.
# Last, build and install a library with a value other than the default for
# every setting of config.h, and check that a consumer that passes no -D
# flags of its own gets the library's settings through find_package and
# through pkg-config alike (qrt_planner_init succeeds).
set -euo pipefail
build=$1
src=$(cd "$(dirname "$0")" && pwd)/consumer
work=$build/consumer-test
rm -rf "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src" -B "$work/cmake" -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/cmake" >/dev/null
"$work/cmake/consumer"
export PKG_CONFIG_PATH=$work/prefix/lib/pkgconfig
cc -std=c99 "$src/main.c" $(pkg-config --cflags --libs qrtplan) -o "$work/pc"
"$work/pc"

# The library's settings, and others for the callers (QRT_GRID_DEG_MIN must
# divide 20).
setting() { sed -n "s/^$1:STRING=//p" "$build/CMakeCache.txt"; }
grid=$(setting QRT_GRID_DEG_MIN)
# the value built with (QRT_MAX_POINTS empty takes the profile's)
points=$(sed -n "s/^QRT_MAX_POINTS_USED:INTERNAL=//p" "$build/CMakeCache.txt")
other_grid=$([ "$grid" = 10 ] && echo 5 || echo 10)
other_points=$([ "$points" = 1024 ] && echo 2048 || echo 1024)
# mismatch NAME EXPECTED... -- CFLAGS...: build mismatch.c with the flags
# (only the include path from pkg-config: its -D are the library's), run
# it, and find each expected phrase in what it prints.
mismatch() {
    local name=$1 expected=() out rc=0
    shift
    while [ "$1" != -- ]; do expected+=("$1"); shift; done
    shift
    cc -std=c99 -Wall -Wextra -Werror -pedantic "$@" "$src/mismatch.c" \
        $(pkg-config --cflags-only-I --libs qrtplan) -o "$work/$name"
    out=$("$work/$name" 2>&1) || rc=$?
    if [ "$rc" != 0 ]; then
        echo "FAIL: $name ($*): exit status $rc: $out"
        exit 1
    fi
    for phrase in "${expected[@]}"; do
        if [[ "$out" != *"$phrase"* ]]; then
            echo "FAIL: $name ($*): '$out' does not say '$phrase'"
            exit 1
        fi
    done
    echo "$name: refused: $out"
}
mismatch grid_points \
    "QRT_GRID_DEG_MIN $other_grid, the library with $grid" \
    "QRT_MAX_POINTS $other_points, the library with $points" -- \
    -DQRT_GRID_DEG_MIN="$other_grid" -DQRT_MAX_POINTS="$other_points"
# the settings match but struct qrt_plan does not: sizes alone would miss it
mismatch waypoints "QRT_MAX_WAYPOINTS 64, the library with " -- \
    -DQRT_GRID_DEG_MIN="$grid" -DQRT_MAX_POINTS="$points" \
    -DQRT_MAX_WAYPOINTS=64

# A library built with a value other than the default for every setting:
# the core alone (QRT_CORE_ONLY installs the headers, the library, the CMake
# package and qrtplan.pc).
alt=$work/alt
cmake -S "$src/../.." -B "$alt/build" -DQRT_CORE_ONLY=ON \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQRT_GRID_DEG_MIN=10 \
    -DQRT_MAX_POINTS=2048 -DQRT_MAX_WAYPOINTS=64 -DQRT_GOAL_REGION_NODES=8 \
    -DQRT_LAZY_INDEX_AFTER=4 >/dev/null
cmake --build "$alt/build" -j2 >/dev/null
cmake --install "$alt/build" --prefix "$alt/prefix" >/dev/null
want="QRT_GRID_DEG_MIN 10 QRT_MAX_POINTS 2048 QRT_MAX_WAYPOINTS 64"
want="$want QRT_GOAL_REGION_NODES 8 QRT_LAZY_INDEX_AFTER 4"
# consumed: run the program, which must plan, and see the settings it saw
consumed() {
    local how=$1 out rc=0
    shift
    out=$("$@" 2>&1) || rc=$?
    if [ "$rc" != 0 ] || [[ "$out" != *"settings: $want"* ]]; then
        echo "FAIL: the library built with $want, consumed through $how: $out"
        exit 1
    fi
    echo "non-default settings through $how: $out"
}
cmake -S "$src" -B "$alt/cmake" -DCMAKE_PREFIX_PATH="$alt/prefix" >/dev/null
cmake --build "$alt/cmake" >/dev/null
consumed find_package "$alt/cmake/consumer"
export PKG_CONFIG_PATH=$alt/prefix/lib/pkgconfig
cc -std=c99 "$src/main.c" $(pkg-config --cflags --libs qrtplan) -o "$alt/pc"
consumed pkg-config "$alt/pc"
