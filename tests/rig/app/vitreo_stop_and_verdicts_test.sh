#!/usr/bin/env bash
# `vitreo` as an operator and a test engineer meet it (issue 20):
#  - SIGTERM mid-session: the step is finished, the recording completed and synced, the summary
#    printed, exit 0, and the recording replays to the same final state; a second signal forces;
#  - `vitreo --replay` of a whole, a cut, a damaged, an appended and a concatenated recording: each
#    says what it is, with its own exit status (0 complete, 4 truncated, 5 corrupted);
#  - options that a replay would ignore are refused.
set -u
vitreo=${1:?usage: vitreo_stop_and_verdicts_test.sh <vitreo> <scenes>}
scenes=${2:?}
tmp=$(mktemp -d)
rig=
trap '[ -n "$rig" ] && kill -9 $rig 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
# The real-time path (the device reader on the wall clock, its starvation measured): --no-lockstep.
run() { exec "$vitreo" --no-render --no-lockstep --cases "$scenes" --retina-vertices 1500 --cache "$tmp/cache" "$@"; }
# Wait until the session's physics runs (its recording holds more than the header).
wait_running() {
  for _ in $(seq 600); do
    [ -s "$1" ] && [ "$(stat -c %s "$1")" -gt 200000 ] && return 0
    sleep 0.1
  done
  return 1
}

echo "--- SIGTERM mid-session (after the whole process was stopped for 0.3 s: its device reader starves)"
run --duration 60 --out "$tmp/term" >"$tmp/term.out" 2>&1 &
rig=$!
wait_running "$tmp/term/session.lcmlog" || { cat "$tmp/term.out"; echo "FAIL: the session never started"; exit 1; }
kill -STOP $rig; sleep 0.3; kill -CONT $rig; sleep 0.5
kill -TERM $rig
rc=0; wait $rig || rc=$?; rig=
grep -v '^\[' "$tmp/term.out"
check "exit 0 after SIGTERM" '[ $rc -eq 0 ]'
check "the summary says why it ended" 'grep -q "stopped early by SIGTERM" "$tmp/term.out"'
check "the summary is printed in full" 'grep -q "state hash" "$tmp/term.out" && grep -q "score" "$tmp/term.out"'
check "the check replay reached the same state" 'grep -q "identical final state and score" "$tmp/term.out"'
check "the summary says the device reader was starved" 'grep -q "sensor faults    driver thread starved [1-9][0-9]* times (longest [0-9]* ms)" "$tmp/term.out"'
rc=0; "$vitreo" --replay "$tmp/term/session.lcmlog" >"$tmp/replay.out" 2>&1 || rc=$?
cat "$tmp/replay.out"
check "--replay: complete, identical to the recorded final state, exit 0" \
  '[ $rc -eq 0 ] && grep -q "recording   complete" "$tmp/replay.out" && grep -q "identical to the recorded final state (session ended: SIGTERM)" "$tmp/replay.out"'

echo "--- a second signal forces"
run --duration 60 --out "$tmp/force" >"$tmp/force.out" 2>&1 &
rig=$!
wait_running "$tmp/force/session.lcmlog" || { echo "FAIL: the session never started"; exit 1; }
kill -INT $rig
# The second one once the first was seen (two signals sent at once may arrive as one).
for _ in $(seq 100); do grep -q "SIGINT — finishing the step" "$tmp/force.out" && break; sleep 0.02; done
kill -INT $rig
rc=0; wait $rig || rc=$?; rig=
check "two SIGINTs end the process at once (by the signal: exit $rc)" '[ $rc -eq 130 ]'
rc=0; "$vitreo" --replay "$tmp/force/session.lcmlog" >"$tmp/force-replay.out" 2>&1 || rc=$?
check "its recording then reads as truncated (exit 4) or, if the first signal was quick enough, complete (0)" \
  '[ $rc -eq 4 ] && grep -q "truncated at step" "$tmp/force-replay.out" || [ $rc -eq 0 ]'

echo "--- verdicts of damaged copies of a whole recording"
whole="$tmp/term/session.lcmlog"
size=$(stat -c %s "$whole")
head -c $((size * 2 / 3)) "$whole" >"$tmp/cut.lcmlog"
cp "$whole" "$tmp/flipped.lcmlog"
# One byte inverted inside the data of the input event nearest the middle: not in the LCM framing's
# timestamp, which the checksum does not cover (RECORDING.md), and never left unchanged.
at=$(grep -obUa VITREO_REC_INPUT "$whole" | cut -d: -f1 | awk -v m=$((size / 2)) '$1 >= m { print $1 + 16 + 20; exit }')
byte=$(od -An -tu1 -j "$at" -N1 "$whole" | tr -d ' ')
printf "\\$(printf '%03o' $((byte ^ 255)))" | dd of="$tmp/flipped.lcmlog" bs=1 seek="$at" conv=notrunc 2>/dev/null
{ cat "$whole"; head -c 500 /dev/urandom; } >"$tmp/appended.lcmlog"
cat "$whole" "$whole" >"$tmp/twice.lcmlog"
verdict() {  # verdict <file> <exit> <pattern>
  local rc=0 want=$2 pattern=$3
  "$vitreo" --replay "$1" >"$tmp/v.out" 2>&1 || rc=$?
  sed -n 2p "$tmp/v.out"
  check "$(basename "$1"): exit $want and '$pattern'" '[ $rc -eq $want ] && grep -q "$pattern" "$tmp/v.out"'
}
verdict "$tmp/cut.lcmlog" 4 "truncated at step [0-9]* — replayed up to there"
verdict "$tmp/flipped.lcmlog" 5 "corrupted at byte [0-9]* — replayed up to there"
verdict "$tmp/appended.lcmlog" 5 "corrupted at byte $size — .*500 bytes after the end"
verdict "$tmp/twice.lcmlog" 5 "corrupted at byte $size — .*another recording starts"
head -c 100 "$whole" >"$tmp/stub.lcmlog"
rc=0; "$vitreo" --replay "$tmp/stub.lcmlog" >"$tmp/stub.out" 2>&1 || rc=$?
check "a file cut inside its header cannot be replayed at all (exit 1, one line)" \
  '[ $rc -eq 1 ] && [ "$(wc -l < "$tmp/stub.out")" -eq 1 ]'

echo "--- options a replay would ignore are refused"
for opt in "--case $scenes/low_membrane_macula.toml" "--duration 3" "--retina-vertices 800" "--serial tracker=/dev/null"; do
  rc=0; "$vitreo" --replay "$whole" $opt >"$tmp/o.out" 2>"$tmp/o.err" || rc=$?
  check "--replay with $opt: exit 2, one line" '[ $rc -eq 2 ] && [ "$(wc -l < "$tmp/o.err")" -eq 1 ] && [ ! -s "$tmp/o.out" ]'
done
exit $fail
