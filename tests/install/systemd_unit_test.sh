#!/bin/sh
# The installed vitreo.service, checked by systemd itself: `systemd-analyze verify` (unit syntax,
# every key and value understood, the ExecStart command executable) must pass without a word, and
# the same unit with one misspelt key and one bad value must not — so the check can fail. The
# command the unit runs is the installed vitreo, and that binary is in the staged tree (that vitreo
# runs a session with the unit's options: installed_vitreo_test.sh).
#   systemd_unit_test.sh STAGE PREFIX
set -u
stage=$1 prefix=$2
unit=$stage$prefix/lib/systemd/system/vitreo.service
. "$(dirname "$0")/checks.sh"
command -v systemd-analyze > /dev/null || { echo "SKIP: systemd-analyze not installed (package systemd)"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# verify loads the unit from its path; it checks that /bin/sh (the ExecStart) is executable here.
out=$(systemd-analyze verify "$unit" 2>&1); rc=$?
printf '%s\n' "$out" | sed 's/^/  verify: /'
check "[ $rc = 0 ]" "systemd-analyze verify exits 0 (exit $rc)"
check "[ -z \"\$(printf '%s' \"\$out\" | grep -F vitreo.service)\" ]" "systemd-analyze verify says nothing about vitreo.service"

# A negative control: systemd warns about these (exit 0 — the warning is the verdict).
sed -e 's/^RestartSec=/RestartSecs=/' -e 's/^DeviceAllow=char-drm rw$/DeviceAllow=char-drm rwz/' "$unit" > "$tmp/vitreo.service"
bad=$(systemd-analyze verify "$tmp/vitreo.service" 2>&1)
check "printf '%s' \"\$bad\" | grep -q \"Unknown key 'RestartSecs'\"" "a misspelt key is reported"
check "printf '%s' \"\$bad\" | grep -q \"Invalid device rights 'rwz'\"" "a bad value is reported"

# What it runs: the installed vitreo on the rig file, as the user vitreo, restarted on failure.
exec_line=$(grep '^ExecStart=' "$unit")
bin=$(printf '%s' "$exec_line" | sed -n "s|.*exec \\($prefix/bin/vitreo\\) .*|\\1|p")
check "[ -n '$bin' ] && [ -x '$stage$bin' ]" "ExecStart runs $prefix/bin/vitreo, installed at $stage$bin"
for key in 'User=vitreo' 'Group=vitreo' 'Restart=on-failure' 'StateDirectory=vitreo' 'NoNewPrivileges=yes' 'DevicePolicy=closed'; do
  check "grep -qx '$key' '$unit'" "$key"
done
finish
