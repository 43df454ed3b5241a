#!/usr/bin/env bash
# Which device tangentd serves (issue 39, docs/server.md "Device sessions"), over real LCM in a
# private network namespace, one short tangentd per choice:
#   * the scene names no device and --device-id is not given: tangentd says so at start-up and
#     serves nothing (every state rejected_device, no answer);
#   * --device-id any: the first device that earns a session is served;
#   * --device-id 2 overrides the scene's device 1: device 1 is refused;
#   * a bad --device-id: a non-zero exit status and a message naming it.
#   device_choice.sh TANGENTD PHANTOM SCENES_DIR
set -euo pipefail
tangentd=$1 phantom=$2 scenes=$3
# shellcheck disable=SC2034  # (used by start_tangentd: $build/server/tangentd)
build=$(cd "$(dirname "$tangentd")/.." && pwd)
# shellcheck source=../../scripts/lib/live_server.sh
source "$(cd "$(dirname "$0")/../.." && pwd)/scripts/lib/live_server.sh"
in_private_netns "$0" "$@"
work=$(mktemp -d)
server_pid=
cleanup() {
  if [ -n "$server_pid" ]; then kill -INT "$server_pid" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
value() { grep -m1 "^$2=" "$1" | cut -d= -f2; }

# The four-bar (loads in a moment) without its device id.
grep -q '"id": 1' "$scenes/fourbar_point.json" || fail "fourbar_point.json no longer names device 1"
sed 's/"id": 1, *//' "$scenes/fourbar_point.json" > "$work/unnamed.json"
! grep -q '"id"' "$work/unnamed.json" || fail "could not remove the device id"

# run NAME SCENE PHANTOM_DEVICE_ID [TANGENTD ARGS...]: tangentd, 1.5 s of tangent-phantom, stop.
run() {
  local name=$1 scene=$2 id=$3
  shift 3
  start_tangentd "$work/$name.server" --scene "$scene" "$@"
  "$phantom" --duration 1.5 --trajectory hold --device-id "$id" > "$work/$name.phantom" 2>&1 || true
  kill -INT "$server_pid"
  wait "$server_pid" || fail "$name: tangentd exited with $?"
  server_pid=
  echo "$name: $(grep '^tangentd: serv\|^tangentd: NO' "$work/$name.server"); phantom sent" \
    "$(value "$work/$name.phantom" sent), answered $(value "$work/$name.phantom" answered);" \
    "server accepted $(value "$work/$name.server" device_messages), rejected_device" \
    "$(value "$work/$name.server" rejected_device), earning $(value "$work/$name.server" rejected_pending)"
}

run undeclared "$work/unnamed.json" 1
grep -q "^tangentd: NO DEVICE DECLARED: every device state is rejected" "$work/undeclared.server" ||
  fail "undeclared: no start-up message"
[ "$(value "$work/undeclared.server" device_messages)" -eq 0 ] || fail "undeclared: a state was accepted"
[ "$(value "$work/undeclared.phantom" answered)" -eq 0 ] || fail "undeclared: the client was answered"
[ "$(value "$work/undeclared.server" rejected_device)" -eq "$(value "$work/undeclared.phantom" sent)" ] ||
  fail "undeclared: not every state rejected as rejected_device"

run any "$work/unnamed.json" 5 --device-id any
grep -q "^tangentd: serving the first device that earns a session" "$work/any.server" ||
  fail "any: no start-up message"
[ "$(value "$work/any.server" sessions)" -eq 1 ] || fail "any: no session started"
[ "$(value "$work/any.phantom" answered)" -ge 1 ] || fail "any: the client was not answered"

run override "$scenes/fourbar_point.json" 1 --device-id 2
grep -q "^tangentd: serving device 2" "$work/override.server" || fail "override: no start-up message"
[ "$(value "$work/override.server" device_messages)" -eq 0 ] || fail "override: device 1 was served"
[ "$(value "$work/override.phantom" answered)" -eq 0 ] || fail "override: device 1 was answered"

status=0
"$tangentd" --scene "$scenes/fourbar_point.json" --device-id first > "$work/bad.out" 2>&1 || status=$?
[ "$status" -ne 0 ] || fail "a bad --device-id was accepted"
grep -q -- '--device-id: must be an integer (a device_state_t.device_id) or "any", got "first"' \
  "$work/bad.out" || { cat "$work/bad.out"; fail "a bad --device-id: no message naming it"; }
echo "bad --device-id: exit $status, $(grep -m1 'device-id must' "$work/bad.out")"
echo "device_choice: 4 cases as expected"
