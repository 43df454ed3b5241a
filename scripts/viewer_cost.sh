#!/usr/bin/env bash
# What an attached viewer costs the server (issue 20): the demo run alternately without a viewer,
# with tangent-view alone (subscribed, serving no browser) and with tangent-view and a headless
# Chromium rendering its live view (software WebGL: on this machine the browser's drawing takes
# CPU from the same two cores the server runs on), same machine, same minutes.
# Reports tangentd's round trip (tangent-phantom's latency p50 minus the bare LCM ping p50) and
# its servo tick p99 (compute_p99_us); each round runs the three in turn (order alternating), and
# the change is the median over rounds of the round's difference (paired, so the machine's
# slower drifts cancel).
#   bash scripts/viewer_cost.sh [--rounds N] [--seconds S]      (default 5 rounds of 10 s)
# With --bridge it measures instead what the bridge's viewer publishing costs with no viewer
# attached (issue 35): tangentd with the viewer URL off (--view-lcm-url "") against the default
# (on, ~30 Hz of scene, contacts and statistics), paired the same way.
# Runs in a private network namespace (LCM multicast on loopback only). Needs a build.
# The costs are reported, never judged here (they depend on the machine: docs/viewer.md has the
# measured figures); what holds on any machine is checked on every run, and fails the script:
# every wrench finite, within max_force and the rate limit, and the accounting closed by counter
# (scripts/lib/accounting.sh), with a viewer attached or not.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=lib/accounting.sh
source scripts/lib/accounting.sh
rounds=5 seconds=10 bridge=
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) rounds=$2; shift 2 ;;
    --seconds) seconds=$2; shift 2 ;;
    --bridge) bridge=--bridge; shift ;;
    *) echo "usage: $0 [--rounds N] [--seconds S] [--bridge]" >&2; exit 2 ;;
  esac
done
build=${TANGENT_BUILD_DIR:-build}
if [ -z "${TANGENT_IN_NETNS:-}" ]; then
  export TANGENT_IN_NETNS=1
  exec unshare -rn bash "$0" --rounds "$rounds" --seconds "$seconds" $bridge
fi
ip link set lo up
ip route add 224.0.0.0/4 dev lo
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT

run() {  # run ROUND with|without -> appends "mode latency_minus_ping p99" to $work/results
  local mode=$2 out="$work/$1-$2"
  local url=()
  [ "$mode" = quiet ] && url=(--view-lcm-url "")  # the bridge publishes nothing for viewers
  "$build/server/tangentd" --scene scenes/paperclips.json "${url[@]}" > "$out.server" 2>&1 &
  local server=$!
  for _ in $(seq 600); do
    grep -q "^tangentd: scene" "$out.server" && break
    kill -0 "$server" 2>/dev/null || { cat "$out.server"; echo "tangentd died at load"; exit 1; }
    sleep 0.1
  done
  local view=
  if [ "$mode" = view ] || [ "$mode" = with ]; then
    local browser=--headless
    [ "$mode" = with ] || browser=
    "$build/view/tangent-view" --scene scenes/paperclips.json --port 0 $browser > "$out.view" 2>&1 &
    view=$!
    # The browser connected (it starts as SCHED_IDLE: on a busy machine that takes a while), and
    # a second for it to take the meshes and draw, before the hand moves.
    if [ "$mode" = with ]; then
      for _ in $(seq 1 300); do grep -q "browser connected" "$out.view" && break; sleep 0.1; done
      grep -q "browser connected" "$out.view" || echo "round $1: the browser did not connect in 30 s"
    fi
    sleep 1
  fi
  "$build/server/tangent-phantom" --duration "$seconds" --trajectory drag > "$out.phantom" 2>&1
  local frames=-
  if [ -n "$view" ]; then
    kill -INT "$view"; wait "$view" || true
    frames=$(grep -o 'frames_sent=[0-9]*' "$out.view" | cut -d= -f2)
  fi
  kill -INT "$server"; wait "$server" || true
  local key
  for key in bad_wrenches over_max_force over_rate_limit; do
    [ "$(grep -m1 "^$key=" "$out.phantom" | cut -d= -f2)" = 0 ] ||
      { echo "round $1 $mode: $key=$(grep -m1 "^$key=" "$out.phantom" | cut -d= -f2)"; failed=1; }
  done
  check_accounting "$out.server" "$out.phantom" > "$out.accounting" ||
    { echo "round $1 $mode: $(tail -1 "$out.accounting")"; failed=1; }
  local lat p99
  lat=$(grep -m1 '^latency_minus_ping_p50_us=' "$out.phantom" | cut -d= -f2)
  p99=$(grep -m1 '^compute_p99_us=' "$out.server" | cut -d= -f2)
  echo "$1 $mode $lat $p99" >> "$work/results"
  printf 'round %d %-7s round trip - ping p50 %6.1f us   tick p99 %6.2f us   frames to the browser %s\n' \
    "$1" "$mode" "$lat" "$p99" "$frames"
}
failed=0
for r in $(seq 1 "$rounds"); do
  if [ -n "$bridge" ]; then
    if [ $((r % 2)) -eq 1 ]; then run "$r" quiet; run "$r" without; else run "$r" without; run "$r" quiet; fi
  elif [ $((r % 2)) -eq 1 ]; then
    run "$r" without; run "$r" view; run "$r" with
  else
    run "$r" with; run "$r" view; run "$r" without
  fi
done
/usr/bin/python3 - "$work/results" "$bridge" <<'PY'
import statistics, sys
runs = {}
for line in open(sys.argv[1]):
    r, mode, lat, p99 = line.split()
    runs.setdefault(int(r), {})[mode] = (float(lat), float(p99))
base_mode, modes = ("quiet", (("without", "viewer URL on, no viewer"),)) if sys.argv[2] else \
    ("without", (("view", "tangent-view alone"), ("with", "tangent-view + headless browser")))
base = [v[base_mode] for v in runs.values()]
print(f"{'viewer URL off' if sys.argv[2] else 'without a viewer'}: round trip - ping p50 median "
      f"{statistics.median(b[0] for b in base):.1f} us, "
      f"tick p99 median {statistics.median(b[1] for b in base):.2f} us")
for mode, name in modes:
    dl = [v[mode][0] - v[base_mode][0] for v in runs.values()]
    dp = [100 * (v[mode][1] / v[base_mode][1] - 1) for v in runs.values()]
    print(f"{name}: round trip change median {statistics.median(dl):+.1f} us "
          f"(rounds {min(dl):+.1f} .. {max(dl):+.1f}; limit 5 us), tick p99 change median "
          f"{statistics.median(dp):+.1f} % (rounds {min(dp):+.1f} .. {max(dp):+.1f}; limit 5 %)")
PY
[ "$failed" -eq 0 ] || { echo "viewer_cost.sh: a run broke the safety contract or the accounting (above)"; exit 1; }
echo "viewer_cost.sh: every run: 0 wrenches non-finite, over max_force or the rate limit; accounting closed"
