#!/usr/bin/env bash
# A technician's day, end to end (label calibration): vitreo-calibrate the simulated rig with injected
# imperfections, run vitreo with the calibration (its summary names it; the recording carries it and
# replays to the same final state), and see the rig refuse the file for another tracker and a
# malformed one with its file:line.
set -u
CAL=${1:?usage: calibrate_then_run_test.sh <vitreo-calibrate> <vitreo> <source dir>}
VITREO=${2:?}; SRC=${3:?}
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
rig="$SRC/rig/config/sim-calibration.toml"

"$CAL" --rig "$rig" --out "$dir/cal.toml" --non-interactive --save-motion "$dir/motion" > "$dir/cal.out" 2>&1; rc=$?
check "vitreo-calibrate passes and writes the file" '[ $rc -eq 0 ] && grep -q "result: PASS" "$dir/cal.out" && grep -q "^\[calibration\]" "$dir/cal.toml"'
check "it saved the scripted technician's motion" 'grep -q "^tip_offset 0.8 -0.5 14.0" "$dir/motion/tracker-0.sim" && grep -c "^key " "$dir/motion/tracker-0.sim" | grep -qv "^1$"'
"$CAL" --rig "$rig" --out "$dir/x.toml" > /dev/null 2> "$dir/err"; rc=$?
check "without --non-interactive it says what is missing" '[ $rc -eq 2 ] && grep -q "not implemented yet" "$dir/err" && [ ! -e "$dir/x.toml" ]'

"$VITREO" --rig "$rig" --calibration "$dir/cal.toml" --duration 0.2 --no-render --out "$dir/run" > "$dir/run.out" 2>&1; rc=$?
check "the rig runs with it and its summary names it" '[ $rc -eq 0 ] && grep -q "^  calibration      $dir/cal.toml (.*vitreo-calibrate" "$dir/run.out"'
check "the rig pins the calibrated units" 'grep -q "tracker-0 must announce serial 1001" "$dir/run.out"'
check "the recording carries it and replays to the same state" 'grep -q "identical final state" "$dir/run.out" && grep -aq "^calibration [0-9]" "$dir/run/session.lcmlog"'

sed 's/^id = 1$/id = 1\nserial = 4242/' "$rig" > "$dir/other-rig.toml"
cp -r "$SRC/rig/config/sim" "$dir/sim"
"$VITREO" --rig "$dir/other-rig.toml" --calibration "$dir/cal.toml" --duration 0.2 --no-render --out "$dir/run2" > "$dir/o.err" 2>&1; rc=$?
check "a calibration for another tracker is refused with the serials" '[ $rc -ne 0 ] && grep -q "made for tracker-0 serial 1001, this rig.s tracker-0 is serial 4242" "$dir/o.err"'

sed 's/^fre_mm = /fre_mm = "x" # /' "$dir/cal.toml" > "$dir/bad.toml"
"$VITREO" --rig "$rig" --calibration "$dir/bad.toml" --duration 0.2 --no-render --out "$dir/run3" > "$dir/b.err" 2>&1; rc=$?
line=$(grep -n "^fre_mm" "$dir/bad.toml" | cut -d: -f1)
check "a malformed calibration is refused with file:line: key" '[ $rc -ne 0 ] && grep -q "bad.toml:$line: registration.fre_mm: must be a number" "$dir/b.err"'
exit $fail
