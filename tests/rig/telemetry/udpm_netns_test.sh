#!/usr/bin/env bash
# udpm between processes, only inside a private network namespace (never multicast on the host
# network): our publisher on the default URL (udpm://239.255.76.67:7667?ttl=0), our subscriber and
# the real lcm-logger in another process, all in the namespace. Exits 77 (CTest skip) when this
# machine does not allow `unshare -n`.
set -u
probe=${1:?usage: udpm_netns_test.sh <lcm_probe> <vitreo-cmd>}
cmd=${2:?usage: udpm_netns_test.sh <lcm_probe> <vitreo-cmd>}
if [ -z "${VITREO_IN_PRIVATE_NETNS:-}" ]; then
  if ! unshare -n true 2>/dev/null; then
    echo "SKIP: 'unshare -n' is not permitted here (needs root or unprivileged user namespaces); udpm not tested"
    exit 77
  fi
  if ! command -v ip >/dev/null || ! command -v lcm-logger >/dev/null; then
    echo "SKIP: needs iproute2 'ip' and lcm-logger"; exit 77
  fi
  VITREO_IN_PRIVATE_NETNS=1 exec unshare -n "$0" "$@"
fi

set -e
tmp=$(mktemp -d)
trap 'kill $logger $sub 2>/dev/null || true; rm -rf "$tmp"' EXIT
logger=; sub=

echo "--- without a multicast route the publisher must fail cleanly, not publish into the void"
if "$probe" publish "" 1 2>"$tmp/err"; then echo "FAIL: publish without a route succeeded"; exit 1; fi
cat "$tmp/err"
grep -q "cannot open LCM URL" "$tmp/err"

ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo

echo "--- 1000 events: probe publisher -> probe subscriber + lcm-logger, default URL"
lcm-logger -f "$tmp/udpm.lcmlog" >"$tmp/logger.out" 2>&1 &
logger=$!
"$probe" subscribe "" 1000 20 >"$tmp/sub.out" 2>&1 &
sub=$!
for _ in $(seq 100); do  # wait for both to be listening (at most 5 s)
  grep -q subscribed "$tmp/sub.out" && [ -e "$tmp/udpm.lcmlog" ] && break
  sleep 0.05
done
sleep 0.2
"$probe" publish "" 1000
sub_rc=0; wait $sub || sub_rc=$?; sub=
cat "$tmp/sub.out"
[ $sub_rc -eq 0 ] || { echo "FAIL: subscriber exit $sub_rc"; exit 1; }
sleep 0.3
kill -INT $logger; wait $logger || true; logger=
"$probe" count "$tmp/udpm.lcmlog" 1000

echo "--- operator commands across processes: vitreo-cmd -> stand-in rig (CommandServer) -> ack"
"$probe" respond "" 4 20 >"$tmp/resp.out" 2>&1 &
sub=$!
for _ in $(seq 100); do grep -q responding "$tmp/resp.out" && break; sleep 0.05; done
"$cmd" --source ci --timeout-ms 5000 zoom 12.5 | tee "$tmp/c1"
grep -q "zoom: accepted" "$tmp/c1"
rc=0; "$cmd" --source ci --timeout-ms 5000 zoom 99 >"$tmp/c2" || rc=$?
cat "$tmp/c2"; [ $rc -eq 1 ] && grep -q "refused: zoom 99" "$tmp/c2"
rc=0; printf 'p\ns peel-start\n' | "$cmd" --source ci --timeout-ms 5000 >"$tmp/c3" || rc=$?
cat "$tmp/c3"; [ $rc -eq 1 ] && grep -q "previous_case: refused: already at the first case" "$tmp/c3" \
  && grep -q "save_snapshot: accepted" "$tmp/c3"
wait $sub; sub=
cat "$tmp/resp.out"
grep -q "2 accepted, 2 refused" "$tmp/resp.out"
echo "--- malformed acknowledgements (string lengths INT_MIN and 0) before the real one: vitreo-cmd ignores them"
"$probe" respond-noisy "" 1 20 >"$tmp/resp2.out" 2>&1 &
sub=$!
for _ in $(seq 100); do grep -q responding "$tmp/resp2.out" && break; sleep 0.05; done
rc=0; "$cmd" --source ci2 --timeout-ms 5000 wireframe >"$tmp/c4" 2>"$tmp/c4.err" || rc=$?
cat "$tmp/c4" "$tmp/c4.err"
[ $rc -eq 0 ] && grep -q "toggle_wireframe: accepted" "$tmp/c4" \
  && grep -q "ignored 2 malformed packet(s) on VITREO_COMMAND_ACK" "$tmp/c4.err"
wait $sub; sub=
echo "udpm in a private namespace: OK"
