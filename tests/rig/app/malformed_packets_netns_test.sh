#!/usr/bin/env bash
# The rig under attack from the local network (issue 20): a live `vitreo` session on the default
# udpm URL, inside a private network namespace (never multicast on the host network), is hit with
# malformed packets on the channel it subscribes to (the operator commands: string lengths INT_MIN,
# 0, -1, past the end, a lying argument, wrong fingerprint, truncated, trailing bytes, empty,
# oversized), junk on every other vitreo channel, and raw datagrams that are not LCM or lie in their
# fragment headers. It must keep running, acknowledge valid commands from vitreo-cmd before and
# after, count every refused packet in VITREO_RECEIVE_STATUS and its summary, and still replay to
# the same state. Exits 77 (CTest skip) where `unshare -n` is not permitted.
set -u
vitreo=${1:?usage: malformed_packets_netns_test.sh <vitreo> <lcm_probe> <vitreo-cmd> <scenes>}
probe=${2:?}; cmd=${3:?}; scenes=${4:?}
if [ -z "${VITREO_IN_PRIVATE_NETNS:-}" ]; then
  if ! unshare -n true 2>/dev/null; then
    echo "SKIP: 'unshare -n' is not permitted here (needs root or unprivileged user namespaces)"; exit 77
  fi
  command -v ip >/dev/null || { echo "SKIP: needs iproute2 'ip'"; exit 77; }
  VITREO_IN_PRIVATE_NETNS=1 exec unshare -n "$0" "$@"
fi
set -e
tmp=$(mktemp -d)
rig=
trap '[ -n "$rig" ] && kill $rig 2>/dev/null; rm -rf "$tmp"' EXIT
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo

"$vitreo" --duration 10 --no-render --cases "$scenes" --out "$tmp/out" --lcm-url 'udpm://239.255.76.67:7667?ttl=0' \
  >"$tmp/rig.out" 2>&1 &
rig=$!
"$probe" wait "" VITREO_PHYSICS_TIMING 120 || { cat "$tmp/rig.out"; echo "FAIL: the session never started"; exit 1; }

fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
"$cmd" --source ci --timeout-ms 5000 wireframe | tee "$tmp/c1"
check "a valid command before the attack is accepted" 'grep -q "toggle_wireframe: accepted" "$tmp/c1"'
"$probe" inject "" | tee "$tmp/inject1"
n=$(sed -n 's/.*injected \([0-9]*\) malformed packets.*/\1/p' "$tmp/inject1")
check "the rig survived the first wave" 'kill -0 $rig'
"$cmd" --source ci --timeout-ms 5000 zoom 3 | tee "$tmp/c2"
check "a valid command between the waves is accepted" 'grep -q "zoom: accepted" "$tmp/c2"'
"$probe" inject "" >/dev/null
"$cmd" --source ci --timeout-ms 5000 labels | tee "$tmp/c3"
check "a valid command after the attack is accepted" 'grep -q "toggle_labels: accepted" "$tmp/c3"'
check "VITREO_RECEIVE_STATUS counts every malformed command packet ($((2 * n)))" \
  '"$probe" expect-status "" VITREO_COMMAND $((2 * n)) 10'
rc=0; wait $rig || rc=$?; rig=
cat "$tmp/rig.out" | grep -v "^\[" || true
check "the session ran to its end (exit 0)" '[ $rc -eq 0 ]'
# Some of the raw datagrams with lying fragment headers name VITREO_COMMAND and are reassembled by
# liblcm into a "message": refused by the decoder too. So: at least the 2n sent, and exactly the
# three valid commands handled.
line=$(grep -E "received +VITREO_COMMAND " "$tmp/rig.out" || true)
got=$(echo "$line" | sed -n 's/.*VITREO_COMMAND *\([0-9]*\) received, \([0-9]*\) refused.*/\1 \2/p')
received=${got% *}; refused=${got#* }
check "the summary counts every refused packet ($refused >= $((2 * n))) and handled the 3 valid ones" \
  '[ -n "$got" ] && [ "$refused" -ge $((2 * n)) ] && [ $((received - refused)) -eq 3 ]'
check "the recording replays to the same state" 'grep -q "identical final state and score" "$tmp/rig.out"'
exit $fail
