#!/usr/bin/env bash
# Installs dependencies, builds with warnings as errors, checks formatting, runs every test and
# a short run of each fuzzer.
# This is the README's test command and what CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/check-format.sh
TANGENT_BUILD_DIR=${TANGENT_BUILD_DIR:-build} bash scripts/build.sh -DTANGENT_WERROR=ON
cd "${TANGENT_BUILD_DIR:-build}"
ctest --output-on-failure --parallel "$(nproc)" --timeout 600
cd - > /dev/null
# A short run of every fuzzer (docs/reliability.md), with a fixed seed: the fuzz build cannot rot.
bash scripts/fuzz.sh --seconds 15 --seed 1
