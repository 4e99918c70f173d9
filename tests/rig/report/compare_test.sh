#!/usr/bin/env bash
# Two sessions side by side (vitreo-report A --compare B): compare.html opens in headless Chromium
# without console errors, its table's A and B columns hold each session's own report.json numbers
# (total, categories, path length, retinal contacts) and A − B their difference, the category chart
# is drawn with both, and B's final fundus is embedded. B is the fixture session cut at 40 % of its
# telemetry log (a running score, lower on every category that progress scales): two different
# sessions of one case without running a second one.
set -euo pipefail
report=$1 session=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/b/frames"
size=$(stat -c %s "$session/telemetry.lcmlog")
head -c $((size * 4 / 10)) "$session/telemetry.lcmlog" > "$work/b/telemetry.lcmlog"
cp "$(ls "$session"/frames/step_*_instructor.png | sort | head -1)" "$work/b/frames/"
set +e
"$report" "$work/b" --out "$work/b" > /dev/null   # B's own report.json, to check the columns against
"$report" "$session" --out "$work/a" --compare "$work/b" --generated "2026-01-01 00:00:00 UTC" > "$work/a.txt"
rc=$?
set -e
[ "$rc" -eq 3 ] || { echo "exit $rc (expected 3: the compared log is truncated)"; cat "$work/a.txt"; exit 1; }
grep -q "compare.html (against $work/b)" "$work/a.txt"
grep -q "compared session: the telemetry log ends inside an event" "$work/a.txt"

timeout 60 chromium --headless --no-sandbox --disable-gpu --no-first-run --user-data-dir="$work/profile" \
  --proxy-server=127.0.0.1:9 --enable-logging=stderr --v=0 --virtual-time-budget=1000 \
  --dump-dom "file://$work/a/compare.html" > "$work/dom.html" 2> "$work/console.txt"
if grep -E 'CONSOLE|Uncaught' "$work/console.txt"; then echo "console messages above"; exit 1; fi
grep -q 'data-rendered="yes"' "$work/dom.html" || { echo "the page did not finish drawing"; exit 1; }
grep -q 'id="compare-fundus" alt="final fundus of B" src="data:image/png;base64,' "$work/dom.html" || { echo "no fundus of B"; exit 1; }
python3 - "$work/dom.html" "$work/a/report.json" "$work/b/report.json" <<'PY'
import html, json, re, sys
dom = open(sys.argv[1]).read()
a, b = json.load(open(sys.argv[2])), json.load(open(sys.argv[3]))
table = dom[dom.index('id="compare-table"'):]
table = table[:table.index("</table>")]
rows = {}
for tr in re.findall(r"<tr>(.*?)</tr>", table, re.S):
    cells = [html.unescape(re.sub(r"<[^>]+>", "", c)).strip() for c in re.findall(r"<td[^>]*>(.*?)</td>", tr, re.S)]
    if cells:
        rows[cells[0]] = cells[1:]
def num(text):
    return float(text.split()[0].replace("+", ""))
assert abs(num(rows["total score"][0]) - a["score"]["total"]["value"]) <= 0.05, rows["total score"]
assert abs(num(rows["total score"][1]) - b["score"]["total"]["value"]) <= 0.05, rows["total score"]
assert abs(num(rows["total score"][2]) - (a["score"]["total"]["value"] - b["score"]["total"]["value"])) <= 0.05
for c in a["score"]["categories"]:
    o = next(x for x in b["score"]["categories"] if x["name"] == c["name"])
    r = rows[c["name"].replace("_", " ")]
    assert abs(num(r[0]) - c["value"]["value"]) <= 0.05 and abs(num(r[1]) - o["value"]["value"]) <= 0.05, (c["name"], r)
r = rows["path length"]
assert abs(num(r[0]) - a["totals"]["path_length"]["value"]) <= 0.005 * a["totals"]["path_length"]["value"], r  # shown to 3 digits
assert abs(num(r[1]) - b["totals"]["path_length"]["value"]) <= 0.005 * b["totals"]["path_length"]["value"] + 1e-9, r
r = rows["retina contacts"]
assert num(r[0]) == a["totals"]["retina_contacts"]["value"] and num(r[1]) == b["totals"]["retina_contacts"]["value"], r
assert a["score"]["total"]["value"] != b["score"]["total"]["value"], "the two sessions must differ for the test to mean anything"
m = re.search(r'<canvas id="chart-compare"[^>]*data-points="(\d+)"', dom)
assert m and int(m.group(1)) == 2 * (len(a["score"]["categories"]) + 1), m and m.group(0)
print(f'compare: A {a["score"]["total"]["value"]:.1f} vs B {b["score"]["total"]["value"]:.1f}; {len(rows)} rows checked')
PY
