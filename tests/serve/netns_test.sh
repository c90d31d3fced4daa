#!/usr/bin/env bash
# Subsystems on different computers: the lab and a controller in two network
# namespaces joined by a veth pair (169.254.77.1 <-> 169.254.77.2, link-local,
# inside this test's own namespaces only). The controller reaches `vlab serve`
# across the link, drives the arm in lockstep, and the run must pass with every
# command accepted. Needs root and `ip netns`; otherwise it is skipped (exit 77)
# with the reason printed.
#   netns_test.sh VLAB CONTROLLER_PY OUT_DIR
set -u
vlab="$1"; controller="$2"; out="$3"
skip() { echo "SKIPPED: $*"; exit 77; }
[ "$(id -u)" -eq 0 ] || skip "not root (network namespaces need CAP_NET_ADMIN)"
command -v ip >/dev/null || skip "no 'ip' command (iproute2)"
lab="vlab_lab_$$"; ctl="vlab_ctl_$$"
cleanup() { ip netns del "$lab" 2>/dev/null; ip netns del "$ctl" 2>/dev/null; }
trap cleanup EXIT
ip netns add "$lab" 2>/dev/null || skip "'ip netns add' is not permitted here"
ip netns add "$ctl" || exit 1
ip link add "vl$$" type veth peer name "vc$$" || skip "cannot create a veth pair"
ip link set "vl$$" netns "$lab" && ip link set "vc$$" netns "$ctl" || exit 1
ip -n "$lab" addr add 169.254.77.1/24 dev "vl$$" && ip -n "$lab" link set "vl$$" up && ip -n "$lab" link set lo up
ip -n "$ctl" addr add 169.254.77.2/24 dev "vc$$" && ip -n "$ctl" link set "vc$$" up && ip -n "$ctl" link set lo up
rm -rf "$out"; mkdir -p "$out"
ip netns exec "$lab" "$vlab" serve scenes/pa10_serve --bind 169.254.77.1 --duration 1 --out "$out/run" \
  >"$out/serve.log" 2>&1 &
serve=$!
for _ in $(seq 100); do grep -q "vlab serve:" "$out/serve.log" 2>/dev/null && break; sleep 0.1; done
ip netns exec "$ctl" timeout 60 python3 "$controller" 169.254.77.1 50010 || { cat "$out/serve.log"; exit 1; }
wait "$serve"; status=$?
cat "$out/serve.log"
[ "$status" -eq 0 ] || { echo "vlab serve exited $status"; exit 1; }
python3 - "$out/run/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
arm = next(d for d in s["bridge"]["devices"] if d["name"] == "pa10")
assert s["result"] == "pass", s["failure"]
assert arm["address"] == "169.254.77.1", arm
assert arm["accepted"] == 500 and arm["refused"] == 0, arm
assert s["clock_stats"]["timeouts"] == 0, s["clock_stats"]
print("netns: controller in another namespace drove 500 lockstep periods across the veth link")
PY
