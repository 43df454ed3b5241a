#!/usr/bin/env bash
# Runs a command inside a private network namespace (user namespace, loopback up, multicast
# routed to it), so LCM traffic never touches the host's network and tests can run side by
# side:   in_netns.sh COMMAND [ARGS...]
set -euo pipefail
if [ -z "${TANGENT_IN_NETNS:-}" ]; then
  export TANGENT_IN_NETNS=1
  exec unshare -rn bash "$0" "$@"
fi
ip link set lo up
ip route add 224.0.0.0/4 dev lo
exec "$@"
