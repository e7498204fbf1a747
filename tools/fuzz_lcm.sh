#!/usr/bin/env bash
# Builds the libFuzzer target on qrtpland's message intake (lcm-gen C++
# decoders, the size guard, scan checks and conversion; clang, ASan and
# UBSan) in build-fuzz/ and runs it for SECONDS (default 30) from seeds made
# by the Python types (a scan of the Table 4 sphere, a request).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
out=build-fuzz
mkdir -p "$out/lcm/cpp" "$out/lcm/python" "$out/corpus_lcm"
lcm-gen -x --cpp-hpath "$out/lcm/cpp" lcm/*.lcm >/dev/null
lcm-gen -p --ppath "$out/lcm/python" lcm/*.lcm >/dev/null
QRT_LCMTYPES_PY="$out/lcm/python" .venv/bin/python - "$out/corpus_lcm" <<'PY'
import os, sys
sys.path[:0] = ["tests/daemon", "tools"]
import conftest as cf
out = sys.argv[1]
scene, pts = cf.scene_points("table4_one_sphere.json")
open(os.path.join(out, "scan"), "wb").write(cf.scan_from_points(pts[:50]).encode())
open(os.path.join(out, "request"), "wb").write(cf.request([1, 2, 3]).encode())
PY
clang++ -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=all -I"$out/lcm/cpp" -Isrc/daemon \
    -isystem /usr/include/eigen3 \
    tests/fuzz/fuzz_lcm.cpp src/daemon/ingest.cpp -o "$out/fuzz_lcm"
"$out/fuzz_lcm" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
    -print_final_stats=1 "$out/corpus_lcm" 2>"$out/fuzz_lcm.log" ||
    { tail -40 "$out/fuzz_lcm.log"; exit 1; }
grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$out/fuzz_lcm.log" || true
