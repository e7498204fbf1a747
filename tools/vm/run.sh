#!/usr/bin/env bash
# Runs COMMAND where a vcan0 interface exists and prints/returns its exit
# status:
#   - directly, when this host's kernel already has vcan0 (an ordinary Linux
#     machine after `ip link add vcan0 type vcan`),
#   - otherwise inside a throw-away VM: Debian's own kernel (it has CAN as
#     modules; the CI kernel has none), a busybox initramfs that loads the
#     CAN modules, brings vcan0 up and chroots into this host's root shared
#     over 9p, so COMMAND sees the same files, programs and virtualenv,
#   - and exits 77 (CTest's SKIP_RETURN_CODE) with a loud message when
#     neither is possible.
# Usage: tools/vm/run.sh [--vm-only|--prepare] [--] COMMAND [ARG...]
# QRT_VM_DIR (default build/vm beside this repo) caches the kernel and initramfs;
# QRT_VM_QEMU names the emulator (default qemu-system-x86_64), QRT_VM_TIMEOUT
# bounds one run in seconds (default 900).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
vmdir=${QRT_VM_DIR:-$repo/build/vm}
mode=auto
case ${1:-} in
--vm-only) mode=vm; shift ;;
--prepare) mode=prepare; shift ;;
esac
[ "${1:-}" = "--" ] && shift
if [ "$mode" != prepare ] && [ $# -eq 0 ]; then
    echo "usage: $0 [--vm-only|--prepare] [--] COMMAND [ARG...]" >&2
    exit 2
fi

skip() {
    echo "************************************************************" >&2
    echo "SKIPPED: no vcan0 on this host and no VM to make one: $*" >&2
    echo "(create one with: ip link add dev vcan0 type vcan && ip link set up vcan0)" >&2
    echo "************************************************************" >&2
    exit 77
}

host_has_vcan() {
    [ -e /sys/class/net/vcan0 ] &&
        python3 -c 'import socket; s = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW); s.bind(("vcan0",))' 2>/dev/null
}

if [ "$mode" = auto ] && host_has_vcan; then
    echo "vm/run.sh: running on this host's vcan0" >&2
    exec "$@"
fi

qemu=${QRT_VM_QEMU:-qemu-system-x86_64}
command -v "$qemu" >/dev/null || skip "$qemu is not installed"
[ "$(uname -m)" = x86_64 ] || skip "the VM harness is for x86-64 hosts"

# --- once: Debian's kernel and modules, unpacked without installing ------
prepare_kernel() {
    [ -f "$vmdir/kernel/done" ] && return 0
    command -v apt-get >/dev/null || return 1
    local pkg
    # the newest plain (not -rt, not -cloud) 6.1 kernel the archive offers
    pkg=$(apt-cache pkgnames linux-image-6.1.0- 2>/dev/null |
        grep -E '^linux-image-6\.1\.0-[0-9]+-amd64$' | sort -V | tac |
        while read -r p; do
            pol=$(apt-cache policy "$p" 2>/dev/null || true)
            if [[ $pol == *"Candidate: "[0-9]* ]]; then
                echo "$p"
                break
            fi
        done)
    [ -n "$pkg" ] || return 1
    rm -rf "$vmdir/kernel" "$vmdir/deb"
    mkdir -p "$vmdir/deb" "$vmdir/kernel"
    echo "vm/run.sh: fetching $pkg (once)" >&2
    (cd "$vmdir/deb" && apt-get download "$pkg" >&2) || return 1
    dpkg -x "$vmdir"/deb/*.deb "$vmdir/kernel/root" || return 1
    rm -rf "$vmdir/deb"
    echo "$pkg" >"$vmdir/kernel/done"
}

# The modules COMMAND needs and everything they depend on, in load order
# (dependencies first). The package has no modules.dep (depmod runs at
# install time), so the "depends=" field of each module's .modinfo is read.
module_list() { # moddir name...
    local moddir=$1
    shift
    python3 - "$moddir" "$@" <<'EOF'
import lzma, os, re, subprocess, sys
moddir, wanted = sys.argv[1], sys.argv[2:]
def norm(n):
    return n.replace("-", "_")
byname = {}
for d, _, files in os.walk(os.path.join(moddir, "kernel")):
    for f in files:
        m = re.match(r"(.*)\.ko(\.xz|\.zst|\.gz)?$", f)
        if m:
            byname[norm(m.group(1))] = os.path.join(d, f)
def depends(path):
    if path.endswith(".xz"):
        data = lzma.open(path).read()
    elif path.endswith(".zst"):
        data = subprocess.run(["zstd", "-q", "-d", "-c", path], check=True,
                              stdout=subprocess.PIPE).stdout
    else:
        data = open(path, "rb").read()
    m = re.search(rb"\0depends=([^\0]*)\0", data)
    return [norm(x) for x in m.group(1).decode().split(",") if x] if m else []
order, seen = [], set()
def visit(name):
    if name in seen or name not in byname:
        return  # built in, or already queued
    seen.add(name)
    for dep in depends(byname[name]):
        visit(dep)
    order.append(os.path.relpath(byname[name], moddir))
for w in wanted:
    visit(norm(w))
print("\n".join(order))
EOF
}

prepare_initramfs() {
    [ -f "$vmdir/initramfs.cpio.gz" ] && [ "$vmdir/initramfs.cpio.gz" -nt "$here/init" ] &&
        [ "$vmdir/initramfs.cpio.gz" -nt "$0" ] &&
        return 0
    local root=$vmdir/kernel/root kver moddir ird bb
    kver=$(ls "$root/lib/modules" | head -1)
    moddir=$root/lib/modules/$kver
    bb=$(command -v busybox || true)
    # static: it runs before any library is reachable (ldd fails on those)
    [ -n "$bb" ] && ! ldd "$bb" >/dev/null 2>&1 || {
        echo "vm/run.sh: busybox-static is needed" >&2
        return 1
    }
    ird=$vmdir/initramfs.d
    rm -rf "$ird"
    mkdir -p "$ird"/{bin,dev,proc,sys,mnt,modules}
    cp "$bb" "$ird/bin/busybox"
    cp "$here/init" "$ird/init"
    chmod +x "$ird/init"
    local i=0 m dst
    # virtio + 9p to reach the host's files, then can, can-raw, can-dev,
    # vcan in that order (vcan needs can-dev); can-bcm for python-can's
    # periodic sends (the SYNC producer of python-canopen); virtio-rng for
    # the host's entropy: without it the emulated kernel's random pool
    # starts empty and libsodium (qrtpland, PyNaCl) waits in getrandom()
    # until it fills, for minutes under emulation
    for m in $(module_list "$moddir" virtio virtio_ring virtio_pci netfs fscache \
        9pnet 9pnet_virtio 9p can can_raw can_bcm can_dev vcan rng_core \
        virtio_rng); do
        i=$((i + 1))
        dst=$ird/modules/$(printf %02d "$i")-$(basename "$m")
        cp "$moddir/$m" "$dst"
        case $dst in
        *.xz) xz -d "$dst" ;;
        *.zst) zstd -q -d --rm "$dst" ;;
        *.gz) gzip -d "$dst" ;;
        esac
    done
    [ "$i" -gt 0 ] || return 1
    cp "$root/boot/vmlinuz-$kver" "$vmdir/vmlinuz"
    (cd "$ird" && find . | "$bb" cpio -o -H newc 2>/dev/null | gzip -1) \
        >"$vmdir/initramfs.cpio.gz.tmp" || return 1
    mv "$vmdir/initramfs.cpio.gz.tmp" "$vmdir/initramfs.cpio.gz"
}

mkdir -p "$vmdir"
# one preparation at a time when tests run in parallel
exec 9>"$vmdir/.lock"
flock 9
prepare_kernel || skip "could not fetch Debian's kernel with apt-get (offline?)"
prepare_initramfs || skip "could not build the initramfs"
flock -u 9
[ "$mode" = prepare ] && exit 0

# --- one run ------------------------------------------------------------
run=$(mktemp -d "$vmdir/run.XXXXXX")
trap 'rm -rf "$run"' EXIT
{
    echo "#!/bin/sh"
    echo "cd $(printf %q "$PWD")"
    printf 'export PATH=%q\n' "$PATH"
    for v in HOME QRT_TEST_SCALE QRT_SEED VIRTUAL_ENV PYTHONPATH \
        ASAN_OPTIONS UBSAN_OPTIONS TSAN_OPTIONS; do
        [ -n "${!v:-}" ] && printf 'export %s=%q\n' "$v" "${!v}"
    done
    printf '%q ' "$@"
    echo
} >"$run/cmd.sh"
chmod +x "$run/cmd.sh"

start=$(date +%s.%N)
timeout "${QRT_VM_TIMEOUT:-900}" "$qemu" -accel tcg -cpu max -m 1024 -smp 2 \
    -nographic -no-reboot -kernel "$vmdir/vmlinuz" \
    -initrd "$vmdir/initramfs.cpio.gz" \
    -append "console=ttyS0 quiet panic=-1 qrt_run=$run" \
    -virtfs local,path=/,mount_tag=host,security_model=passthrough,multidevs=remap \
    -device virtio-rng-pci \
    </dev/null | tr -d '\r' | sed 's/\x1b\[[0-9;?]*[a-zA-Z]//g' |
    grep -v -E '^\s*$' >&2 || true
end=$(date +%s.%N)
echo "vm/run.sh: VM ran for $(python3 -c "print(f'{$end - $start:.1f}')") s" >&2
if [ ! -f "$run/status" ]; then
    echo "vm/run.sh: the VM wrote no exit status (boot failure or timeout)" >&2
    exit 1
fi
exit "$(cat "$run/status")"
