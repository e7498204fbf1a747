#!/usr/bin/env bash
# The cross-built qrtplan, run under its emulator, must plan every scene in
# scenes/ exactly as the host build does: same status, blocked-cell count,
# expansions and waypoints (everything in the plan but the timings), by
# default and on the whole mask (--whole-mask, the one that counts the
# blocked cells).
#   compare_plans.sh HOST_QRTPLAN TARGET_QRTPLAN [EMULATOR ARGS...]
set -euo pipefail
host=$1
target=$2
shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
strip_times() { grep -v '"time_us"' | sed 's/"time_us": {[^}]*}//'; }
status=0
for scene in "$root"/scenes/*.json; do
    for mode in "" --whole-mask; do
        a=$("$host" plan "$scene" $mode | strip_times)
        b=$("$@" "$target" plan "$scene" $mode | strip_times)
        if [ "$a" = "$b" ]; then
            echo "same plan: $(basename "$scene") ${mode:-(default)}"
        else
            echo "DIFFERENT plan for $(basename "$scene") ${mode:-(default)}:"
            diff <(echo "$a") <(echo "$b") || true
            status=1
        fi
    done
done
exit $status
