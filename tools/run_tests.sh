#!/usr/bin/env bash
# Every test of the project, as `make test` and CI run them:
#   1. the release build's CTest suite (C unit tests, Python tests, the
#      daemon over LCM, the CAN tests on vcan0 in a VM),
#   2. the same suite built with AddressSanitizer and UBSan, and the tests
#      that run threads built with ThreadSanitizer,
#   3. the core's C tests cross-built for armhf and aarch64, run under
#      qemu-user, with the paper's scenes planned exactly as on the host,
#   4. the core cross-built for a Cortex-M7, and bare-metal Cortex-M7 images
#      (ports/mps2-an500) running the core's tests, the Table 4 plan and
#      the servo side's tests (codec, drive firmware, CiA 402 master) on
#      qemu-system-arm, compared with the host's bit for bit,
#   5. the memory table of docs/embedded.md checked against the built objects,
#   6. the libFuzzer targets (scene/PCD readers, CAN frames, LCM messages).
# With --fast (`make check`) only step 1 without its VM tests (names ending
# in _vm): the C unit tests, the Python tests, the daemon over LCM.
# Ends with one "N passed, M failed" line; exits non-zero on any failure.
set -uo pipefail
cd "$(dirname "$0")/.."
fast=0
case "${1:-}" in
--fast) fast=1 ;;
"") ;;
*)
    echo "usage: tools/run_tests.sh [--fast]" >&2
    exit 2
    ;;
esac
jobs=$(nproc 2>/dev/null || echo 2)
gen=$(command -v ninja >/dev/null && echo "-G Ninja")
fuzz_seconds=${QRT_FUZZ_SECONDS:-30}
passed=0
failed=0

run_suite() { # name builddir cmake-args...
    local name=$1 dir=$2 out
    shift 2
    echo "== $name"
    if ! cmake -S . -B "$dir" $gen "$@" >/dev/null ||
        ! cmake --build "$dir" -j "$jobs" >"$dir/build.log" 2>&1; then
        tail -50 "$dir/build.log"
        echo "$name: build failed"
        failed=$((failed + 1))
        return
    fi
    out=$(cd "$dir" && ctest --output-on-failure -j "$jobs" ${ctest_args:-} 2>&1)
    echo "$out" | grep -E "Test +#|tests passed|Failed|FAIL|Error" | tail -40
    local total fails
    total=$(echo "$out" | sed -n 's/.*tests passed, [0-9]* tests failed out of \([0-9]*\).*/\1/p')
    fails=$(echo "$out" | sed -n 's/.*tests passed, \([0-9]*\) tests failed out of.*/\1/p')
    if [ -z "$total" ]; then
        echo "$out" | tail -20
        failed=$((failed + 1))
        return
    fi
    passed=$((passed + total - fails))
    failed=$((failed + fails))
}

if [ $fast = 1 ]; then
    ctest_args="-E _vm$" run_suite "release build, no VM tests" build \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQRT_PYTHON_TESTS=ON
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
    exit
fi
run_suite "release build" build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQRT_PYTHON_TESTS=ON
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    run_suite "ASan + UBSan build" build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DQRT_SANITIZE=ON -DQRT_PYTHON_TESTS=ON

# The tests that run threads (the daemon's planner, clock, guard and CAN link
# threads, its watchdog over them and a goal changed mid-move; the
# two-thread mask; qrtplan-exec's CAN link), built with
# ThreadSanitizer. A race is logged, not fatal, so that every test runs; any
# log fails the step.
tsan_logs="$PWD/build-tsan/races"
rm -rf "$tsan_logs"
mkdir -p "$tsan_logs"
TSAN_OPTIONS="halt_on_error=0 log_path=$tsan_logs/race" \
    ctest_args="-R ^(test_mask_threads|daemon_tests|daemon_can_vm|daemon_soak_vm|can_exec_vm|canopen_drive_vm|failsafe_watchdog_vm|failsafe_goal_change_vm)$" \
    run_suite "ThreadSanitizer build (the tests that run threads)" build-tsan \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQRT_TSAN=ON -DQRT_PYTHON_TESTS=ON
if ls "$tsan_logs"/race* >/dev/null 2>&1; then
    head -80 "$tsan_logs"/race*
    echo "ThreadSanitizer: data races reported (build-tsan/races/)"
    failed=$((failed + 1))
else
    echo "ThreadSanitizer: no data race reported"
    passed=$((passed + 1))
fi

# The core and its C tests on ARM Linux, under qemu-user, and the plans of
# the paper's scenes compared with the host build's.
for target in arm-linux-gnueabihf aarch64-linux-gnu; do
    run_suite "$target (qemu-user)" "build-$target" \
        -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/$target.cmake \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQRT_PYTHON_TESTS=OFF \
        -DQRT_HOST_QRTPLAN="$PWD/build/bin/qrtplan"
done

echo "== Cortex-M7 (arm-none-eabi): the core builds with -Werror"
if cmake -S . -B build-cortex-m7 $gen -DQRT_CORE_ONLY=ON \
    -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/cortex-m7.cmake >/dev/null &&
    cmake --build build-cortex-m7 >build-cortex-m7/build.log 2>&1; then
    passed=$((passed + 1))
    echo "cortex-m7 core: built"
else
    tail -30 build-cortex-m7/build.log
    failed=$((failed + 1))
fi

echo "== Cortex-M7 bare metal (qemu-system-arm -M mps2-an500): core tests, Table 4 plan, the servo side's tests"
if ports/mps2-an500/run.sh build/bin/qrtplan; then
    passed=$((passed + 1))
else
    failed=$((failed + 1))
fi

echo "== memory budget: docs/embedded.md's table against the built objects"
if tools/memory_budget.sh --check docs/embedded.md; then
    passed=$((passed + 1))
else
    failed=$((failed + 1))
fi

echo "== libFuzzer: scene and PCD readers, ${fuzz_seconds} s"
if tools/fuzz.sh "$fuzz_seconds"; then
    passed=$((passed + 1))
else
    failed=$((failed + 1))
fi

echo "== libFuzzer: CANopen decoders and the simulated drive, ${fuzz_seconds} s"
if tools/fuzz_can.sh "$fuzz_seconds"; then
    passed=$((passed + 1))
else
    failed=$((failed + 1))
fi

echo "== libFuzzer: qrtpland's LCM message intake, ${fuzz_seconds} s"
if tools/fuzz_lcm.sh "$fuzz_seconds"; then
    passed=$((passed + 1))
else
    failed=$((failed + 1))
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
