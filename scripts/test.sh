#!/usr/bin/env bash
# Installs dependencies, builds with warnings as errors, checks formatting, runs every test and
# a short run of two fuzzers.
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
load='' fuzz_build=''
cleanup() {  # whatever ends the script stops what it started
  if [ -n "$fuzz_build" ]; then kill -- "-$fuzz_build" 2>/dev/null || true; wait "$fuzz_build" 2>/dev/null || true; fi
  if [ -n "$load" ]; then kill "$load" 2>/dev/null || true; wait "$load" 2>/dev/null || true; fi
}
trap cleanup EXIT
if [ -n "$under_load" ]; then
  stress-ng --cpu 1 --cpu-method matrixprod --quiet &
  load=$!
  echo "test.sh: one core kept busy by stress-ng --cpu 1 (pid $load) until the tests end"
fi
# Two of the five fuzzers, the NURBS reader and the CAD import (docs/reliability.md,
# "Fuzzing"), are built with clang, libFuzzer and the sanitizers (build-fuzz/) at nice 19 from
# here to the end of ctest, and then run for 15 s each with a fixed seed, so the fuzz build
# cannot rot. They need only the NURBS and CAD libraries: ~145 s of CPU, which fits in what the
# build and the tests leave of the two cores; all five need ~550 s, which trailed ctest by
# minutes. ctest replays all five harnesses over their seeds and kept findings (fuzz_replay.*),
# and `bash scripts/fuzz.sh` runs all five with clang. The fuzzers run after the tests, one per
# core: their -timeout is wall-clock time, which a starved process at nice 19 would exceed.
# The build is its own process group (set -m), so a failure can stop all of it; not its own
# session (setsid): with the kernel's autogroups, on by default, a new session is a new
# scheduling group that gets half the CPU whatever its nice value (measured: the fuzz build
# took half the cores from the main build at nice 19).
ci_fuzzers=(surface cad)
mkdir -p build-fuzz
fuzz_log=build-fuzz/build.log
set -m
nice -n 19 bash scripts/fuzz.sh --build-only "${ci_fuzzers[@]}" > "$fuzz_log" 2>&1 &
fuzz_build=$!
set +m
bash scripts/check-format.sh
TANGENT_BUILD_DIR=${TANGENT_BUILD_DIR:-build} bash scripts/build.sh -DTANGENT_WERROR=ON
(cd "${TANGENT_BUILD_DIR:-build}" && ctest --output-on-failure --parallel "$(nproc)" --timeout 600)
status=0
wait "$fuzz_build" || status=$?
fuzz_build=''
if [ "$status" -ne 0 ]; then cat "$fuzz_log"; echo "test.sh: the fuzz build failed" >&2; exit 1; fi
bash scripts/fuzz.sh --seconds 15 --seed 1 "${ci_fuzzers[@]}"
