#!/bin/sh
# `cmake --install` into a DESTDIR staging tree, then what a package's installation does next:
# systemd-sysusers creates the user and group, systemd-tmpfiles puts the rig file in place — both
# real tools, run against the staging tree (--root). Checks every file the layout promises
# (cmake/VitreoInstall.cmake) is there, every case and script of the source tree is installed, and
# nothing is left unconfigured. The other install tests use the tree this leaves (CTest fixture).
#   install_tree_test.sh BUILD_DIR SOURCE_DIR STAGE PREFIX SYSCONFDIR
set -u
build=$1 src=$2 stage=$3 prefix=$4 sysconf=$5
. "$(dirname "$0")/checks.sh"

rm -rf "$stage"
mkdir -p "$(dirname "$stage")"
DESTDIR="$stage" cmake --install "$build" > "$stage.log" 2>&1
rc=$?
check "[ $rc = 0 ]" "cmake --install into DESTDIR $stage (exit $rc; log $stage.log)"
[ $rc = 0 ] || { cat "$stage.log"; exit 1; }
root=$stage$prefix

for b in vitreo vitreo-cmd vitreo-report vitreo-cases vitreo-devices vitreo-calibrate; do
  check "[ -f '$root/bin/$b' ] && [ -x '$root/bin/$b' ]" "bin/$b installed, executable"
done
for f in lib/systemd/system/vitreo.service lib/udev/rules.d/70-vitreo.rules lib/sysusers.d/vitreo.conf \
         lib/tmpfiles.d/vitreo.conf share/vitreo/config/installed-rig.toml share/vitreo/scenes/materials.toml \
         share/doc/vitreo/README.md share/doc/vitreo/rig/system/README.md share/doc/vitreo/firmware-protocol/PROTOCOL.md; do
  check "[ -s '$root/$f' ]" "$f installed"
done
# Every case, script and rig file of the source tree, byte for byte (listed from the source tree,
# not from the install rules).
missing=0
for f in "$src"/scenes/*.toml "$src"/scenes/scripts/*.toml "$src"/rig/config/*.toml "$src"/rig/config/sim/*.sim; do
  rel=${f#"$src"/}
  case $rel in
    scenes/*) dest=$root/share/vitreo/$rel ;;
    rig/config/*) dest=$root/share/vitreo/config/${rel#rig/config/} ;;
  esac
  cmp -s "$f" "$dest" || { echo "  not installed (or differs): $rel → $dest"; missing=$((missing + 1)); }
done
n=$(ls "$src"/scenes/*.toml "$src"/scenes/scripts/*.toml | wc -l)
check "[ $missing = 0 ]" "all $n cases and scripts and every rig file installed under share/vitreo ($missing missing)"
check "! grep -rl '@[A-Z_]*@' '$root/lib'" "no @VARIABLE@ left unconfigured in the unit or the snippets"
check "grep -q '^ExecStart=.* $prefix/bin/vitreo --rig $sysconf/vitreo/rig.toml ' '$root/lib/systemd/system/vitreo.service'" \
  "the unit runs the installed vitreo on $sysconf/vitreo/rig.toml"

# What a package's installation runs next, against the staging tree.
mkdir -p "$stage/etc"
out=$(systemd-sysusers --root="$stage" 2>&1); rc=$?
check "[ $rc = 0 ]" "systemd-sysusers --root (exit $rc): $out"
check "grep -q '^vitreo:x:[0-9]*:[0-9]*:.*:/usr/sbin/nologin$' '$stage/etc/passwd'" "user vitreo created (a system user, no login shell)"
check "grep -q '^vitreo:x:[0-9]*:' '$stage/etc/group'" "group vitreo created"
for g in $(sed -n 's/^SupplementaryGroups=//p' "$root/lib/systemd/system/vitreo.service"); do
  check "grep -q '^$g:x:' '$stage/etc/group'" "group $g, a supplementary group of the unit, is made where it is missing"
done
out=$(systemd-tmpfiles --root="$stage" --create 2>&1); rc=$?
check "[ $rc = 0 ]" "systemd-tmpfiles --root --create (exit $rc)${out:+: $out}"
check "cmp -s '$stage$sysconf/vitreo/rig.toml' '$root/share/vitreo/config/installed-rig.toml'" \
  "the rig file $sysconf/vitreo/rig.toml is the installed example"
# An existing rig file, edited for this rig, is never overwritten.
echo "# edited" >> "$stage$sysconf/vitreo/rig.toml"
systemd-tmpfiles --root="$stage" --create > /dev/null 2>&1
check "tail -1 '$stage$sysconf/vitreo/rig.toml' | grep -q '^# edited$'" "a second tmpfiles run keeps the edited rig file"
sed -i '$d' "$stage$sysconf/vitreo/rig.toml"

finish
