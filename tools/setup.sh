#!/usr/bin/env bash
# Installs what qrtplan needs on a Debian 12 machine, once: Debian packages
# that are missing and a project virtualenv (.venv) with the Python tools.
# Idempotent and quiet when everything is there; `make demo` and `make test`
# both run it first.
set -euo pipefail
cd "$(dirname "$0")/.."

debs=(build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev valgrind python3-venv
      python3-dev cppcheck clang-format
      # cross builds of the core and their emulated tests
      gcc-arm-linux-gnueabihf libc6-dev-armhf-cross gcc-aarch64-linux-gnu
      libc6-dev-arm64-cross qemu-user-static gcc-arm-none-eabi
      libnewlib-arm-none-eabi qemu-system-arm
      # the daemon (LCM, Eigen), the OMPL comparison, CAN tools and the VM
      g++ liblcm-dev liblcm-bin libeigen3-dev libsodium-dev libompl-dev can-utils iproute2
      qemu-system-x86 busybox-static)
missing=()
for p in "${debs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" ||
        missing+=("$p")
done
if ((${#missing[@]})); then
    echo "setup: installing Debian packages: ${missing[*]}"
    if [ "$(id -u)" != 0 ]; then
        echo "setup: need root to install packages (or install them yourself)" >&2
        exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The venv's Python: prefer the system python3 that python3-venv belongs
# to; fall back to whatever python3 is first on PATH.
py=/usr/bin/python3
[ -x "$py" ] || py=$(command -v python3)
stamp=.venv/.requirements.stamp
if [ ! -x .venv/bin/python ] || ! cmp -s tools/requirements.txt "$stamp"; then
    echo "setup: .venv with $(grep -v '^#' tools/requirements.txt | tr '\n' ' ')"
    [ -x .venv/bin/python ] || "$py" -m venv .venv
    .venv/bin/python -m pip install -q --upgrade pip >/dev/null
    # --upgrade: where the requirements changed (a pin loosened), an old
    # .venv gets what a new machine gets, not the version it already had
    .venv/bin/python -m pip install -q --upgrade -r tools/requirements.txt
    cp tools/requirements.txt "$stamp"
fi
