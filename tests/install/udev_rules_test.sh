#!/bin/sh
# The installed udev rules, run by udev itself: `udevadm test` (systemd-udevd's rule engine, with
# the system's own rules beside ours) on the rig's devices as umockdev describes them in sysfs
# (rig_devices.umockdev: the tracker and the pedals on USB-CDC, the eyeball fixture's vendor-class
# USB interface, someone else's FTDI adapter). udev 252 has no `udevadm verify` (253 has), and
# `udevadm test` reads only the system's rules folders, so the test runs in a private mount
# namespace where the staged rules folder is /etc/udev/rules.d, the staged group vitreo (made by
# systemd-sysusers) is in /etc/group, and /dev and /run/udev are private copies udev may write
# its links into. Checks: udev reads our file without a complaint; each device gets its
# /dev/vitreo names, the group vitreo and mode 0660; the stranger gets none of them; every
# serial: path of the installed rig file is one of the names udev made.
#   udev_rules_test.sh STAGE PREFIX SYSCONFDIR
set -u
stage=$1 prefix=$2 sysconf=$3
here=$(cd "$(dirname "$0")" && pwd)
rules=$stage$prefix/lib/udev/rules.d
if [ -z "${VITREO_IN_PRIVATE_NS:-}" ]; then
  for t in udevadm umockdev-run unshare; do
    command -v $t > /dev/null || { echo "SKIP: $t not installed"; exit 77; }
  done
  unshare -m true 2>/dev/null || { echo "SKIP: 'unshare -m' is not permitted here (needs root)"; exit 77; }
  VITREO_IN_PRIVATE_NS=1 exec unshare -m "$0" "$@"
fi
. "$(dirname "$0")/checks.sh"
tmp=$(mktemp -d)
# (All of it is private to this namespace; only the empty $tmp folder is left to remove.)
trap 'cd /; for m in /dev/pts /dev /run/udev /etc/udev/rules.d /etc/udev/rules.d /etc/group "$tmp"; do umount "$m" 2>/dev/null; done; rmdir "$tmp"' EXIT

# The private namespace: /run/udev a tmpfs, /dev an overlay (links land in its upper layer, not in
# the machine's /dev), the staged rules and group.
mount -t tmpfs tmpfs "$tmp" || exit 1
mkdir -p "$tmp/ov/up" "$tmp/ov/work" "$tmp/pts" /run/udev
mount --bind /dev/pts "$tmp/pts"
mount -t overlay overlay -o "lowerdir=/dev,upperdir=$tmp/ov/up,workdir=$tmp/ov/work" /dev ||
  { echo "SKIP: no overlayfs for a private /dev"; exit 77; }
mount --move "$tmp/pts" /dev/pts
mount -t tmpfs tmpfs /run/udev
mkdir -p /etc/udev/rules.d
mount --bind "$rules" /etc/udev/rules.d
gid=$(sed -n 's/^vitreo:x:\([0-9]*\):.*/\1/p' "$stage/etc/group")
check "[ -n '$gid' ]" "the staged group vitreo (systemd-sysusers, install_tree_test.sh) has gid ${gid:-none}"
if ! grep -q '^vitreo:' /etc/group; then
  { cat /etc/group; grep '^vitreo:' "$stage/etc/group"; } > "$tmp/group"
  mount --bind "$tmp/group" /etc/group
fi
dialout=$(getent group dialout | cut -d: -f3)

grep -v '^#' "$here/rig_devices.umockdev" > "$tmp/devices.umockdev"
usb=/sys/devices/pci0000:00/0000:00:14.0/usb1
umockdev-run -d "$tmp/devices.umockdev" -- sh -c "
  udevadm test -a add $usb/1-1/1-1:1.0/tty/ttyACM0 > $tmp/tracker-tty.log 2>&1
  udevadm test -a add $usb/1-1 > $tmp/tracker-usb.log 2>&1
  udevadm test -a add $usb/1-2/1-2:1.0/tty/ttyACM1 > $tmp/pedals-tty.log 2>&1
  udevadm test -a add $usb/1-3 > $tmp/eyeball-usb.log 2>&1
  udevadm test -a add $usb/1-4/1-4:1.0/ttyUSB0/tty/ttyUSB0 > $tmp/ftdi-tty.log 2>&1
  udevadm test -a add $usb/1-4 > $tmp/ftdi-usb.log 2>&1"
check "[ \$? = 0 ]" "udevadm test ran on every device"

