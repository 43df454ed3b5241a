#!/usr/bin/env bash
# Runs the offline design examples (scenes/*.run.json) with tangent-opt and draws their plots
# into docs/img/ (docs/offline.md). Builds first; needs python3-matplotlib from Debian
# (scripts/install-deps.sh). Takes about a minute on two cores (the map's 1764 cases most of it).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh > /dev/null
out=build/design-examples
mkdir -p "$out" docs/img
for run in three_link_finger fourbar_dexterity three_link_finger_design fourbar_force_transmission \
  three_link_finger_map; do
  build/design/tangent-opt "scenes/$run.run.json" -o "$out/$run.result.json"
done
# Debian's interpreter (its matplotlib), whatever python3 comes first on PATH.
/usr/bin/python3 scripts/plot_design.py "$out/three_link_finger.result.json" \
  --map "$out/three_link_finger_map.result.json" -o docs/img
/usr/bin/python3 scripts/plot_design.py "$out/fourbar_dexterity.result.json" -o docs/img
/usr/bin/python3 scripts/plot_design.py "$out/three_link_finger_design.result.json" -o docs/img
/usr/bin/python3 scripts/plot_design.py "$out/fourbar_force_transmission.result.json" -o docs/img
