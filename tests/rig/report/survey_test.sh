#!/usr/bin/env bash
# The post-session survey (thesis Appendix C) beside a session: DIR/survey.json is read, its modified
# Cooper-Harper rating follows the form's decision tree (not accomplished: 10; errors not small:
# 7..9; workload not acceptable: 4..6; acceptable: 1..3; the five levels in half steps), it appears
# in report.json (the page: chromium_test.sh), and a survey with a wrong answer is refused
# with a notice naming the field while the report is still written.
set -euo pipefail
report=$1 session=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$session/telemetry.lcmlog" "$work/"

rating() {  # rating JSON_BODY EXPECTED
  printf '{"format": "vitreo-survey-1", %s}\n' "$1" > "$work/survey.json"
  "$report" "$work" > "$work/out.txt" || { cat "$work/out.txt"; exit 1; }
  got=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["survey"]["cooper_harper_rating"]["value"])' "$work/report.json")
  [ "$got" = "$2" ] || { echo "rating $got for $1, expected $2"; exit 1; }
}
rating '"accomplished": false' 10
rating '"accomplished": true, "errors_small": false, "level": "high"' 9
rating '"accomplished": true, "errors_small": false, "level": "low"' 7
rating '"accomplished": true, "errors_small": true, "workload_acceptable": false, "level": "somewhat_high"' 5.5
rating '"accomplished": true, "errors_small": true, "workload_acceptable": true, "level": "very_easy"' 1
rating '"accomplished": true, "errors_small": true, "workload_acceptable": true, "level": "somewhat_fair"' 2.5
grep -q "survey: modified Cooper-Harper rating 2.5 of 10" "$work/out.txt"

# A full one, as the page's form writes it, shown on the page.
cat > "$work/survey.json" <<'JSON'
{
  "format": "vitreo-survey-1", "subject": "fellow-07", "date": "2026-11-26",
  "accomplished": true, "errors_small": true, "workload_acceptable": false, "level": "medium",
  "categories": {"tracking": "somewhat_high", "physical_interface": "medium", "instrumentation": "low"},
  "instruments": {"forceps": {"rating": "very_good", "comment": "jaws <b>grip</b> well"}, "light_pipe": {"rating": "fair", "comment": ""}},
  "comments": "the pedal's travel felt short"
}
JSON
"$report" "$work" --generated "2026-01-01 00:00:00 UTC" > "$work/out.txt"
python3 - "$work/report.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["survey"]
assert s["cooper_harper_rating"]["value"] == 5 and s["page"] == "workload" and s["rating_text"] == "moderately objectionable difficulty", s
assert s["instruments"]["forceps"] == {"rating": "very_good", "comment": "jaws <b>grip</b> well"}, s["instruments"]
assert s["categories"]["tracking"] == "somewhat_high" and s["subject"] == "fellow-07", s
PY
# The page's view of this survey is checked in chromium_test.sh (one browser start for both).

# Refused answers: the report is written, the notice names the field.
printf '{"format": "vitreo-survey-1", "accomplished": true, "errors_small": false, "level": "awful"}' > "$work/survey.json"
set +e; "$report" "$work" > "$work/out.txt"; rc=$?; set -e
[ "$rc" -eq 3 ] || { echo "exit $rc for a bad survey (expected 3)"; exit 1; }
grep -q "survey.json not shown: survey: level 'awful' is not one of low, somewhat_medium, medium, somewhat_high, high" "$work/out.txt"
python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); assert r["survey"] is None and any("awful" in n for n in r["notices"])' "$work/report.json"
printf '{"format": "vitreo-survey-1", "accomplished": "maybe"}' > "$work/survey.json"
set +e; "$report" "$work" > "$work/out.txt"; rc=$?; set -e
[ "$rc" -eq 3 ] && grep -q "'accomplished' must be true or false" "$work/out.txt"
printf 'not json' > "$work/survey.json"
set +e; "$report" "$work" > "$work/out.txt"; rc=$?; set -e
[ "$rc" -eq 3 ] && grep -q "survey: not JSON" "$work/out.txt"
echo "survey: ratings, page and refusals as expected"
