#!/usr/bin/env bash
# The same telemetry log gives the same report, byte for byte: report.json always, report.html when
# the generation time is the same (the one thing allowed to differ). The report the main job wrote at
# the end of the session is the same JSON as one made afterwards from its folder. The final fundus
# inside the page is the folder's last instructor frame, byte for byte (checked against coreutils'
# base64, not the report's encoder).
set -euo pipefail
report=$1 session=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$report" "$session" --out "$work/a" --generated "2026-01-01 00:00:00 UTC" > "$work/a.txt"
"$report" "$session" --out "$work/b" --generated "2026-01-01 00:00:00 UTC" > "$work/b.txt"
"$report" "$session" --out "$work/c" --generated "2027-06-30 12:00:00 UTC" > /dev/null
cmp "$work/a/report.json" "$work/b/report.json"
cmp "$work/a/report.html" "$work/b/report.html"
cmp "$work/a/report.json" "$work/c/report.json"
# Pages made at different times differ in the generation time and nothing else.
diff <(sed 's/2026-01-01 00:00:00 UTC/TIME/' "$work/a/report.html") <(sed 's/2027-06-30 12:00:00 UTC/TIME/' "$work/c/report.html") > /dev/null
cmp "$session/report.json" "$work/a/report.json"
grep -q "report: exercise_pull_tissue" "$work/a.txt"
grep -q '"trainee":"fellow-07"' "$session/report.json"   # vitreo --trainee, kept in DIR/trainee.txt

# The embedded fundus is the last instructor frame.
last=$(ls "$session"/frames/step_*_instructor.png | sort | tail -1)
grep -q "frames/$(basename "$last")" "$work/a/report.html"
grep -o 'id="final-fundus" alt="final fundus" src="data:image/png;base64,[^"]*' "$work/a/report.html" | cut -d, -f2 | base64 -d | cmp - "$last"
# So are the key moments' pictures, in step order.
moments=$(ls "$session"/frames/moment_*_instructor.png | sort)
[ -n "$moments" ] || { echo "the fixture session pictured no key moment"; exit 1; }
i=0
for m in $moments; do
  i=$((i + 1))
  grep -o '<figure><img class="fundus" alt="[^"]*" src="data:image/png;base64,[^"]*' "$work/a/report.html" | sed -n "${i}p" | cut -d, -f2 | base64 -d | cmp - "$m"
  grep -q "(frames/$(basename "$m"))" "$work/a/report.html"
done
# Nothing in the page reaches for the network.
if grep -qiE '(src|href)="(https?:)?//' "$work/a/report.html"; then echo "the page references a remote resource"; exit 1; fi
echo "deterministic: json $(stat -c %s "$work/a/report.json") bytes, html $(stat -c %s "$work/a/report.html") bytes"
