#!/usr/bin/env bash
# The Python package from a clean tree into a fresh virtualenv, then its
# tests (tests/pkg/test_package.py) against the CLI:
#   tests/pkg/fresh_venv.sh SOURCE_DIR QRTPLAN_BIN [pytest args]
# The clean tree is SOURCE_DIR's tracked files (git ls-files) as they are in
# its working tree: no build/, no .venv, nothing untracked. numpy, pytest
# and the build backend come from PyPI. Prints how long `pip install .`
# took. Needs python3 with venv; the build needs cmake, a C compiler and
# lcm-gen (tools/setup.sh installs them).
set -euo pipefail
src=$(cd "$1" && pwd)
bin=$2
shift 2
tmp=$(mktemp -d "${TMPDIR:-/tmp}/qrtplan-pkg.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/src"
git -C "$src" ls-files -z | (cd "$src" && xargs -0 tar -cf - --no-recursion) |
    tar -xf - -C "$tmp/src"
py=/usr/bin/python3
[ -x "$py" ] || py=$(command -v python3)
"$py" -m venv "$tmp/venv"
"$tmp/venv/bin/python" -m pip install -q --disable-pip-version-check pytest
t0=$EPOCHREALTIME
# one build job: the machine may be shared (CI runs other tests beside it)
CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-1} \
    "$tmp/venv/bin/python" -m pip install -q --disable-pip-version-check "$tmp/src[lcm]"
t1=$EPOCHREALTIME
awk -v a="$t0" -v b="$t1" 'BEGIN { printf "fresh_venv: pip install . took %.1f s\n", b - a }'
cd "$tmp"
QRT_SOURCE_DIR="$tmp/src" QRTPLAN_BIN="$bin" \
    "$tmp/venv/bin/python" -m pytest -q -p no:cacheprovider \
    "$tmp/src/tests/pkg" "$@"
