#!/usr/bin/env bash
# Nonsense a careless user can type or name (issue 20), refused loudly by the tools as they ship:
# one line that says why, a non-zero exit, nothing run, and never a hang (each call is bounded by
# `timeout`, so a regression to "runs for ever" fails instead of stalling the suite).
set -u
vitreo=${1:?usage: refuse_nonsense_test.sh <vitreo> <vitreo-cases> <vitreo-devices> <scenes>}
cases=${2:?}; devices=${3:?}; scenes=${4:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
# refused <what> <pattern> <command...>: non-zero exit within 20 s, one line of output, the pattern in it.
refused() {
  local what=$1 pattern=$2; shift 2
  local rc=0
  timeout 20 "$@" >"$tmp/out" 2>&1 </dev/null || rc=$?
  local lines; lines=$(wc -l <"$tmp/out")
  if [ $rc -ne 0 ] && [ $rc -ne 124 ] && [ "$lines" -eq 1 ] && grep -q -- "$pattern" "$tmp/out"; then
    echo "ok: $what -> exit $rc: $(cat "$tmp/out")"
  else
    echo "FAIL: $what (exit $rc, $lines lines; wanted '$pattern'):"; cat "$tmp/out"; fail=1
  fi
}

# Files: a case whose library is /dev/zero, a case that is a directory, a 2 MB case, TOML that
# toml++ 3.3.0 misbehaves on, pedal files with one switch for two jobs or a device for a path.
mkdir -p "$tmp/scn"
cp "$scenes/low_membrane_macula.toml" "$tmp/scn/zero.toml"
sed -i 's|^library = .*|library = "/dev/zero"|' "$tmp/scn/zero.toml"
grep -q '"/dev/zero"' "$tmp/scn/zero.toml" || { echo "FAIL: could not point the case at /dev/zero"; exit 1; }
{ cat "$scenes/low_membrane_macula.toml"; head -c 2100000 /dev/zero | tr '\0' '#'; echo; } >"$tmp/big.toml"
printf '[&x]\nname = "x"\n' >"$tmp/header.toml"
printf 'format_version = 1\nfo \xc2\xb5 = 1\n' >"$tmp/micro.toml"
printf '[pedals]\nlaser_switch = 0\nreflux_switch = 0\n' >"$tmp/pedals.toml"

refused "vitreo-cases validate: library = /dev/zero" "is not a regular file" "$cases" validate "$tmp/scn/zero.toml"
refused "vitreo-cases list: a case whose library is /dev/zero" "not a regular file" "$cases" list --dir "$tmp/scn"
refused "vitreo-cases validate: a directory" "is a directory" "$cases" validate "$tmp/scn"
refused "vitreo-cases validate: a 2 MB case" "larger than 1 MiB" "$cases" validate "$tmp/big.toml"
refused "vitreo-cases validate: [&x]" "a table header must start with a key" "$cases" validate "$tmp/header.toml"
refused "vitreo-cases validate: fo µ = 1" "non-ASCII character outside a string" "$cases" validate "$tmp/micro.toml"
refused "vitreo --case: library = /dev/zero" "is not a regular file" "$vitreo" --no-render --out "$tmp/o" --case "$tmp/scn/zero.toml"
refused "vitreo --case: a 2 MB case" "larger than 1 MiB" "$vitreo" --no-render --out "$tmp/o" --case "$tmp/big.toml"
refused "vitreo --pedal-config: one switch for laser and reflux" "are the same switch" \
  "$vitreo" --no-render --out "$tmp/o" --pedal-config "$tmp/pedals.toml"
refused "vitreo --pedal-config /dev/zero" "not a regular file" "$vitreo" --no-render --out "$tmp/o" --pedal-config /dev/zero

# Options: NaN and infinities, unknown device kinds, ports that are not ports.
for v in nan inf -inf 1e999 -3 0; do
  refused "vitreo --duration $v" "is not a number in" "$vitreo" --duration "$v" --no-render
done
for v in 0 65 -1 two; do
  refused "vitreo --physics-threads $v" "physics-threads" "$vitreo" --physics-threads "$v" --no-render --out "$tmp/o"
done
refused "vitreo --physics-threads 2 --realtime" "share the pinned physics core" "$vitreo" --physics-threads 2 --realtime --no-render --out "$tmp/o"
refused "vitreo --serial foo=/dev/null" "unknown device kind 'foo'" "$vitreo" --no-render --out "$tmp/o" --serial foo=/dev/null
refused "vitreo --serial tracker=/dev/null" "is not a serial port" "$vitreo" --no-render --out "$tmp/o" --serial tracker=/dev/null
refused "vitreo --serial tracker=<a regular file>" "is not a serial port" "$vitreo" --no-render --out "$tmp/o" --serial "tracker=$tmp/header.toml"
refused "vitreo --serial tracker=<missing>" "no such device" "$vitreo" --no-render --out "$tmp/o" --serial "tracker=$tmp/none"
refused "vitreo --serial twice the same kind" "a second tracker" "$vitreo" --no-render --out "$tmp/o" --serial tracker=/dev/ptmx --serial tracker=/dev/ptmx
refused "vitreo-devices watch --duration-s nan" "is not a number in" "$devices" watch --serial /dev/null --duration-s nan
refused "vitreo-devices simulate --duration-s nan" "is not a number in" "$devices" simulate --duration-s nan
refused "vitreo-devices identify --timeout-s nan" "is not a number in" "$devices" identify --serial /dev/null --timeout-s nan
refused "vitreo-devices watch --print-hz inf" "is not a number in" "$devices" watch --serial /dev/null --print-hz inf
refused "vitreo-devices watch --serial /dev/null" "is not a serial port" "$devices" watch --serial /dev/null --duration-s 1
printf 'device tracker\nkey 0 1 2 3 0 0 0 0\nfault 100 10 jump nan\n' >"$tmp/jump.txt"
refused "vitreo-devices simulate: an emulator script with 'jump nan'" "line 3: fault ... jump needs" \
  "$devices" simulate --script "$tmp/jump.txt" --link "$tmp/tty" --duration-s 1
exit $fail
