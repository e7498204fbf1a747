#!/usr/bin/env bash
# Install the core into a scratch prefix and build a separate project
# against it twice: with find_package(qrtplan) and with pkg-config. Then
# compile programs against it with other settings than the library's and
# check that qrt_planner_init refuses them (QRT_E_ABI, a sentence naming the
# settings) instead of letting the library overrun their smaller planner.
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
points=$(setting QRT_MAX_POINTS)
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
