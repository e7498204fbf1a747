#!/usr/bin/env bash
# Builds the libFuzzer targets on qrtpland's message intake (lcm-gen C++
# decoders, the size guard, scan checks and conversion; and the
# authenticated-message decoder; clang, ASan and UBSan) in build-fuzz/ and
# runs each for SECONDS (default 30) from seeds made by the Python types (a
# scan and a point cloud of the Table 4 sphere, a request; the scan and the
# request also authenticated with the fuzz target's fixed test keys).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
out=build-fuzz
mkdir -p "$out/lcm/cpp" "$out/lcm/python" "$out/corpus_lcm" "$out/corpus_auth"
mkdir -p -m 700 "$out/fuzz_keys"
lcm-gen -x --cpp-hpath "$out/lcm/cpp" lcm/*.lcm >/dev/null
lcm-gen -p --ppath "$out/lcm/python" lcm/*.lcm >/dev/null
QRT_LCMTYPES_PY="$out/lcm/python" .venv/bin/python - "$out" <<'PY'
import os, sys
sys.path[:0] = ["tests/daemon", "tools"]
import conftest as cf
import qrtauth
out = sys.argv[1]
scene, pts = cf.scene_points("table4_one_sphere.json")
scan = cf.scan_from_points(pts[:50]).encode()
req = cf.request([1, 2, 3]).encode()
cloud = cf.cloud_from_points(pts[:50], position=(0.1, 0.0, 0.3),
                             orientation=(0.6, 0.0, 0.8, 0.0)).encode()
open(os.path.join(out, "corpus_lcm", "scan"), "wb").write(scan)
open(os.path.join(out, "corpus_lcm", "cloud"), "wb").write(cloud)
open(os.path.join(out, "corpus_lcm", "request"), "wb").write(req)
# the fuzz target's fixed keys (tests/fuzz/fuzz_auth.cpp)
signers = []
for name, role, first in (("op", "operator", 0), ("s0", "sensor", 32)):
    path = os.path.join(out, "fuzz_keys", name + ".key")
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.write(fd, f"name {name}\nrole {role}\nsecret "
             f"{bytes(range(first, first + 32)).hex()}\n".encode())
    os.close(fd)
    signers.append(qrtauth.Signer(path))
# the first byte picks the channel: 0 requests, 1 scans
seeds = {"request": b"\0" + signers[0].seal("QRT_PLAN_REQUEST", req),
         "scan": b"\1" + signers[1].seal("QRT_SCAN", scan),
         "unsigned": b"\0" + req}
for name, data in seeds.items():
    open(os.path.join(out, "corpus_auth", name), "wb").write(data)
PY
# the core's arm model (the reach the ingest drops returns beyond), in C
clang -std=c99 -g -O1 -fsanitize=fuzzer-no-link,address,undefined \
    -fno-sanitize-recover=all -Iinclude -Isrc/core \
    -c src/core/arm.c -o "$out/arm.o"
clang++ -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=all -I"$out/lcm/cpp" -Isrc/daemon -Iinclude \
    -isystem /usr/include/eigen3 \
    tests/fuzz/fuzz_lcm.cpp src/daemon/ingest.cpp "$out/arm.o" -lm \
    -o "$out/fuzz_lcm"
# inputs that once failed, run once each before the search
"$out/fuzz_lcm" tests/fuzz/regress_lcm/* 2>"$out/fuzz_lcm_regress.log" ||
    { tail -40 "$out/fuzz_lcm_regress.log"; exit 1; }
"$out/fuzz_lcm" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
    -print_final_stats=1 "$out/corpus_lcm" 2>"$out/fuzz_lcm.log" ||
    { tail -40 "$out/fuzz_lcm.log"; exit 1; }
grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$out/fuzz_lcm.log" || true
clang++ -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=all -I"$out/lcm/cpp" -Isrc/daemon \
    tests/fuzz/fuzz_auth.cpp src/daemon/auth.cpp src/daemon/keyfile.cpp \
    -lsodium -o "$out/fuzz_auth"
"$out/fuzz_auth" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
    -print_final_stats=1 "$out/corpus_auth" 2>"$out/fuzz_auth.log" ||
    { tail -40 "$out/fuzz_auth.log"; exit 1; }
grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$out/fuzz_auth.log" || true
