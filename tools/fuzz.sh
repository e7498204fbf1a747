#!/usr/bin/env bash
# Builds the libFuzzer target (clang, with ASan and UBSan) in build-fuzz/ and
# runs it on a copy of the seed corpus for SECONDS (default 30).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
out=build-fuzz
mkdir -p "$out/corpus"
cp tests/fuzz/corpus/* "$out/corpus/"
clang -std=c99 -g -O1 -D_POSIX_C_SOURCE=200809L -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=all -Iinclude -Isrc/cli \
    tests/fuzz/fuzz_scene.c src/cli/budget.c src/cli/json.c src/cli/lzf.c src/cli/pcd.c \
    src/cli/scene.c \
    src/core/*.c -lm -o "$out/fuzz_scene"
"$out/fuzz_scene" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
    -print_final_stats=1 "$out/corpus" 2>"$out/fuzz.log" ||
    { tail -40 "$out/fuzz.log"; exit 1; }
grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$out/fuzz.log" || true
