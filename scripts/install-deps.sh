#!/usr/bin/env bash
# Installs every build, test and benchmark dependency of Tangent from Debian's packages.
# Idempotent: apt-get skips what is already installed. Run as root on Debian 12 (bookworm).
set -euo pipefail

packages=(
  # Build tools.
  build-essential cmake ninja-build pkg-config git clang-format
  # LLVM's linker: our ~100 executables each link Open CASCADE, 6x faster than GNU ld.
  lld
  # Linear algebra (all of it: fixed-size in hot paths).
  libeigen3-dev
  # Mesh certification (self-intersection, Hausdorff, exact point-in-trim).
  libcgal-dev
  # BVH collision on offset meshes, broad phase.
  libfcl-dev
  # Transport and logging; liblcm-bin provides lcm-gen.
  liblcm-dev liblcm-bin
  # Tests and benchmarks.
  libgtest-dev libgmock-dev libbenchmark-dev
  # Scenes and command lines.
  nlohmann-json3-dev libcli11-dev
  # Peers for cross-checks and benchmarks: Open CASCADE, IPOPT, NLopt.
  # (OCCT's CMake config links libtbb.so, which only libtbb-dev provides.)
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev libtbb-dev
  # CAD import (tangent-import, cad/): Open CASCADE's STEP and IGES readers, through XCAF
  # documents (OCAF) for the files' names and colours.
  libocct-data-exchange-dev libocct-ocaf-dev
  coinor-libipopt-dev libnlopt-cxx-dev
  # Offline design runs across processes and machines (tangent-opt under mpirun), and their plots.
  libopenmpi-dev openmpi-bin python3-matplotlib
  # Fuzzing (scripts/fuzz.sh): clang with its libFuzzer and sanitizer runtimes.
  clang libclang-rt-14-dev
  # Instructions per servo tick, independent of the machine's load (scripts/bench_report.sh).
  valgrind
  # A core kept busy by another process (bash scripts/test.sh --under-load).
  stress-ng
  # The live 3D view (tangent-view): WebSocket server (websocketpp on standalone asio), PNG
  # reading in its browser test, and Chromium for snapshots and the test (headless, software
  # WebGL). three.js comes from npm, pinned by view/web/package-lock.json (scripts/install-web.sh).
  libwebsocketpp-dev libasio-dev libpng-dev chromium
)
# npm for the browser code: Debian's, unless this machine already has node and npm (NodeSource).
command -v npm >/dev/null 2>&1 || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  bash "$(dirname "$0")/install-web.sh"
  exit 0
fi

if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages (${missing[*]}); run this script as root" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
bash "$(dirname "$0")/install-web.sh"
