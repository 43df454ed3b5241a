#!/usr/bin/env bash
# Installs the browser code's packages (three.js for tangent-view) from npm, exactly as pinned by
# view/web/package-lock.json (npm ci). Skipped when node_modules is newer than the lockfile.
set -euo pipefail
cd "$(dirname "$0")/../view/web"
if [ -f node_modules/three/build/three.module.js ] && [ node_modules/.package-lock.json -nt package-lock.json ]; then
  echo "install-web: view/web/node_modules up to date"
  exit 0
fi
echo "install-web: npm ci (view/web, pinned by package-lock.json)"
npm ci --no-audit --no-fund --loglevel=error
