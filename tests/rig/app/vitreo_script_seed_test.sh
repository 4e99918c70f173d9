#!/usr/bin/env bash
# `vitreo --script-seed N` and `tools/script_seeds.py` as a test engineer would check them: the seed
# the summary names is the one played (no option: the script's own `seed = 1`; --script-seed 1 the
# same session bit for bit); another seed is another noise realisation (another final state) and
# its recording replays to it; the option is refused where nothing would play it; and the tool's
# table gives, seed by seed, the final state and outcome of a session run directly with that seed,
# and over several cases one summary line a case.
set -u
vitreo=${1:?usage: vitreo_script_seed_test.sh <vitreo> <scenes> <tools/script_seeds.py>}
scenes=${2:?}
tool=${3:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
case_file="$scenes/low_membrane_macula.toml"
# The default case and its expert script, 6 s of it (the forceps grasp the membrane and peel it), at
# 1500 retina vertices, lockstep.
session() {  # NAME [OPTIONS...]
  local name=$1; shift
  "$vitreo" --case "$case_file" --no-render --no-verify --unpaced --retina-vertices 1500 --duration 6 \
    --cache "$tmp/cache" --out "$tmp/$name" "$@" >"$tmp/$name.out" 2>&1
}
hash_of() { grep -o 'state hash       [0-9a-f]*' "$1" | awk '{print $3}'; }
met_of() { grep -oE 'membrane_freed erm: [0-9.]+ \(goal [0-9.]+\) (met|not met)' "$1"; }

rc=0; session own || rc=$?
check "the script's own seed: exit 0" '[ $rc -eq 0 ]' || cat "$tmp/own.out"
check "the summary names the script's own seed (1)" 'grep -q "low_membrane_macula.expert.toml (expert, seed 1)" "$tmp/own.out"'
rc=0; session s1 --script-seed 1 || rc=$?
check "--script-seed 1: exit 0" '[ $rc -eq 0 ]'
rc=0; session s2 --script-seed 2 || rc=$?
check "--script-seed 2: exit 0" '[ $rc -eq 0 ]' || cat "$tmp/s2.out"
check "the summary names seed 2" 'grep -q "(expert, seed 2)" "$tmp/s2.out"'
h_own=$(hash_of "$tmp/own.out"); h1=$(hash_of "$tmp/s1.out"); h2=$(hash_of "$tmp/s2.out")
check "state hashes were printed ($h_own, $h1, $h2)" '[ -n "$h_own" ] && [ -n "$h1" ] && [ -n "$h2" ]'
check "--script-seed 1 is the script's own seed, bit for bit" '[ "$h1" = "$h_own" ]'
check "seed 2 is another noise realisation: another final state" '[ "$h2" != "$h_own" ]'
check "the seeds drove the same hand (a grasp, attachments broken in both)" \
  'grep -q "events           [1-9][0-9]* grasps, [0-9]* burns, [1-9][0-9]* attachments broken" "$tmp/own.out" &&
   grep -q "events           [1-9][0-9]* grasps, [0-9]* burns, [1-9][0-9]* attachments broken" "$tmp/s2.out"'
rc=0; "$vitreo" --replay "$tmp/s2/session.lcmlog" --cache "$tmp/cache" --out "$tmp/replay" >"$tmp/replay.out" 2>&1 || rc=$?
check "the seed-2 recording replays to its own final state (exit $rc)" '[ $rc -eq 0 ] && grep -q "$h2" "$tmp/replay.out"'

# Refused where no script would play the seed, or where it is not a seed: a message naming the option,
# exit 2 (1 for a case without an expert script, found only once the case list is read).
refused() {  # WHAT EXPECTED_RC OPTIONS...
  local what=$1 want=$2; shift 2
  local rc=0; "$vitreo" "$@" --no-render --out "$tmp/refused" >"$tmp/refused.out" 2>&1 || rc=$?
  check "refused: $what (exit $rc, the option named)" '[ $rc -eq $want ] && grep -q "script-seed" "$tmp/refused.out"'
}
refused "--script-seed with --idle" 2 --case "$case_file" --idle --script-seed 2
refused "a negative seed" 2 --case "$case_file" --script-seed -1
refused "a seed beyond the script file's range" 2 --case "$case_file" --script-seed 1000000000000001
refused "--script-seed with --replay" 2 --replay "$tmp/s2/session.lcmlog" --script-seed 2
refused "--script-seed with --serial (real devices play no script)" 2 --case "$case_file" --serial tracker=/dev/null --script-seed 2
mkdir -p "$tmp/bare"
cp "$case_file" "$scenes/materials.toml" "$tmp/bare/"
refused "--script-seed for a case with no expert script" 1 --case "$tmp/bare/low_membrane_macula.toml" --script-seed 2 --duration 1

# The tool: seeds 1 and 2 of the same session, each row against the direct session with that seed.
rc=0; python3 "$tool" "$case_file" --seeds 1,2 --retina-vertices 1500 --duration 6 --jobs 1 --vitreo "$vitreo" \
  --out "$tmp/tool" >"$tmp/tool.out" 2>&1 || rc=$?
check "script_seeds.py: exit 0" '[ $rc -eq 0 ]' || cat "$tmp/tool.out"
row() { awk -v s="$1" '$1 == s && NF >= 7' "$tmp/tool.out"; }
check "the tool's seed-1 row ends in the direct seed-1 state ($h1)" '[ "$(row 1 | awk "{print \$6}")" = "$h1" ]'
check "the tool's seed-2 row ends in the direct seed-2 state ($h2)" '[ "$(row 2 | awk "{print \$6}")" = "$h2" ]'
for s in 1 2; do
  direct_met=$(met_of "$tmp/s$s.out" | grep -q "not met" && echo no || echo yes)
  check "the tool's seed-$s row says the criteria were met as the direct session does ($direct_met)" \
    '[ "$(row $s | awk "{print \$4}")" = "$direct_met" ]'
  direct_freed=$(met_of "$tmp/s$s.out" | awk '{print $3}')
  check "the tool's seed-$s row gives the direct session's freed share ($direct_freed)" \
    'row $s | grep -q "membrane_freed erm $(printf %.3g "$direct_freed") "'
done
met=$(grep -oE 'criteria met in [0-9]+ of 2 seeds, cleanly \(no iatrogenic event\) in [0-9]+' "$tmp/tool.out")
check "the tool's tally is printed ($met)" '[ -n "$met" ]'
clean=$(echo "$met" | awk '{print $NF}')
rc=0; python3 "$tool" "$case_file" --seeds 1,2 --retina-vertices 1500 --duration 6 --jobs 1 --vitreo "$vitreo" \
  --out "$tmp/tool" --require-rate 1 >"$tmp/tool2.out" 2>&1 || rc=$?
want=$([ "$clean" = 2 ] && echo 0 || echo 1)
check "--require-rate 1 exits $want with $clean of 2 clean (exit $rc)" '[ $rc -eq $want ]'
# Several cases at once (as `scenes/*.toml` gives them): each its own table and folder, a file with no
# expert script passed over, then one summary line a case that repeats that case's own tally.
rc=0; python3 "$tool" "$case_file" "$scenes/materials.toml" "$scenes/exercise_navigation.toml" --seeds 1 \
  --retina-vertices 1500 --duration 10 --jobs 1 --vitreo "$vitreo" --out "$tmp/multi" >"$tmp/multi.out" 2>&1 || rc=$?
check "script_seeds.py over three files: exit 0" '[ $rc -eq 0 ]' || cat "$tmp/multi.out"
check "the file without an expert script is passed over, said so" 'grep -q "materials.toml: no expert script" "$tmp/multi.out"'
for c in low_membrane_macula exercise_navigation; do
  check "$c has its own folder with its session" '[ -f "$tmp/multi/$c/seed-1/report.json" ]'
  own=$(awk -v c="$c" '$1 == c":" {f=1} f && /^criteria met in/ {sub(";", "", $13); print $4, $13; exit}' "$tmp/multi.out")
  summary=$(awk -v c="$c" '$1 == c && NF >= 8 {print $2, $5}' "$tmp/multi.out")
  check "$c's summary line repeats its tally (met, cleanly: $own / $summary)" '[ -n "$own" ] && [ "$own" = "$summary" ]'
done
rc=0; python3 "$tool" "$case_file" "$scenes/exercise_navigation.toml" --script "$scenes/scripts/low_membrane_macula.expert.toml" \
  >"$tmp/tool4.out" 2>&1 || rc=$?
check "the tool refuses --script with several cases (exit $rc)" '[ $rc -eq 2 ] && grep -q "give one case" "$tmp/tool4.out"'
rc=0; python3 "$tool" "$case_file" --seeds 3-1 >"$tmp/tool3.out" 2>&1 || rc=$?
check "the tool refuses a backwards seed range (exit $rc)" '[ $rc -eq 2 ] && grep -q "runs backwards" "$tmp/tool3.out"'
exit $fail
