#!/usr/bin/env bash
# Sensor faults reach the debrief (issue 20): a session whose tracker sticks, jumps and drops out and
# whose pedals send out-of-range samples (device_faults.script.toml, through the emulators and the real
# ptys, in lockstep), then its report checked by check_device_faults.py.
set -euo pipefail
vitreo=$1 repo=$2 dir=$3 pytypes=$4
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$dir"
mkdir -p "$dir"
cd "$repo"
"$vitreo" --case scenes/exercise_pull_tissue.toml --script "$here/device_faults.script.toml" \
  --out "$dir" --unpaced --no-render --no-verify > "$dir/summary.txt" 2> "$dir/stderr.txt" || { cat "$dir/summary.txt" "$dir/stderr.txt"; exit 1; }
test -s "$dir/report.json" || { echo "no report.json"; cat "$dir/summary.txt"; exit 1; }
python3 "$here/check_device_faults.py" "$pytypes" "$dir"
