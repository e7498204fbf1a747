#!/usr/bin/env bash
# Install the core into a scratch prefix and build a separate project
# against it twice: with find_package(qrtplan) and with pkg-config.
set -euo pipefail
build=$1
src=$(cd "$(dirname "$0")" && pwd)/consumer
work=$build/consumer-test
rm -rf "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src" -B "$work/cmake" -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/cmake" >/dev/null
"$work/cmake/consumer"
export PKG_CONFIG_PATH=$work/prefix/lib/pkgconfig
cc -std=c99 "$src/main.c" $(pkg-config --cflags --libs qrtplan) -o "$work/pc"
"$work/pc"
