#!/usr/bin/env bash
# vitreo-devices end to end over a pty: --help, one-line errors on bad input, a simulated pedal
# device identified and watched by a second instance of the tool.
set -u
B=${1:?usage: vitreo_devices_test.sh <vitreo-devices>}
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }
dir=$(mktemp -d); trap 'kill $sim 2>/dev/null; rm -rf "$dir"' EXIT

check "--help exits 0 and names the subcommands" '"$B" --help > "$dir/help" && grep -q simulate "$dir/help" && grep -q identify "$dir/help"'
for bad in "" "frobnicate" "watch --usb toaster" "identify --serial /x --usb tracker" "watch --can vcan0 --node 300" \
            "simulate --script /nonexistent"; do
  "$B" $bad > "$dir/out" 2> "$dir/err"; rc=$?
  check "bad input '$bad' -> non-zero exit with one line" '[ $rc -ne 0 ] && [ "$(wc -l < "$dir/err")" -eq 1 ] && [ ! -s "$dir/out" ]'
done
"$B" identify --serial "$dir/none" --timeout-s 0.3 > /dev/null 2> "$dir/err"; rc=$?
check "identify on a missing port fails with a reason" '[ $rc -ne 0 ] && grep -q "cannot open" "$dir/err"'

"$B" simulate --device pedals --link "$dir/tty" --duration-s 6 > "$dir/sim.out" 2>&1 & sim=$!
for _ in $(seq 50); do [ -e "$dir/tty" ] && break; sleep 0.05; done
check "identify the simulated pedals" '"$B" identify --serial "$dir/tty" 2>/dev/null | grep -q "^pedals serial 2001 .*protocol 1.1"'
check "identify them by their URI" '"$B" identify --device "serial:$dir/tty" 2>/dev/null | grep -q "^pedals serial 2001 "'
"$B" identify --device "serial:$dir/tty?speed=1" > /dev/null 2> "$dir/err"; rc=$?
check "a bad URI is refused with the reason" '[ $rc -ne 0 ] && [ "$(wc -l < "$dir/err")" -eq 1 ] && grep -q "unknown parameter" "$dir/err"'
"$B" watch --serial "$dir/tty" --duration-s 1.5 --print-hz 5 > "$dir/watch" 2> "$dir/watch.log"
check "watch shows decoded pedal samples" 'grep -q "^pedal t_dev=" "$dir/watch"'
check "watch shows link statistics while streaming" 'grep -q "^\[streaming\] .*delivered=[1-9]" "$dir/watch"'
check "watch saw no rejected frames" '! grep -E "crc=[1-9]|framing=[1-9]" "$dir/watch"'
"$B" dump --serial "$dir/tty" --duration-s 0.5 > "$dir/dump" 2>/dev/null
check "dump prints raw frames" 'grep -qE "^rx +[0-9]+ B: ([0-9a-f]{2} )+" "$dir/dump"'
exit $fail
