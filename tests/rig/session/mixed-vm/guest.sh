#!/bin/sh
# Inside the VM (tests/vm/run-in-vm.sh runs this as /test): a whole vitreo session on
# rig/config/sim-mixed.toml — the tracker on a umockdev USB device (vitreo under umockdev's preload
# library), the pedals on a pty, the eyeball fixture on vcan0 — playing the main job's scripted peel,
# with the USB tracker's and the CAN eyeball's cables pulled mid-session and plugged back
# (--sim-unplug). vitreo records it and replays the recording itself (exit 3 when the replay's
# final state differs from the live one). Prints PASS/FAIL lines; exits 1 on any failure.
mkdir -p /dev/pts && mount -t devpts devpts /dev/pts
failures=0
check() {  # check CONDITION MESSAGE
  if eval "$1"; then echo "PASS $2"; else echo "FAIL $2"; failures=$((failures + 1)); fi
}
# device line of the summary: "device  NAME  frames F, valid V, CRC errors C, samples S, reconnects R"
field() {  # field DEVICE samples|reconnects
  awk -v d="$1" -v f="$2" '$1 == "device" && $2 == d {
      for (i = 3; i <= NF; ++i) { w = $i; sub(",", "", w); if ($(i-1) == f) { print w; exit } } }' /tmp/session.txt
}
LD_PRELOAD=libumockdev-preload.so.0 /bin/vitreo --rig /data/sim-mixed.toml --case /data/low_membrane_macula.toml \
  --duration 3 --retina-vertices 1000 --texture-size 64 --no-render --out /tmp/out --cache /tmp/cache \
  --sim-unplug tracker-0:1.2:0.4 --sim-unplug eyeball:1.4:0.6 < /dev/null > /tmp/session.txt 2>&1
rc=$?
cat /tmp/session.txt
check "[ $rc = 0 ]" "vitreo exit code $rc (0: it ran, and the replay of its recording ended in the same state)"
check "grep -q 'identical final state and score' /tmp/session.txt" "the recording replays bit for bit"
for d in tracker-0 pedals eyeball; do
  s=$(field $d samples)
  check "[ \"\${s:-0}\" -gt 100 ]" "$d streamed (${s:-no} samples)"
done
check "grep -q 'sim:tracker?transport=usb' /tmp/out/telemetry.lcmlog" "device status names the tracker's URI"
check "grep -q 'sim:eyeball?transport=can' /tmp/out/telemetry.lcmlog" "device status names the eyeball's URI"
# unplugged, found again under its name, streaming again
for d in tracker-0 eyeball; do
  r=$(field $d reconnects)
  check "[ \"\${r:-0}\" -ge 1 ]" "$d found again after its cable was pulled (${r:-no} reconnects)"
  check "grep -q \"$d: [a-z]* -> lost\" /tmp/session.txt" "$d was seen lost"
  check "[ \$(grep -c \"$d: configuring -> streaming\" /tmp/session.txt) -ge 2 ]" "$d streams again after the re-plug"
done
echo "failures: $failures"
[ $failures = 0 ]
