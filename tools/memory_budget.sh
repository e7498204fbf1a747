#!/usr/bin/env bash
# The core's memory on each target and profile, read off built objects:
# .text/.data/.bss of libqrtplan.a (size -t), the caller's state
# (sizeof(struct qrt_planner), read from a probe object's symbol size, so it
# is the target compiler's figure), and the worst stack path
# (tools/stack_report.py over GCC's call-graph files).
#
#   tools/memory_budget.sh                 print the table (markdown)
#   tools/memory_budget.sh --update FILE   rewrite the table in FILE between
#                                          the memory-budget markers
#   tools/memory_budget.sh --check FILE    fail if FILE's table is stale
#
# Profiles: "paper" is the 5 degree lattice with 16384 exact points, the
# CMake board profile's settings (Cortex-A boards); "small" is a 10 degree
# lattice with 1024 exact points, whose state and stack fit a Cortex-M7's
# 512 KiB of SRAM; "host" is the CMake host profile's (its exact points read
# from CMakeLists.txt, 2^19 now), for the robot computer's programs (x86-64 and aarch64 only: no board
# holds its state).
set -euo pipefail
cd "$(dirname "$0")/.."
gen=$(command -v ninja >/dev/null && echo "-G Ninja" || true)
top=build-budget
mkdir -p "$top"

targets=("x86-64:" "armhf:cmake/toolchains/arm-linux-gnueabihf.cmake"
         "aarch64:cmake/toolchains/aarch64-linux-gnu.cmake"
         "cortex-m7:cmake/toolchains/cortex-m7.cmake")
host_points=$(sed -n '/QRT_PROFILE_USED STREQUAL "host"/,/endif/ s/.*set(QRT_PROFILE_MAX_POINTS \([0-9]*\)).*/\1/p' CMakeLists.txt)
[ -n "$host_points" ] || { echo "host profile's points not found in CMakeLists.txt" >&2; exit 1; }
profiles=("paper:5:16384:board" "small:10:1024:board" "host:5:$host_points:host")
sram=$((512 * 1024))

tool_for() { # target tool -> the target's binutils program
    case $1 in
    x86-64) echo "$2" ;;
    armhf) echo "arm-linux-gnueabihf-$2" ;;
    aarch64) echo "aarch64-linux-gnu-$2" ;;
    cortex-m7) echo "arm-none-eabi-$2" ;;
    esac
}

table() {
    echo "| target | profile | .text (B) | .data (B) | .bss (B) | state \`struct qrt_planner\` (B) | worst stack (B) | state + stack |"
    echo "|---|---|---:|---:|---:|---:|---:|---:|"
    for t in "${targets[@]}"; do
        local name=${t%%:*} chain=${t#*:}
        for p in "${profiles[@]}"; do
            IFS=: read -r prof grid pts cmake_profile <<<"$p"
            [ "$prof" = host ] && [ "$name" != x86-64 ] &&
                [ "$name" != aarch64 ] && continue
            local dir=$top/$name-$prof
            local tc=()
            [ -n "$chain" ] && tc=(-DCMAKE_TOOLCHAIN_FILE="$PWD/$chain")
            cmake -S . -B "$dir" $gen -DQRT_CORE_ONLY=ON \
                -DQRT_PROFILE="$cmake_profile" \
                -DCMAKE_BUILD_TYPE=RelWithDebInfo "${tc[@]}" \
                -DQRT_GRID_DEG_MIN="$grid" -DQRT_MAX_POINTS="$pts" >/dev/null
            cmake --build "$dir" >"$dir/build.log" 2>&1 ||
                { tail -20 "$dir/build.log" >&2; exit 1; }
            local cc flags
            cc=$(sed -n 's/^CMAKE_C_COMPILER:[A-Z]*=//p' "$dir/CMakeCache.txt")
            [ -n "$cc" ] || cc=$(tool_for "$name" gcc)
            [ "$name" = cortex-m7 ] &&
                flags="-mcpu=cortex-m7 -mfpu=fpv5-d16 -mfloat-abi=hard -mthumb"
            echo 'char qrt_budget_state[sizeof(struct qrt_planner)];' |
                $cc ${flags:-} -x c -std=c99 -include qrtplan/planner.h -Iinclude \
                    -DQRT_GRID_DEG_MIN="$grid" -DQRT_MAX_POINTS="$pts" \
                    -c - -o "$dir/probe.o"
            local state text data bss stack report
            state=$((16#$($(tool_for "$name" nm) -S "$dir/probe.o" |
                awk '/qrt_budget_state/ {print $2}')))
            read -r text data bss < <($(tool_for "$name" size) -t \
                "$dir/lib/libqrtplan.a" | awk '/TOTALS/ {print $1, $2, $3}')
            # a report that fails (an unlisted indirect call, recursion)
            # has no worst path to put in the table
            report=$(python3 tools/stack_report.py "$dir/CMakeFiles/qrtplan.dir") ||
                { grep '^FAIL' <<<"$report" >&2; exit 1; }
            stack=$(awk '/^worst path:/ {print $3}' <<<"$report")
            local total=$((state + stack)) fits=""
            [ "$prof" = small ] &&
                fits=" ($((total * 100 / sram)) % of 512 KiB)"
            echo "| $name | $prof (${grid}°, $pts points) | $text | $data | $bss | $state | $stack | $total$fits |"
        done
    done
}

begin='<!-- memory-budget:begin (tools/memory_budget.sh --update docs/embedded.md) -->'
end='<!-- memory-budget:end -->'
case ${1:-} in
--update | --check)
    file=$2
    new=$(table)
    old=$(awk -v b="$begin" -v e="$end" '$0 == e {on = 0} on {print} $0 == b {on = 1}' "$file")
    if [ "$1" = --check ]; then
        if [ "$new" != "$old" ]; then
            echo "memory_budget: the table in $file is stale; now:"
            echo "$new"
            exit 1
        fi
        echo "memory_budget: the table in $file matches the built objects"
    else
        python3 - "$file" "$begin" "$end" "$new" <<'EOF'
import sys
path, begin, end, table = sys.argv[1:]
text = open(path).read()
a = text.index(begin) + len(begin)
b = text.index(end)
open(path, "w").write(text[:a] + "\n" + table + "\n" + text[b:])
EOF
    fi
    ;;
*) table ;;
esac
