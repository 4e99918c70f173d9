#!/usr/bin/env bash
# Fixture of the report tests: one scripted session (the clumsy surgeon of exercise_pull_tissue, cut
# at 8 s: four retinal contacts, six excessive-force and nine wall-contact events) into DIR, with
# the main job's console summary kept in DIR/summary.txt. Lockstep and unpaced: the same session,
# step for step, on any machine.
set -euo pipefail
vitreo=$1 repo=$2 dir=$3
rm -rf "$dir"
mkdir -p "$dir"
cd "$repo"
# This session renders (the report embeds its last frame): at exit eglTerminate unloads Mesa's
# software driver, and LeakSanitizer then reports a few once-per-process Mesa/LLVM allocations as
# "<unknown module>" leaks that no suppression can name. The render tests check our rendering for
# leaks in-process with the driver pinned (tests/rig/render/pin_mesa_driver.cpp), and the other
# main-job tests run it with --no-render under LeakSanitizer; here leaks are not checked.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
"$vitreo" --case scenes/exercise_pull_tissue.toml --script scenes/scripts/exercise_pull_tissue.clumsy.toml \
  --out "$dir" --unpaced --duration 8 --no-verify --eye-size 320 --trainee fellow-07 > "$dir/summary.txt" 2> "$dir/stderr.txt"
grep -q '^  report  ' "$dir/summary.txt" || { echo "the main job printed no report line"; cat "$dir/summary.txt"; exit 1; }
test -s "$dir/report.json" && test -s "$dir/report.html"
echo "session ready in $dir"