check "grep -q 'Reading rules file: /etc/udev/rules.d/70-vitreo.rules' $tmp/tracker-tty.log" "udev read 70-vitreo.rules"
complaints=$(grep -h '70-vitreo.rules:[0-9]* ' "$tmp"/*.log | grep -v -E ' (GROUP|MODE|LINK|ENV|GOTO) ' | sort -u)
check "[ -z \"\$complaints\" ]" "udev has nothing to say about 70-vitreo.rules${complaints:+: $complaints}"

last() {  # last LOG KEY: the value of the last GROUP/MODE udev assigned to the device
  grep -E "^[^ ]+: [^ ]+:[0-9]+ $2 " "$1" | tail -1 | awk '{print $NF}'
}
link() { readlink "/dev/vitreo/$1" 2>/dev/null; }
for kind in tracker:1001:ttyACM0 pedals:2001:ttyACM1; do
  k=${kind%%:*} rest=${kind#*:}; serial=${rest%%:*} tty=${rest#*:}
  log=$tmp/$k-tty.log
  check "[ \"\$(link $k)\" = ../$tty ]" "/dev/vitreo/$k → $tty ($(link $k))"
  check "[ \"\$(link $k-$serial)\" = ../$tty ]" "/dev/vitreo/$k-$serial → $tty"
  check "[ \"\$(last $log GROUP)\" = '$gid' ] && [ \"\$(last $log MODE)\" = 0660 ]" \
    "$tty: group vitreo, mode 0660 (udev: group $(last "$log" GROUP), mode $(last "$log" MODE))"
done
check "[ \"\$(link usb/tracker-1001)\" = ../../bus/usb/001/002 ] && [ \"\$(link usb/tracker)\" = ../../bus/usb/001/002 ]" \
  "/dev/vitreo/usb/tracker and usb/tracker-1001 → the tracker's USB device node"
check "[ \"\$(link usb/eyeball-3001)\" = ../../bus/usb/001/004 ]" "/dev/vitreo/usb/eyeball-3001 → the eyeball fixture's USB device node"
for d in tracker-usb eyeball-usb; do
  check "[ \"\$(last $tmp/$d.log GROUP)\" = '$gid' ] && [ \"\$(last $tmp/$d.log MODE)\" = 0660 ]" "$d: group vitreo, mode 0660 (libusb opens it)"
done
strangers=$(ls -l /dev/vitreo /dev/vitreo/usb 2>/dev/null | grep -E 'ttyUSB0|001/005')
check "[ -z \"\$strangers\" ] && ! grep -q 'LINK .vitreo' $tmp/ftdi-tty.log $tmp/ftdi-usb.log" "the FTDI adapter gets no /dev/vitreo name"
check "[ \"\$(last $tmp/ftdi-tty.log GROUP)\" = '$dialout' ] && [ \"\$(last $tmp/ftdi-usb.log GROUP)\" != '$gid' ]" \
  "the FTDI adapter keeps its group (tty: $(last "$tmp/ftdi-tty.log" GROUP), dialout is $dialout)"

# The installed rig file names its serial devices by these names.
for p in $(sed -n 's|^uri = "serial:\(/dev/vitreo/[^"?]*\).*|\1|p' "$stage$sysconf/vitreo/rig.toml"); do
  check "[ -L '$p' ]" "the rig file's $p is a name udev gives"
done
check "grep -q '^uri = \"serial:/dev/vitreo/' '$stage$sysconf/vitreo/rig.toml'" "the installed rig file names serial devices under /dev/vitreo"

# The check can fail: a misspelt key in a copy of the rules is reported, and its names are not made.
mkdir "$tmp/broken"
sed 's/SYMLINK+="vitreo\/$env{VITREO_KIND}"$/SYMLNK+="vitreo\/$env{VITREO_KIND}"/' "$rules/70-vitreo.rules" > "$tmp/broken/70-vitreo.rules"
mount --bind "$tmp/broken" /etc/udev/rules.d
umockdev-run -d "$tmp/devices.umockdev" -- udevadm test -a add $usb/1-2/1-2:1.0/tty/ttyACM1 > "$tmp/broken.log" 2>&1
check "grep -q \"70-vitreo.rules:[0-9]* Invalid key 'SYMLNK'\" $tmp/broken.log && ! grep -q \"LINK 'vitreo/pedals'\" $tmp/broken.log" \
  "a copy with a misspelt key: udev reports it and makes no /dev/vitreo/pedals"

[ $failures = 0 ] || { echo "--- udev's log for the tracker's tty:"; cat "$tmp/tracker-tty.log"; }
finish
