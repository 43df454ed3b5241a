# Shared by scripts/faults.sh and scripts/soak.sh (sourced, not run): a private network
# namespace for LCM and a tangentd started in it.

# Re-runs the calling script in a user + network namespace with loopback up and multicast
# routed to it, so nothing touches the host's network. Call as: in_private_netns "$0" "$@"
in_private_netns() {
  if [ -z "${TANGENT_IN_NETNS:-}" ]; then
    export TANGENT_IN_NETNS=1
    exec unshare -rn bash "$@"
  fi
  ip link set lo up
  ip route add 224.0.0.0/4 dev lo
}

# start_tangentd OUT_FILE TANGENTD_ARGS...: starts tangentd in the background, sets
# $server_pid, and returns once its scene is loaded (exits the script if it dies loading).
start_tangentd() {
  local out=$1
  shift
  : > "$out"  # exists before the first grep below (the background redirect may come later)
  "$build/server/tangentd" "$@" > "$out" 2>&1 &
  server_pid=$!
  for _ in $(seq 600); do
    grep -q "^tangentd: scene" "$out" && return 0
    kill -0 "$server_pid" 2>/dev/null || { cat "$out"; echo "tangentd died at load"; exit 1; }
    sleep 0.1
  done
  echo "tangentd did not load its scene in 60 s"; exit 1
}
