#!/usr/bin/env bash
# A truncated or corrupted telemetry log gives a report of what was readable, with a notice that says
# where and why it stops (exit 3); a file that is not a log, an empty one, or a folder without a log
# give a clear error and no report (exit 1). Never a crash (no exit status above 3, nothing on stderr
# but the one error line).
set -euo pipefail
report=$1 session=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
log="$session/telemetry.lcmlog"
size=$(stat -c %s "$log")

run() {  # run NAME EXPECTED_STATUS args...: the status and output are kept in $work/NAME.*
  local name=$1 want=$2; shift 2
  set +e
  "$report" "$@" > "$work/$name.out" 2> "$work/$name.err"
  local rc=$?
  set -e
  if [ "$rc" -ne "$want" ]; then
    echo "$name: exit $rc, expected $want"; cat "$work/$name.out" "$work/$name.err"; exit 1
  fi
}

# Cut in the middle of an event: the first 60 % of the session is reported, with a notice.
head -c $((size * 6 / 10 + 7)) "$log" > "$work/truncated.lcmlog"
run truncated 3 "$session" --log "$work/truncated.lcmlog" --out "$work/truncated"
grep -q "notice: the telemetry log ends inside an event at byte" "$work/truncated.out"
python3 - "$work/truncated/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["source"]["complete"] is False, r["source"]
assert any("truncated" in n for n in r["notices"]), r["notices"]
assert r["source"]["events_read"] > 100, r["source"]
assert r["hands"] and r["hands"][0]["samples"] > 0, "nothing of what was readable is reported"
print("truncated:", r["notices"][0])
PY
grep -q 'truncated: the session was cut off' "$work/truncated/report.html"

# Bytes overwritten over an event's header in the middle: reported up to there, the notice names
# the byte offset. (Bytes changed inside a message's numbers cannot be told from real ones: the
# telemetry log has no checksum, unlike the recording; the README says so.)
cp "$log" "$work/corrupt.lcmlog"
at=$(python3 -c 'import sys; d=open(sys.argv[1],"rb").read(); print(d.index(bytes.fromhex("EDA1DA01"), len(d)//2))' "$log")
printf 'garbage!garbage!garbage!' | dd of="$work/corrupt.lcmlog" bs=1 seek="$at" conv=notrunc status=none
run corrupt 3 "$session" --log "$work/corrupt.lcmlog" --out "$work/corrupt"
grep -q "notice: the telemetry log is corrupted at byte $at " "$work/corrupt.out"
grep -q '"complete":false' "$work/corrupt/report.json"

# Cut before the first score card: a report of the paths, saying there is no score.
head -c 20000 "$log" > "$work/early.lcmlog"
run early 3 "$session" --log "$work/early.lcmlog" --out "$work/early"
grep -q "no score card" "$work/early/report.json"

# Not a log, empty, missing: a clear error, no report.
head -c 5000 /dev/urandom > "$work/noise.lcmlog"
run noise 1 "$session" --log "$work/noise.lcmlog" --out "$work/noise"
grep -q "holds no readable LCM event" "$work/noise.err"
: > "$work/empty.lcmlog"
run empty 1 "$session" --log "$work/empty.lcmlog" --out "$work/empty"
grep -q "holds no readable LCM event" "$work/empty.err"
mkdir "$work/nolog"
run missing 1 "$work/nolog"
grep -q "no telemetry log at" "$work/missing.err"
test ! -e "$work/nolog/report.json" && test ! -e "$work/noise/report.json"
echo "damaged logs: reported with notices, or refused with a reason"
