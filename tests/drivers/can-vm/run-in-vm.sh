#!/bin/bash
# Boots a minimal Linux VM (qemu TCG, Debian's kernel, busybox) with vcan0 up at CAN FD MTU and runs
# one static test binary in it; the host kernel of the development machines has no CAN at all.
# Usage: run-in-vm.sh <static-test-binary> [args...]
#   EXTRA_BINS="..."   host programs copied to /bin with their shared libraries (can-utils)
#   EXTRA_FILES="..."  files copied to /data
# Exit: the test's exit code; 124 timeout; 125 = could not run the VM (CTest SKIP_RETURN_CODE),
# with the reason on stderr. Our own version of shared/recipes/can-vm/run-can-vm.sh.
set -uo pipefail
skip() { echo "SKIP: $*" >&2; exit 125; }
TEST_BIN=${1:?usage: run-in-vm.sh <static-test-binary> [args...]}; shift
command -v qemu-system-x86_64 >/dev/null || skip "qemu-system-x86_64 not installed (apt-get install qemu-system-x86)"
[ -x /bin/busybox ] || skip "busybox-static not installed"
command -v cpio >/dev/null || skip "cpio not installed"
KVER=${KVER:-$(ls /lib/modules 2>/dev/null | sort -V | tail -n1)}
KERNEL=${KERNEL:-/boot/vmlinuz-$KVER}
[ -n "$KVER" ] && [ -r "$KERNEL" ] || skip "no readable kernel image in /boot (apt-get install linux-image-amd64)"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/vitreo-canvm.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
R=$WORK/root
mkdir -p "$R"/{bin,sbin,proc,sys,dev,tmp,data,lib/modules}

declare -A seen=(); order=()
add_mod() {
  local m=$1 d
  [[ -n ${seen[$m]:-} ]] && return; seen[$m]=1
  for d in $(modinfo -k "$KVER" -F depends "$m" 2>/dev/null | tr ',' ' '); do add_mod "$d"; done
  order+=("$m")
}
for m in can can-raw vcan; do add_mod "$m"; done
for m in "${order[@]}"; do
  f=$(modinfo -k "$KVER" -F filename "$m" 2>/dev/null) || skip "kernel module $m not found for $KVER"
  case $f in
    *.ko) cp "$f" "$R/lib/modules/$m.ko" ;;
    *.ko.xz) xz -dc "$f" > "$R/lib/modules/$m.ko" ;;
    *.ko.zst) zstd -qdc "$f" > "$R/lib/modules/$m.ko" ;;
  esac
done
printf '%s\n' "${order[@]}" > "$R/modules.order"
cp /bin/busybox "$R/bin/busybox"
for b in ${EXTRA_BINS:-}; do
  cp "$b" "$R/bin/"
  for l in $(ldd "$b" | grep -o '/[^ ]*'); do mkdir -p "$R$(dirname "$l")"; cp -L "$l" "$R$l"; done
done
for f in ${EXTRA_FILES:-}; do cp "$f" "$R/data/"; done
cp "$TEST_BIN" "$R/test"
: > "$R/test.args"; [ $# -gt 0 ] && printf "%q " "$@" > "$R/test.args"
cat > "$R/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin:/sbin
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for m in $(cat /modules.order); do insmod /lib/modules/$m.ko || echo "insmod $m failed"; done
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set vcan0 up || echo "vcan0 setup failed"
eval "/test $(cat /test.args)"
echo "@@VM_TEST_RC=$?@@"
poweroff -f
INIT
chmod +x "$R/init"
(cd "$R" && find . -print0 | cpio --null -o -H newc --quiet | gzip -1) > "$WORK/initramfs.cpio.gz"
t0=$(date +%s%N)
# TCG: KVM is unusable on these machines (PLATFORM-NOTES); -machine pc (microvm hangs under TCG);
# -cpu max because the project builds for x86-64-v3 (AVX2), which the default qemu64 CPU lacks
timeout "${TIMEOUT:-150}" qemu-system-x86_64 -machine pc -accel tcg -cpu max -m 256 -smp 1 -nographic -no-reboot \
  -kernel "$KERNEL" -initrd "$WORK/initramfs.cpio.gz" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init" \
  -nic none -serial mon:stdio < /dev/null > "$WORK/console.log" 2>&1
qrc=$?
tr -d '\r' < "$WORK/console.log" | grep -v '^$'
echo "host: qemu rc=$qrc, $(( ($(date +%s%N) - t0) / 1000000 )) ms" >&2
[ $qrc = 124 ] && exit 124
rc=$(tr -d '\r' < "$WORK/console.log" | sed -n 's/.*@@VM_TEST_RC=\([0-9]*\)@@.*/\1/p' | tail -n1)
[ -z "$rc" ] && skip "the VM produced no result marker (boot failure)"
exit "$rc"
