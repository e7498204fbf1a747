#!/usr/bin/env bash
# tools/stack_report.py must fail on what it is there to catch: recursion,
# a variable-length array and an unlisted indirect call (tests/stack/recursive.c),
# each reported by name, and two static functions of one name in two units
# (twin_a.c, twin_b.c), whose frames it would otherwise merge.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cc=${1:-gcc}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && "$cc" -std=c99 -O1 -fcallgraph-info=su -c "$here/recursive.c")
if out=$(python3 "$here/../../tools/stack_report.py" "$tmp"); then
    echo "$out"
    echo "FAIL: stack_report accepted recursion, a VLA and an indirect call"
    exit 1
fi
for what in "recursion through qrt_fact" "qrt_vla: unbounded dynamic" \
    "qrt_indirect: indirect call not listed"; do
    grep -q "$what" <<<"$out" || { echo "$out"; echo "FAIL: no '$what'"; exit 1; }
done
mkdir "$tmp/a" "$tmp/b"
(cd "$tmp/a" && "$cc" -std=c99 -O1 -fcallgraph-info=su -c "$here/twin_a.c")
(cd "$tmp/b" && "$cc" -std=c99 -O1 -fcallgraph-info=su -c "$here/twin_b.c")
if out=$(python3 "$here/../../tools/stack_report.py" "$tmp/a" "$tmp/b"); then
    echo "$out"
    echo "FAIL: stack_report merged two static functions of one name"
    exit 1
fi
grep -q "two functions named twin" <<<"$out" ||
    { echo "$out"; echo "FAIL: no 'two functions named twin'"; exit 1; }
echo "ok: stack_report refuses recursion, VLAs, unlisted indirect calls and" \
    "two statics of one name"
