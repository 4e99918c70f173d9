#!/usr/bin/env bash
# A session folder without its telemetry log but with its recording: vitreo-report regenerates the log
# by replaying the recording and reports from it — number for number the report of the live log, but
# for what a recording does not hold (the device statuses, the log's own size and times), with a
# notice that says so (exit 3). A truncated recording gives the report of what it vouches for, with
# its verdict in the notice; a folder with neither log nor recording gives no report (exit 1).
set -euo pipefail
report=$1 session=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

run() {  # run NAME EXPECTED_STATUS args...
  local name=$1 want=$2; shift 2
  set +e
  "$report" "$@" > "$work/$name.out" 2> "$work/$name.err"
  local rc=$?
  set -e
  if [ "$rc" -ne "$want" ]; then
    echo "$name: exit $rc, expected $want"; cat "$work/$name.out" "$work/$name.err"; exit 1
  fi
}

# The live session's folder without its log (frames, recording, trainee kept).
mkdir -p "$work/s"
cp -r "$session/frames" "$session/session.lcmlog" "$session/trainee.txt" "$work/s/"
run regenerated 3 "$work/s" --generated "2026-01-01 00:00:00 UTC"
grep -q "regenerating it from the recording" "$work/regenerated.out"
grep -q "notice: the telemetry log was regenerated from the recording (complete" "$work/regenerated.out"
test -s "$work/s/telemetry.lcmlog" && test ! -e "$work/s/telemetry.lcmlog.regenerating"
python3 - "$session/report.json" "$work/s/report.json" <<'PY'
import json, sys
live, regen = (json.load(open(p)) for p in sys.argv[1:3])
# What a recording cannot give back: the drivers' device statuses, the log's own size and timestamps.
allowed = {"/case/started_utime_us", "/source/bytes/value", "/source/events_read", "/devices", "/notices"}
diffs = []
def walk(a, b, path=""):
    if path in allowed:
        return
    if type(a) is not type(b):
        diffs.append(f"{path}: {type(a).__name__} vs {type(b).__name__}")
    elif isinstance(a, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                if f"{path}/{k}" not in allowed:
                    diffs.append(f"{path}/{k}: only in one")
            else:
                walk(a[k], b[k], f"{path}/{k}")
    elif isinstance(a, list):
        if len(a) != len(b):
            diffs.append(f"{path}: {len(a)} vs {len(b)} items")
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]")
    elif a != b:
        diffs.append(f"{path}: {a} vs {b}")
walk(live, regen)
for d in diffs[:20]:
    print("differs:", d)
assert not diffs, f"{len(diffs)} numbers differ between the live log's report and the regenerated one"
assert live["devices"] and regen["devices"] == [], "the live log has device statuses, the regenerated one none"
assert any("regenerated from the recording" in n for n in regen["notices"]), regen["notices"]
assert live["hands"] and live["controls"]["t"], "the comparison covered the tip paths and timelines"
print(f'regenerated: the same report but for the devices; {len(live["controls"]["t"])} control samples, '
      f'score {regen["score"]["total"]["value"]}')
PY
# The page shows the notice.
grep -q "regenerated from the recording" "$work/s/report.html"

# A recording cut short: the report of the steps it vouches for, and its verdict in the notice.
mkdir -p "$work/t"
size=$(stat -c %s "$session/session.lcmlog")
head -c $((size / 2)) "$session/session.lcmlog" > "$work/t/session.lcmlog"
run truncated 3 "$work/t"
grep -q "notice: the telemetry log was regenerated from the recording (truncated at step" "$work/truncated.out"
grep -q "no final score in the log" "$work/truncated.out"

# Neither a log nor a recording: no report, one line why.
mkdir -p "$work/empty"
run empty 1 "$work/empty"
grep -q "no telemetry log at" "$work/empty.err"
test ! -e "$work/empty/report.json"
echo "regenerate: ok"
