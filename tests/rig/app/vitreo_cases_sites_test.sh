#!/bin/bash
# vitreo-cases sites: a band's attachment-site table as its documentation (scenes/README.md,
# tools/delamination_script.py) says — one line a site, the same number of sites at 5k and at the
# case's own resolution, every stalk holding in the settled start, its strand nearly radial (the
# crossing 0.55 mm up lies within 0.1 mm of the wall point under its foot, in the site's own frame),
# its foot on the retina (within 0.05 mm of the wall) — and a membrane the case lacks refused.
set -u
cases=${1:?usage: vitreo_cases_sites_test.sh <vitreo-cases> <scenes>}
scenes=${2:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }

"$cases" sites "$scenes/traction_anteroposterior.toml" ap_band --retina-vertices 5000 > "$tmp/5k.txt" || { echo "FAIL: sites at 5k"; exit 1; }
"$cases" sites "$scenes/traction_anteroposterior.toml" ap_band --retina-vertices 8000 > "$tmp/8k.txt" || { echo "FAIL: sites at 8k"; exit 1; }
n5=$(grep -c '^site ' "$tmp/5k.txt"); n8=$(grep -c '^site ' "$tmp/8k.txt")
check "41 sites at 5k (0.85 mm lattice over the band), got $n5" '[ "$n5" -eq 41 ]'
check "the same number at 8k, got $n8" '[ "$n8" -eq "$n5" ]'
check "every line has its 13 fields" '[ "$(awk '"'"'/^site /{ if (NF != 13) bad++ } END { print bad + 0 }'"'"' "$tmp/5k.txt")" -eq 0 ]'
check "every stalk holds in the settled start" '[ "$(grep "^site " "$tmp/5k.txt" | grep -vc " holds ")" -eq 0 ]'
check "each strand crosses 0.55 mm within 0.1 mm of the wall under its foot" \
  '[ "$(awk '"'"'/^site /{ if ($6 * $6 + $7 * $7 > 0.01) bad++ } END { print bad + 0 }'"'"' "$tmp/5k.txt")" -eq 0 ]'
check "each foot lies on the retina (within 0.05 mm of the wall)" \
  '[ "$(awk '"'"'/^site /{ if ($10 > 0.05 || $10 < -0.05) bad++ } END { print bad + 0 }'"'"' "$tmp/5k.txt")" -eq 0 ]'
check "the header names the case and the resolution" 'head -1 "$tmp/5k.txt" | grep -q "traction_anteroposterior at 5000 retina vertices"'
if "$cases" sites "$scenes/traction_anteroposterior.toml" no_such_band --retina-vertices 5000 > "$tmp/out" 2> "$tmp/err"; then
  echo "FAIL: a membrane the case lacks was accepted"; fail=1
else
  check "a membrane the case lacks is refused by name" 'grep -q "the case has no membrane '"'"'no_such_band'"'"'" "$tmp/err"'
fi
exit $fail
