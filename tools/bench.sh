#!/usr/bin/env bash
# Builds the Release preset and runs every benchmark executable (or those matching a regex given as
# the first argument, matched against executable names). Extra arguments go to Google Benchmark,
# e.g. tools/bench.sh tissue --benchmark_format=json
set -euo pipefail
cd "$(dirname "$0")/.."
filter=${1:-.}
shift || true
cmake --preset release -DVITREO_BUILD_BENCHMARKS=ON -DVITREO_BUILD_TESTS=OFF >/dev/null
cmake --build --preset release
for b in build/release/bench/*; do
  [ -x "$b" ] || continue
  if [[ "$(basename "$b")" =~ $filter ]]; then
    echo "== $(basename "$b")"
    "$b" "$@"
  fi
done
