#!/usr/bin/env bash
# Installs dependencies, builds with warnings as errors, checks formatting, runs every test and,
# beside them, a short run of each fuzzer.
# This is the README's test command and what CI runs.
#   bash scripts/test.sh [--under-load]
# --under-load keeps one core busy with another process (stress-ng --cpu 1, at normal priority)
# from the build to the end, as on a developer's laptop: the tests assert only what holds on
# any machine, however slow or loaded (docs/reliability.md, "What the real-time tests assert"),
# so they must pass like this too.
set -euo pipefail
cd "$(dirname "$0")/.."
under_load=
for a in "$@"; do
  case $a in
    --under-load) under_load=1 ;;
    *) echo "test.sh: unknown argument '$a' (expected --under-load)" >&2; exit 2 ;;
  esac
done
bash scripts/install-deps.sh
if [ -n "$under_load" ]; then
  stress-ng --cpu 1 --cpu-method matrixprod --quiet &
  load=$!
  trap 'kill "$load" 2>/dev/null || true; wait "$load" 2>/dev/null || true' EXIT
  echo "test.sh: one core kept busy by stress-ng --cpu 1 (pid $load) until the tests end"
fi
bash scripts/check-format.sh
TANGENT_BUILD_DIR=${TANGENT_BUILD_DIR:-build} bash scripts/build.sh -DTANGENT_WERROR=ON
# The fuzzers (build-fuzz/, clang) are built and then each run for 15 s with a fixed seed
# (docs/reliability.md: the fuzz build cannot rot) at nice 19 beside the tests: they take only
# what the tests leave of the two cores (the real-time tests run serially and mostly sleep
# between device periods), and the tests assert only what holds on a loaded machine anyway.
fuzz_log=${TANGENT_BUILD_DIR:-build}/fuzz.log
setsid nice -n 19 bash scripts/fuzz.sh --seconds 15 --seed 1 > "$fuzz_log" 2>&1 &
fuzz=$!  # (setsid: its own process group, so a failed ctest can stop the fuzzers at once)
status=0
(cd "${TANGENT_BUILD_DIR:-build}" && ctest --output-on-failure --parallel "$(nproc)" --timeout 600) ||
  status=$?
if [ "$status" -ne 0 ]; then
  kill -- "-$fuzz" 2>/dev/null || true
  wait "$fuzz" 2>/dev/null || true
  exit "$status"
fi
echo "test.sh: the tests passed; the fuzzers' build and short run (log $fuzz_log):"
fuzz_status=0
wait "$fuzz" || fuzz_status=$?
grep -E "^fuzz.sh|^-- |FINDING" "$fuzz_log" || true
if [ "$fuzz_status" -ne 0 ]; then
  tail -60 "$fuzz_log"
  echo "test.sh: the fuzzers failed (exit $fuzz_status; log $fuzz_log)" >&2
  exit 1
fi
