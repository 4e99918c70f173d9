#!/bin/sh
# The installed rig runs from its install alone: the staged tree (install_tree_test.sh) is mounted
# at another place and the source tree is hidden under an empty tmpfs (a private mount namespace),
# so a binary that still read the source tree or the configured prefix would fail. From an empty
# working folder:
#   - vitreo's embedded default finds the installed cases and the case's expert script, runs,
#     writes its report (the page's assets are in the binary) and replays to the same state;
#   - vitreo-cases lists the installed cases;
#   - vitreo with the unit's own options (vitreo.service's ExecStart, a short duration) on the rig
#     file systemd-tmpfiles put in place: no device is plugged in here, so each one is lost and
#     retried while the session runs, as on a rig switched on before its devices; its system calls
#     and socket families (strace) are within what the unit's sandbox allows.
# Runs in private mount and network namespaces (LCM multicast on a private loopback); exits 77
# (CTest skip) where `unshare` is not permitted.
#   installed_vitreo_test.sh STAGE PREFIX SYSCONFDIR SOURCE_DIR
set -u
stage=$1 prefix=$2 sysconf=$3 src=$4
if [ -z "${VITREO_IN_PRIVATE_NS:-}" ]; then
  if ! unshare -mn true 2>/dev/null; then
    echo "SKIP: 'unshare -mn' is not permitted here (needs root or unprivileged user namespaces)"; exit 77
  fi
  VITREO_IN_PRIVATE_NS=1 exec unshare -mn "$0" "$@"
fi
. "$(dirname "$0")/checks.sh"
tmp=$(mktemp -d)
# The staged tree is bind-mounted under $tmp: unmount it before removing $tmp, never remove through it.
trap 'cd /; umount "$tmp/root" 2>/dev/null; [ -z "$(ls -A "$tmp/root" 2>/dev/null)" ] && rm -rf --one-file-system "$tmp"' EXIT
mkdir "$tmp/root" "$tmp/work"
mount --bind "$stage" "$tmp/root" || exit 1
mount -t tmpfs -o ro tmpfs "$src" || exit 1
check "[ -z \"\$(ls -A '$src')\" ]" "the source tree $src is out of reach (an empty tmpfs over it)"
root=$tmp/root$prefix
data=$root/share/vitreo
cd "$tmp/work" || exit 1
ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo

"$root/bin/vitreo" --help > help.txt 2>&1
check "[ \$? = 0 ] && grep -q '^Usage:' help.txt" "installed vitreo --help"

"$root/bin/vitreo" --duration 0.3 --no-render --unpaced --retina-vertices 500 --texture-size 64 --out "$tmp/default" > default.txt 2>&1
rc=$?
check "[ $rc = 0 ]" "the embedded default runs (exit $rc)"
check "grep -q '^  case file  *$data/scenes/low_membrane_macula.toml ' default.txt" "its case is the installed one"
check "grep -q '^  script  *$data/scenes/scripts/low_membrane_macula.expert.toml' default.txt" "its script is the installed expert script"
check "grep -q 'identical final state and score' default.txt" "the recording replays to the same state"
check "[ -s '$tmp/default/report.html' ] && grep -q 'Chart' '$tmp/default/report.html'" "the report page is written with its chart library"
[ $failures = 0 ] || cat default.txt

"$root/bin/vitreo-cases" list > cases.txt 2>&1
rc=$?
n=$(ls "$data"/scenes/*.toml | grep -vc materials.toml)
check "[ $rc = 0 ] && [ \$(grep -c '\\.toml' cases.txt) -ge $n ] && grep -q 'low_membrane_macula' cases.txt" \
  "vitreo-cases lists the $n installed cases (exit $rc)"
[ $rc = 0 ] || cat cases.txt

# The unit's ExecStart, as systemd would run it, with a short session instead of ten hours.
unit=$root/lib/systemd/system/vitreo.service
script=$(sed -n "s|^ExecStart=/bin/sh -c '\\(.*\\)'\$|\\1|p" "$unit" | sed -e 's/\$\$/$/g' -e 's/%%/%/g' \
  -e "s| $prefix/bin/vitreo | $root/bin/vitreo |" -e "s| --rig $sysconf/| --rig $tmp/root$sysconf/|" -e 's/--duration 36000/--duration 0.3/')
check "[ -n \"\$script\" ]" "the unit's ExecStart read"
# Under strace where it is installed: the unit's sandbox allows the system calls of
# @system-service and the socket families it lists, and everything this session calls must be in
# them (systemd's own lists, expanded by systemd-analyze).
trace=
command -v strace > /dev/null && trace="strace -f -qq -o $tmp/strace.txt"
STATE_DIRECTORY=$tmp/state CACHE_DIRECTORY=$tmp/cache VITREO_LCM_URL='udpm://239.255.76.67:7667?ttl=0' VITREO_OPTIONS='--retina-vertices 500' \
  $trace sh -c "$script" > unit.txt 2>&1
rc=$?
check "[ $rc = 0 ]" "vitreo runs with the unit's options on the installed rig file (exit $rc)"
check "grep -q 'rig $tmp/root$sysconf/vitreo/rig.toml: 3 device(s)' unit.txt" "it read the rig file"
check "grep -q '^  case file  *$data/scenes/' unit.txt" "its cases are the installed ones"
check "[ \$(ls '$tmp/state/sessions' | grep -c '^[0-9]\\{8\\}T[0-9]\\{6\\}Z\$') = 1 ] && [ -s \"\$(ls -d '$tmp/state/sessions'/*)/session.lcmlog\" ]" \
  "its recording is in a session folder named by its start time"
for d in tracker pedals eyeball; do
  check "grep -q '^  device  *$d  *frames 0,' unit.txt && grep -q 'device $d: lost -> reconnecting' unit.txt" "$d absent: lost and retried"
done
[ $failures = 0 ] || cat unit.txt
if [ -n "$trace" ]; then
  expand() {  # expand @GROUP: its system calls, nested groups expanded
    systemd-analyze syscall-filter "$1" | sed -e '1d' -e 's/#.*//' | awk 'NF {print $1}' |
      while read -r x; do case $x in @*) expand "$x" ;; *) echo "$x" ;; esac; done
  }
  filter=$(sed -n 's/^SystemCallFilter=//p' "$unit")
  for g in $filter; do expand "$g"; done | sort -u > allowed.txt
  sed -n 's/^[0-9]*  *\([a-z_0-9]*\)(.*/\1/p' "$tmp/strace.txt" | sort -u > called.txt
  outside=$(comm -23 called.txt allowed.txt | tr '\n' ' ')
  check "[ -s allowed.txt ] && [ -z '$outside' ]" \
    "the session's $(wc -l < called.txt) system calls are all in SystemCallFilter=$filter${outside:+ (not: $outside)}"
  families=$(sed -n 's/^RestrictAddressFamilies=//p' "$unit")
  used=$(sed -n 's/^[0-9]*  *socket(\(AF_[A-Z0-9]*\),.*/\1/p' "$tmp/strace.txt" | sort -u | tr '\n' ' ')
  stray=$(for f in $used; do case " $families " in *" $f "*) ;; *) printf '%s ' "$f" ;; esac; done)
  check "[ -n '$used' ] && [ -z '$stray' ]" "its sockets ($used) are in RestrictAddressFamilies=$families${stray:+ (not: $stray)}"
else
  echo "NOTE strace not installed: the session's system calls were not checked against the unit's filter"
fi

finish
