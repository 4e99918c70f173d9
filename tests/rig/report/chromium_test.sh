#!/usr/bin/env bash
# The page as an instructor meets it: headless Chromium opens report.html from the file alone, with
# the network switched off, logs no console error or page error, and its DOM shows the charts drawn
# with data (each canvas carries the number of points Chart.js was given), the criteria and score
# card tables filled, the final fundus and the key moments' pictures embedded. A screenshot is left in the build folder to
# look at, and compared with the checked-in golden (tests/rig/report/golden/) with a tolerance when
# one is given.
set -euo pipefail
report=$1 session=$2 shots=$3 compare=${4:-} golden=${5:-}
command -v chromium > /dev/null || { echo "chromium is not installed (tools/install-deps.sh)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The session's log and a survey as the page's form writes it (survey_test.sh checks its numbers).
cp "$session/telemetry.lcmlog" "$session/session.lcmlog" "$work/"
cp -r "$session/frames" "$work/"
cat > "$work/survey.json" <<'JSON'
{
  "format": "vitreo-survey-1", "subject": "fellow-07", "date": "2026-11-26",
  "accomplished": true, "errors_small": true, "workload_acceptable": false, "level": "medium",
  "categories": {"tracking": "somewhat_high", "physical_interface": "medium", "instrumentation": "low"},
  "instruments": {"forceps": {"rating": "very_good", "comment": "jaws <b>grip</b> well"}},
  "comments": "the pedal's travel felt short"
}
JSON
"$report" "$work" --generated "2026-01-01 00:00:00 UTC" > /dev/null
flags=(--headless --no-sandbox --disable-gpu --no-first-run --user-data-dir="$work/profile" --disable-extensions
       --proxy-server=127.0.0.1:9 --proxy-bypass-list='<-loopback>' --hide-scrollbars --force-device-scale-factor=1
       --enable-logging=stderr --v=0 --virtual-time-budget=1000)
timeout 60 chromium "${flags[@]}" --dump-dom "file://$work/report.html" > "$work/dom.html" 2> "$work/console.txt"

fail=0
# Console messages arrive as 'CONSOLE(line)' lines; a page error also sets data-error on #page-status.
if grep -E 'CONSOLE|Uncaught' "$work/console.txt" | grep -viE 'level=0|"Download the' > "$work/console_errors.txt"; then
  echo "console messages:"; cat "$work/console_errors.txt"; fail=1
fi
grep -q 'id="page-status"[^>]*data-rendered="yes"' "$work/dom.html" || { echo "the page did not finish drawing"; grep -o '<div id="page-status"[^>]*>[^<]*' "$work/dom.html"; fail=1; }
grep -q 'data-error=' "$work/dom.html" && { echo "page error:"; grep -o 'data-error="[^"]*"' "$work/dom.html"; fail=1; }
for id in chart-fundus chart-force chart-controls chart-dose chart-actuation chart-score chart-events; do
  points=$(grep -o "<canvas id=\"$id\"[^>]*>" "$work/dom.html" | grep -o 'data-points="[0-9]*"' | grep -o '[0-9]*' || true)
  if [ -z "$points" ] || [ "$points" -eq 0 ]; then echo "chart $id has no data (${points:-not drawn})"; fail=1; fi
  echo "$id: ${points:-0} points"
done
grep -q '<td>membrane_released patch</td>' "$work/dom.html" || { echo "criteria table not filled"; fail=1; }
grep -q '<td>tissue treatment</td>' "$work/dom.html" || { echo "score card not filled"; fail=1; }
grep -q 'id="final-fundus" alt="final fundus" src="data:image/png;base64,' "$work/dom.html" || { echo "no final fundus"; fail=1; }
# The fixture's first excessive force and first wall contact, pictured (rig/session/key_moments.hpp).
grep -q '<figcaption>step [0-9]*: <b>excessive retina force</b>' "$work/dom.html" || { echo "no key moment: excessive retina force"; fail=1; }
grep -q '<figcaption>step [0-9]*: <b>globe wall contact</b>' "$work/dom.html" || { echo "no key moment: globe wall contact"; fail=1; }
grep -q '<canvas id="chart-pedals"' "$work/dom.html" || { echo "no pedal travel chart"; fail=1; }
# The case's anatomy under the paths (from the recording's case file): ora, disc, macula, fovea, the patch.
anatomy=$(grep -o '<canvas id="chart-fundus"[^>]*>' "$work/dom.html" | grep -o 'data-anatomy="[0-9]*"' | grep -o '[0-9]*' || true)
[ "${anatomy:-0}" -ge 5 ] || { echo "the fundus chart has ${anatomy:-no} anatomy outlines, expected 5"; fail=1; }
grep -q 'rating 5 of 10: moderately objectionable difficulty' "$work/dom.html" || { echo "survey not shown"; fail=1; }
grep -q '<td>very good — jaws &lt;b&gt;grip&lt;/b&gt; well</td>' "$work/dom.html" || { echo "survey comment not shown as text"; fail=1; }
grep -q 'name="ins_forceps"' "$work/dom.html" || { echo "the survey form lacks the session's instruments"; fail=1; }
[ "$fail" -eq 0 ] || exit 1

mkdir -p "$shots"
timeout 60 chromium "${flags[@]}" --window-size=1200,2100 --screenshot="$shots/report.png" "file://$work/report.html" 2> /dev/null > /dev/null
test -s "$shots/report.png"
echo "screenshot: $shots/report.png"
if [ -n "$golden" ]; then
  # The top of the page: score, criteria, score card, the fundus paths and the final fundus.
  "$compare" "$golden" "$shots/report.png"
fi
