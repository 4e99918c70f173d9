#!/usr/bin/env bash
# The layers' dependencies point one way (firmware-protocol → drivers → core → rig, with core
# independent of drivers). This test fails if a file includes a header from a layer above it.
set -u
root=${1:?usage: check_layering.sh <source-root>}
fail=0
check() {  # check <folder> <forbidden-include-prefix>...
  local dir=$1; shift
  [ -d "$root/$dir" ] || return 0
  for bad in "$@"; do
    hits=$(grep -rnE "#\s*include\s*[<\"]$bad/" "$root/$dir" --include='*.[ch]' --include='*.[ch]pp' || true)
    if [ -n "$hits" ]; then
      echo "layering violation: $dir/ must not include $bad/:"; echo "$hits"; fail=1
    fi
  done
}
check firmware-protocol drivers core rig
check drivers core rig
check core drivers rig firmware-protocol
# The core has no clocks, threads or I/O of its own (design guide): forbid the headers that bring them.
# Its one exception is the tissue step's worker pool (core/common/worker_pool.*), whose fixed
# partition keeps the results independent of the threads: only it may start threads.
pool='core/common/worker_pool\.[ch]pp:'
hits=$(grep -rnE '#\s*include\s*<(thread|chrono|mutex|condition_variable|future|iostream|fstream|cstdio|random)>' \
  "$root/core" --include='*.[ch]pp' | grep -v 'core/scene/' | grep -vE "${pool}[0-9]+:#include <thread>" || true)
if [ -n "$hits" ]; then echo "core/ must not use clocks, threads, random devices or stream I/O outside core/scene/:"; echo "$hits"; fail=1; fi
hits=$(grep -rnE '\bstd::(thread|jthread|async)\b|\bpthread_' "$root/core" --include='*.[ch]pp' | grep -vE "$pool" || true)
if [ -n "$hits" ]; then echo "core/ starts threads only in its worker pool (core/common/worker_pool.*):"; echo "$hits"; fail=1; fi
[ $fail -eq 0 ] && echo "layering ok"
exit $fail
