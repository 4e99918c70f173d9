#!/usr/bin/env bash
# A trainee's history (vitreo-report --trainee ID ROOT): the sessions under ROOT that name the
# trainee (DIR/trainee.txt, written by `vitreo --trainee ID`), per case in the order they started,
# each attempt's total and categories equal to its own report.json, pass = the case completed with a
# final score at or above --pass (a high score on an unfinished case does not pass); other trainees' and unnamed sessions left out; the page draws a learning curve per case in
# headless Chromium without console errors; a bad id or no sessions give a clear error.
set -euo pipefail
report=$1 session=$2 vitreo=${3:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
log="$session/telemetry.lcmlog"
size=$(stat -c %s "$log")
# Three attempts of fellow-07: cut at 50 % and 75 % (running scores) and the whole session (final);
# one of another trainee, one unnamed, one folder with a damaged report.
mk() {  # mk FOLDER TRAINEE BYTES
  mkdir -p "$work/root/$1"
  head -c "$3" "$log" > "$work/root/$1/telemetry.lcmlog"
  [ -z "$2" ] || echo "$2" > "$work/root/$1/trainee.txt"
  "$report" "$work/root/$1" > /dev/null || [ $? -eq 3 ]
}
mk a-first fellow-07 $((size / 2))
mk b-second fellow-07 $((size * 3 / 4))
mk c-third fellow-07 "$size"
mk d-other fellow-12 "$size"
mk e-unnamed "" "$size"
mkdir -p "$work/root/f-damaged" && echo '{"trainee": "fellow-07", "case": 3}' > "$work/root/f-damaged/report.json"
python3 - "$work/root" <<'PY'
# The attempts' start times come from the logs; cut copies of one log share it. Spread them so the
# order is the folders' (an attempt's time is its first telemetry event's).
import json, sys
for i, name in enumerate(["c-third", "a-first", "b-second"]):
    p = f"{sys.argv[1]}/{name}/report.json"
    r = json.load(open(p))
    r["case"]["started_utime_us"] = 1_800_000_000_000_000 + [3, 1, 2][i] * 86_400_000_000
    json.dump(r, open(p, "w"))
PY
"$report" "$work/root" --trainee fellow-07 --pass 25 --generated "2026-01-01 00:00:00 UTC" > "$work/out.txt"
grep -q "history of fellow-07: 3 sessions in 1 cases, 1 unreadable reports left out" "$work/out.txt"
python3 - "$work/root" <<'PY'
import json, sys
root = sys.argv[1]
h = json.load(open(f"{root}/history-fellow-07.json"))
assert h["trainee"] == "fellow-07" and h["sessions"] == 3 and h["skipped_folders"] == 1, h
(case,) = h["cases"]
assert case["case"] == "exercise_pull_tissue"
assert [a["folder"] for a in case["attempts"]] == ["a-first", "b-second", "c-third"], case["attempts"]
for a in case["attempts"]:
    r = json.load(open(f'{root}/{a["folder"]}/report.json'))
    assert a["total"]["value"] == r["score"]["total"]["value"] and a["final"] == r["score"]["final"], (a, r["score"])
    assert {k: v["value"] for k, v in a["categories"].items()} == {c["name"]: c["value"]["value"] for c in r["score"]["categories"]}
    assert a["completed"] == r["case"]["completed"], (a, r["case"])
    assert a["passed"] == (r["case"]["completed"] and r["score"]["total"]["value"] >= 25)
# The fixture is the clumsy surgeon cut at 8 s: the third attempt's score is final (the session ended)
# and above 25, but the case was not completed, so no attempt passes.
assert case["attempts"][2]["final"] and not case["attempts"][2]["completed"] and case["attempts"][2]["total"]["value"] >= 25, case["attempts"]
assert not any(a["passed"] for a in case["attempts"]), case["attempts"]
assert case["first_passed_attempt"] == 0 and case["best"]["value"] == max(a["total"]["value"] for a in case["attempts"])
assert case["pass_score"]["value"] == 25 and case["pass_score_from"] == "--pass", case["pass_score"]
print("history:", [(a["folder"], round(a["total"]["value"], 1), a["passed"]) for a in case["attempts"]])
PY
# Without --pass each case is judged against its own pass score, which its reports carry (the case
# file's [proficiency] pass_score, read here from the file itself).
"$report" "$work/root" --trainee fellow-07 --out "$work/own" --generated "2026-01-01 00:00:00 UTC" > /dev/null
python3 - "$work/root" "$work/own" "$(dirname "$0")/../../../scenes/exercise_pull_tissue.toml" <<'PY'
import json, re, sys
root, own, case_file = sys.argv[1:]
want = float(re.search(r"^\[proficiency\]\npass_score = ([0-9.]+)$", open(case_file).read(), re.M).group(1))
h = json.load(open(f"{own}/history-fellow-07.json"))
assert h["pass_score"] is None, h["pass_score"]
(case,) = h["cases"]
assert case["pass_score"]["value"] == want and case["pass_score_from"] == "case file", (case["pass_score"], want)
for a in case["attempts"]:
    r = json.load(open(f'{root}/{a["folder"]}/report.json'))
    assert r["case"]["pass_score"]["value"] == want
    assert a["passed"] == r["case"]["passed"] == (r["case"]["completed"] and r["score"]["total"]["value"] >= want), (a, r["case"])
print("history with the case's own pass score", want, [(a["folder"], a["passed"]) for a in case["attempts"]])
PY
timeout 60 chromium --headless --no-sandbox --disable-gpu --no-first-run --user-data-dir="$work/profile" \
  --proxy-server=127.0.0.1:9 --enable-logging=stderr --v=0 --virtual-time-budget=1000 \
  --dump-dom "file://$work/root/history-fellow-07.html" > "$work/dom.html" 2> "$work/console.txt"
if grep -E 'CONSOLE|Uncaught' "$work/console.txt"; then echo "console messages above"; exit 1; fi
grep -q 'data-rendered="yes"' "$work/dom.html" && grep -q 'data-charts="1"' "$work/dom.html"
grep -q '<canvas id="chart-case-0"[^>]*data-points="[1-9]' "$work/dom.html"
grep -q 'not passed yet' "$work/dom.html"

# The same final report with a total far above the pass score, still unfinished: once as this report
# format writes it (case.completed false) and once as a report from before that field (the history
# reads its criteria); and once completed (every criterion met), which passes.
mkdir -p "$work/unfinished"
python3 - "$work/root/c-third/report.json" "$work/unfinished" <<'PY'
import copy, json, os, sys
src, out = sys.argv[1:]
r = json.load(open(src))
assert r["score"]["final"] and not r["case"]["completed"] and not r["case"]["passed"] and r["criteria"], r["case"]
def save(name, rep, day):
    os.makedirs(f"{out}/{name}")
    rep["case"]["started_utime_us"] = 1_800_000_000_000_000 + day * 86_400_000_000
    json.dump(rep, open(f"{out}/{name}/report.json", "w"))
new = copy.deepcopy(r)
new["score"]["total"]["value"] = 99.0
assert not all(c["met"] or c["kind"] == "time_limit" for c in new["criteria"]), new["criteria"]
save("a-unfinished", new, 1)
old = copy.deepcopy(new)
del old["case"]["completed"], old["case"]["passed"]
save("b-unfinished-older-report", old, 2)
done = copy.deepcopy(r)
done["case"]["completed"] = True
for c in done["criteria"]:
    c["met"] = True
save("c-finished", done, 3)
PY
"$report" "$work/unfinished" --trainee fellow-07 --pass 25 --generated "2026-01-01 00:00:00 UTC" > /dev/null
python3 - "$work/unfinished/history-fellow-07.json" <<'PY'
import json, sys
(case,) = json.load(open(sys.argv[1]))["cases"]
got = [(a["folder"], a["final"], a["completed"], a["passed"]) for a in case["attempts"]]
assert got == [("a-unfinished", True, False, False), ("b-unfinished-older-report", True, False, False), ("c-finished", True, True, True)], got
assert case["first_passed_attempt"] == 3 and case["best"]["value"] == 99.0, case
print("unfinished attempts do not pass:", got)
PY

set +e
"$report" "$work/root" --trainee '../x' > /dev/null 2> "$work/err.txt"; rc1=$?
"$report" "$work/root" --trainee nobody > /dev/null 2> "$work/err2.txt"; rc2=$?
set -e
[ $rc1 -eq 1 ] && grep -q "1-64 characters" "$work/err.txt"
[ $rc2 -eq 1 ] && grep -q "no session of trainee 'nobody'" "$work/err2.txt"

# The main job names the trainee: refused when the id is not one.
if [ -n "$vitreo" ]; then
  set +e; "$vitreo" --trainee 'a b' --out "$work/x" --duration 0.01 > /dev/null 2> "$work/err3.txt"; rc=$?; set -e
  [ $rc -ne 0 ] && grep -q "1-64 characters" "$work/err3.txt"
fi
echo "history: ok"
