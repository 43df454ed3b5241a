#!/usr/bin/env bash
# The main job: the live demo. Installs and builds, then starts tangentd with the three-paperclip
# scene and tangent-phantom dragging the chain with its built-in "drag" trajectory, shows a live
# one-line status (progress, loop rate, contacts, force), and ends with both summaries.
#
# Both processes run inside a private network namespace (unshare -rn; loopback up and multicast
# routed to it), so LCM's UDP multicast works on any machine and nothing leaves this host.
#   DEMO_SECONDS=20 bash scripts/demo.sh
#   DEMO_SCENE=peg_in_hole bash scripts/demo.sh   (any scenes/NAME.json; a scenes/NAME.path.csv
#                                                 beside it is the hand's path, else "drag")
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${TANGENT_DEMO_IN_NETNS:-}" ]; then
  bash scripts/install-deps.sh
  bash scripts/build.sh
  export TANGENT_DEMO_IN_NETNS=1
  exec unshare -rn bash "$0" "$@"
fi
ip link set lo up
ip route add 224.0.0.0/4 dev lo
seconds=${DEMO_SECONDS:-20}
scene=${DEMO_SCENE:-paperclips}
[ -f "scenes/$scene.json" ] || { echo "DEMO_SCENE: no scenes/$scene.json" >&2; exit 2; }
trajectory=drag
[ -f "scenes/$scene.path.csv" ] && trajectory="scenes/$scene.path.csv"
work=$(mktemp -d)
cleanup() {
  if [ -n "${view:-}" ]; then kill -INT "$view" 2>/dev/null || true; fi
  if [ -n "${server:-}" ]; then kill -INT "$server" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

echo "== tangentd: loading scenes/$scene.json (offset meshes certified by CGAL)"
./build/server/tangentd --scene "scenes/$scene.json" --log build/tangentd.log > "$work/server.out" 2>&1 &
server=$!
until grep -q "^tangentd: scene" "$work/server.out"; do
  kill -0 "$server" 2>/dev/null || { cat "$work/server.out"; exit 1; }
  sleep 0.1
done
cat "$work/server.out"
# The live 3D view (docs/viewer.md): in a browser window when there is a display; without one, a
# snapshot PNG of the view is written when the hand has finished (so the browser's software
# rendering does not share the cores with the run being measured).
view=
if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ -z "${DEMO_NO_VIEW:-}" ]; then
  ./build/view/tangent-view --scene "scenes/$scene.json" --open > "$work/view.out" 2>&1 &
  view=$!
  echo "== tangent-view: the live view opens in a browser window"
fi
if [ "$trajectory" = drag ]; then
  echo "== tangent-phantom: a simulated hand drags the grasped part for ${seconds} s (lift 6 mm, then circles)"
else
  echo "== tangent-phantom: a simulated hand follows $trajectory for ${seconds} s"
fi
./build/server/tangent-phantom --duration "$seconds" --trajectory "$trajectory" --status \
  --log build/phantom.csv > "$work/phantom.out"
if [ -z "$view" ] && [ -z "${DEMO_NO_VIEW:-}" ]; then
  echo "== tangent-view: no display; a snapshot of the view where the hand stopped"
  if ./build/view/tangent-view --scene "scenes/$scene.json" --port 0 --timeout 60 \
       --snapshot "build/demo-view-$scene.png" > "$work/view.out" 2>&1; then
    echo "view snapshot: build/demo-view-$scene.png"
  else
    cat "$work/view.out"
    echo "view snapshot failed (the demo's results below stand)"
  fi
fi
if [ -n "$view" ]; then
  echo "== tangent-view: close the browser window or press Enter to end"
  read -r -t 600 _ || true
  kill -INT "$view" 2>/dev/null || true
  wait "$view" || true
  view=
fi
kill -INT "$server"
wait "$server"
server=
echo
echo "== tangent-phantom summary (CSV of every step: build/phantom.csv)"
cat "$work/phantom.out"
echo
echo "== tangentd summary (log: build/tangentd.log)"
sed -n '/^tangentd summary:/,$p' "$work/server.out"
