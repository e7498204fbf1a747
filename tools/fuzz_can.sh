#!/usr/bin/env bash
# Builds the libFuzzer target on the CANopen frame decoders, the
# simulated drive's frame handler and the CiA 402 master's (clang, ASan and UBSan) in build-fuzz/
# and runs it for SECONDS (default 30) from a small seed corpus.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
out=build-fuzz
mkdir -p "$out/corpus_can"
# seeds: NMT start, SYNC, an SDO read of 0x6041, an RPDO enabling node 1,
# each as id(2) dlc(1) data(8)
printf '\x00\x00\x02\x01\x01\x00\x00\x00\x00\x00\x00' >"$out/corpus_can/nmt"
printf '\x00\x80\x00\x00\x00\x00\x00\x00\x00\x00\x00' >"$out/corpus_can/sync"
printf '\x06\x01\x08\x40\x41\x60\x00\x00\x00\x00\x00' >"$out/corpus_can/sdo"
printf '\x00\x00\x02\x01\x00\x00\x00\x00\x00\x00\x00\x02\x01\x06\x06\x00\x00\x00\x00\x00\x00\x00\x02\x01\x06\x0f\x00\x10\x27\x00\x00\x00\x00\x02\x01\x06\x1f\x00\x10\x27\x00\x00\x00\x00' \
    >"$out/corpus_can/enable"
# the closed loop (tests/fuzz/fuzz_can.c) brought up and moving: 300 frames
# the master ignores, 5 ms apart, a path at the 200th, a quick stop at the
# 260th, the host watchdog at the 280th (data bytes 7 and 8 carry the
# command)
for i in $(seq 1 300); do
    case $i in
    200) cmd='\x01\x01' ;;
    260) cmd='\x02\x01' ;;
    280) cmd='\x08\x01' ;;
    *) cmd='\x00\x00' ;;
    esac
    printf "\x07\xff\x50\x00\x00\x00\x00\x00\x00$cmd"
done >"$out/corpus_can/loop"
clang -std=c99 -g -O1 -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=all -Iinclude -Ifirmware_sim \
    tests/fuzz/fuzz_can.c firmware_sim/drive.c src/canopen/*.c \
    src/canmaster/master.c src/canmaster/profile.c -lm \
    -o "$out/fuzz_can"
"$out/fuzz_can" -max_total_time="$seconds" -max_len=4096 -timeout=10 \
    -print_final_stats=1 "$out/corpus_can" 2>"$out/fuzz_can.log" ||
    { tail -40 "$out/fuzz_can.log"; exit 1; }
grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$out/fuzz_can.log" || true
