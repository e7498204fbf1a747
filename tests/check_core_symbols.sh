#!/usr/bin/env bash
# The core's promise, checked on the built library: it calls nothing but
# libm, memset and compiler helpers (no malloc, stdio, clocks or other OS
# calls) and has no global or static data (all state is the caller's
# struct qrt_planner).
set -euo pipefail
lib=$1
nm=${2:-nm}
# libm, memset/memcpy (struct initialisers), the core's own functions, and
# the compiler's runtime helpers (libgcc: __aeabi_idiv on 32-bit ARM,
# __divdi3 and the like), which are code, not OS calls
allowed='^(acos|asin|atan2|cos|sin|sincos|floor|ceil|fmod|hypot|sqrt|memset|memcpy|qrt_[a-z0-9_]+|__aeabi_[a-z0-9_]+|__[a-z]+[0-9])$'
undefined=$("$nm" -u "$lib" | awk 'NF == 2 {print $2}' | sort -u)
bad=$(echo "$undefined" | grep -Ev "$allowed" || true)
data=$("$nm" "$lib" | awk '$2 ~ /^[bBdDcC]$/ {print $3}' | sort -u)
echo "core calls: $(echo "$undefined" | grep -v '^qrt_' | tr '\n' ' ')"
if [ -n "$bad" ]; then
    echo "FAIL: the core calls outside libm: $bad"
    exit 1
fi
if [ -n "$data" ]; then
    echo "FAIL: the core has global or static data: $data"
    exit 1
fi
echo "ok: no allocation, I/O, clock or OS calls; no global data"
