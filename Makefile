# Thin front over CMake. `make help` lists the targets.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
GEN := $(shell command -v ninja >/dev/null 2>&1 && echo "-G Ninja")

.PHONY: all setup check test demo bench cross clean format help

all:
	@cmake -S . -B $(BUILD) $(GEN) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

setup:
	@tools/setup.sh

# the fast tier: the release build's tests but the VM ones
check: setup
	@tools/run_tests.sh --fast

test: setup
	@tools/run_tests.sh

demo: setup all
	@tools/demo.sh

bench: setup all
	@tools/bench.sh

# the core for ARM boards: build-<target>/lib/libqrtplan.a
cross: setup
	@for t in arm-linux-gnueabihf aarch64-linux-gnu; do \
	  cmake -S . -B build-$$t $(GEN) -DQRT_PYTHON_TESTS=OFF \
	    -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/$$t.cmake >/dev/null && \
	  cmake --build build-$$t -j $(JOBS) || exit 1; done
	@cmake -S . -B build-cortex-m7 $(GEN) -DQRT_CORE_ONLY=ON \
	  -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/cortex-m7.cmake >/dev/null
	@cmake --build build-cortex-m7 -j $(JOBS)

format:
	@clang-format -i $$(git ls-files '*.c' '*.h' '*.cpp' '*.hpp')

clean:
	rm -rf build build-asan build-fuzz build-arm-linux-gnueabihf \
	  build-aarch64-linux-gnu build-cortex-m7

help:
	@echo "make        build everything into build/ (programs in build/bin/)"
	@echo "make demo   install what is missing, plan the paper's scenes, draw them (build/demo/)"
	@echo "make check  install what is missing, build, run the release tests but the VM ones (minutes)"
	@echo "make test   install what is missing, run every test: unit, Python, VM, sanitizers, cross, fuzz"
	@echo "make bench  the paper's Table 5 and larger clouds, timed (build/bench/)"
	@echo "make cross  the core for armhf, aarch64 (with tests) and Cortex-M7"
	@echo "make format clang-format all C sources"
	@echo "make clean  remove the build directories"
