#!/usr/bin/env bash
# `vitreo --physics-threads N` (the tissue step's worker pool) as a test engineer would check it: the
# same scripted lockstep session run with 1, 2 and 3 threads ends in the same state hash and score,
# the summary names the count, and a recording made with 2 threads replays to its final state with 1.
set -u
vitreo=${1:?usage: vitreo_physics_threads_test.sh <vitreo> <scenes>}
scenes=${2:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
# The default case and its expert script, 6 s of it (the forceps grasp the membrane and peel it: about
# 40 attachments let go), lockstep.
session() {
  "$vitreo" --no-render --unpaced --retina-vertices 1500 --texture-size 64 --duration 6 --cases "$scenes" \
    --cache "$tmp/cache" --physics-threads "$1" --no-verify --out "$tmp/t$1" >"$tmp/t$1.out" 2>&1
}
for t in 1 2 3; do
  rc=0; session $t || rc=$?
  check "$t thread(s): exit 0" '[ $rc -eq 0 ]' || cat "$tmp/t$t.out"
  check "$t thread(s): the summary names the count" 'grep -q "physics threads  $t\$" "$tmp/t$t.out"'
done
hash_of() { grep -o 'state hash       [0-9a-f]*' "$1" | awk '{print $3}'; }
score_of() { grep -o 'score            [0-9]* / 100' "$1"; }
h1=$(hash_of "$tmp/t1.out")
check "a state hash was printed ($h1)" '[ -n "$h1" ]'
check "the session did work the tissue (a grasp, attachments broken)" \
  'grep -q "events           [1-9][0-9]* grasps, [0-9]* burns, [1-9][0-9]* attachments broken" "$tmp/t1.out"'
for t in 2 3; do
  ht=$(hash_of "$tmp/t$t.out")
  check "$t threads end in the 1-thread state ($ht)" '[ "$ht" = "$h1" ]'
  check "$t threads give the 1-thread score" '[ "$(score_of "$tmp/t$t.out")" = "$(score_of "$tmp/t1.out")" ]'
done
rc=0; "$vitreo" --replay "$tmp/t2/session.lcmlog" --physics-threads 1 --cache "$tmp/cache" --out "$tmp/replay" >"$tmp/replay.out" 2>&1 || rc=$?
check "the 2-thread recording replays with 1 thread to its final state (exit $rc)" '[ $rc -eq 0 ] && grep -q "$h1" "$tmp/replay.out"'
[ $fail -eq 0 ] || cat "$tmp/replay.out"
exit $fail
