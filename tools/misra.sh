#!/usr/bin/env bash
# cppcheck with its MISRA C:2012 addon over the core (src/core,
# include/qrtplan) or, with --can, over the servo side that runs on boards
# too (the CANopen / CiA 402 codec, the master, the drive firmware). Fails on
# any finding that is not a deviation listed in tools/misra/deviations.txt
# (justified in docs/embedded.md); the servo side's public headers may also
# define protocol constants the library itself does not use (rule 2.5).
#   tools/misra.sh [--can]            check (what core_misra / can_misra run)
#   tools/misra.sh [--can] --report   count the findings of each deviated rule
set -euo pipefail
cd "$(dirname "$0")/.."
args=(-q --std=c99 --enable=warning,style,performance,portability
      --addon=misra --inline-suppr -Iinclude)
part=core
if [ "${1:-}" = --can ]; then
    part="servo side"
    shift
    args+=(-Ifirmware_sim "--suppress=misra-c2012-2.5:include/qrtcan/*")
    sources=(src/canopen/*.c src/canmaster/master.c src/canmaster/profile.c firmware_sim/drive.c)
else
    args+=(-Isrc/core -DQRT_GRID_DEG_MIN=5 -DQRT_MAX_POINTS=16384)
    sources=(src/core/*.c)
fi
if ! command -v cppcheck >/dev/null; then
    echo "misra: cppcheck is not installed (tools/setup.sh installs it)" >&2
    exit 1
fi
if [ "${1:-}" = --report ]; then
    # the addon reports one rule per line; suppress each rule in turn to
    # see the next one, so every finding is counted once
    supp=$(mktemp)
    trap 'rm -f "$supp"' EXIT
    while :; do
        out=$(cppcheck "${args[@]}" --template='{id}' \
            --suppressions-list="$supp" "${sources[@]}" 2>&1 | sort | uniq -c)
        [ -z "$out" ] && break
        echo "$out"
        echo "$out" | awk '{print $2}' >>"$supp"
    done | sort -k2 -u | sort -rn
    exit 0
fi
out=$(cppcheck "${args[@]}" --template='{file}:{line}: {id}: {message}' \
    --suppressions-list=tools/misra/deviations.txt "${sources[@]}" 2>&1)
if [ -n "$out" ]; then
    echo "$out"
    echo "misra ($part): findings outside the documented deviations"
    exit 1
fi
echo "misra ($part): cppcheck $(cppcheck --version | cut -d' ' -f2) with the MISRA" \
    "C:2012 addon: no finding outside the $(grep -c '^[a-zA-Z]' tools/misra/deviations.txt)" \
    "documented deviations"
