#!/bin/bash
# Boots a minimal Linux VM (qemu TCG, Debian's kernel, busybox) and runs one static test binary in
# it, for what the development machines' kernel lacks: SocketCAN (vcan0 up at CAN FD MTU) and a KMS
# display (qemu's bochs-display, /dev/dri/card0).
# Usage: run-in-vm.sh <static-test-binary> [args...]
#   VM_MODULES="..."   kernel modules to load (default: can can-raw vcan; dependencies follow)
#   VM_DISPLAY=1       add a bochs-display PCI device (load the bochs module for /dev/dri/card0)
#   SCREENDUMP=FILE    implies VM_DISPLAY; when the guest prints @@SCREENDUMP@@ on its console, the
#                      host saves what the virtual display shows to FILE (PPM, through qemu's
#                      monitor) and then sends the guest a line on its console ("dumped"), so the
#                      guest can wait for it on stdin instead of guessing a delay
#   EXTRA_BINS="..."   host programs copied to /bin with their shared libraries (can-utils)
#   EXTRA_LIBS="..."   shared libraries copied to their own paths with theirs (LD_PRELOAD ones)
#   EXTRA_FILES="..."  files copied to /data
#   VM_MEM=MiB (256), VM_SMP=N (1)
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
for m in ${VM_MODULES:-can can-raw vcan}; do add_mod "$m"; done
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
for l in ${EXTRA_LIBS:-}; do
  mkdir -p "$R$(dirname "$l")"; cp -L "$l" "$R$l"
  for d in $(ldd "$l" | grep -o '/[^ ]*'); do mkdir -p "$R$(dirname "$d")"; cp -L "$d" "$R$d"; done
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
if [ -e /sys/module/vcan ]; then
  ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set vcan0 up || echo "vcan0 setup failed"
fi
eval "/test $(cat /test.args)"
echo "@@VM_TEST_RC=$?@@"
poweroff -f
INIT
chmod +x "$R/init"
(cd "$R" && find . -print0 | cpio --null -o -H newc --quiet | gzip -1) > "$WORK/initramfs.cpio.gz"
t0=$(date +%s%N)
QEMU_IO=(-serial mon:stdio)
STDIN=/dev/null
[ -n "${SCREENDUMP:-}" ] && VM_DISPLAY=1
[ -n "${VM_DISPLAY:-}" ] && QEMU_IO+=(-device bochs-display)
if [ -n "${SCREENDUMP:-}" ]; then
  # A second monitor on a pipe pair for the host's commands, and the serial console's input on a
  # fifo for the answer; both are opened read-write here so neither side blocks on open.
  mkfifo "$WORK/mon.in" "$WORK/mon.out" "$WORK/serial.in"
  exec 4<>"$WORK/serial.in" 5<>"$WORK/mon.in" 6<>"$WORK/mon.out"
  QEMU_IO+=(-monitor "pipe:$WORK/mon")
  STDIN=$WORK/serial.in
  cat <&6 > "$WORK/monitor.log" &
  MON_READER=$!
fi
: > "$WORK/console.log"
# TCG: KVM is unusable on these machines (PLATFORM-NOTES); -machine pc (microvm hangs under TCG);
# -cpu max because the project builds for x86-64-v3 (AVX2), which the default qemu64 CPU lacks
timeout "${TIMEOUT:-150}" qemu-system-x86_64 -machine pc -accel tcg -cpu max -m "${VM_MEM:-256}" -smp "${VM_SMP:-1}" -nographic -no-reboot \
  -kernel "$KERNEL" -initrd "$WORK/initramfs.cpio.gz" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init" \
  -nic none "${QEMU_IO[@]}" < "$STDIN" > "$WORK/console.log" 2>&1 &
QEMU=$!
if [ -n "${SCREENDUMP:-}" ]; then
  while kill -0 $QEMU 2>/dev/null && ! grep -q '@@SCREENDUMP@@' "$WORK/console.log"; do sleep 0.2; done
  if kill -0 $QEMU 2>/dev/null; then
    rm -f "$SCREENDUMP"
    # The monitor runs commands in order: once "info status" has answered, the dump is written.
    printf 'screendump %s\ninfo status\n' "$SCREENDUMP" >&5
    for _ in $(seq 100); do grep -q 'VM status' "$WORK/monitor.log" && break; sleep 0.1; done
    echo dumped >&4
  fi
fi
wait $QEMU
qrc=$?
[ -n "${MON_READER:-}" ] && kill "$MON_READER" 2>/dev/null
tr -d '\r' < "$WORK/console.log" | grep -v '^$'
echo "host: qemu rc=$qrc, $(( ($(date +%s%N) - t0) / 1000000 )) ms" >&2
[ $qrc = 124 ] && exit 124
rc=$(tr -d '\r' < "$WORK/console.log" | sed -n 's/.*@@VM_TEST_RC=\([0-9]*\)@@.*/\1/p' | tail -n1)
[ -z "$rc" ] && skip "the VM produced no result marker (boot failure)"
exit "$rc"
