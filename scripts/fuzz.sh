#!/usr/bin/env bash
# Fuzzes the scene parser, the NURBS JSON reader, the run-file parser, the server's
# device-message path and the CAD import (STEP/IGES through Open CASCADE) with libFuzzer (clang from Debian), AddressSanitizer and
# UndefinedBehaviorSanitizer (docs/reliability.md "Fuzzing").
#   bash scripts/fuzz.sh [--seconds N] [--seed S] [--build-only] [scene surface run device cad]
# Builds build-fuzz/ (clang, the fuzz targets asked for and the libraries they need), seeds each
# target's corpus (build-fuzz/corpus/<target>, kept between runs so coverage accumulates) from
# scenes/, the seed writer and the kept findings (fuzz/regressions/<target>), then runs each
# target for N seconds (default 600), one per core at a time. A crash, a hang (> 10 s on one
# input), an input using more than 2 GB, an uncaught exception or a sanitizer report stops that target: its input is written
# to build-fuzz/findings/<target>/ and the script exits non-zero after the others ran. Keep a
# finding as a regression: copy it to fuzz/regressions/<target>/ (ctest replays it).
# --build-only stops after the build (scripts/test.sh builds the fuzzers at nice 19 while ctest
# runs, so the build takes only what the tests leave of the two cores).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=600
seed_args=()
targets=()
build_only=
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --seed) seed_args=(-seed="$2"); shift 2 ;;  # libFuzzer's mutation seed (CI: fixed)
    --build-only) build_only=1; shift ;;
    scene|surface|run|device|cad) targets+=("$1"); shift ;;
    *) echo "fuzz.sh: unknown argument '$1' (expected --seconds N, --seed S, --build-only or scene|surface|run|device|cad)" >&2
       exit 2 ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=(scene surface run device cad)

bash scripts/install-deps.sh
# -O2 with line tables: Eigen-heavy code (the solver on the device path) runs some 10x slower at
# -O1, whose inlining is too weak for its expression templates; line tables keep stacks readable.
flags="-O2 -gline-tables-only -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined"
flags+=" -fno-sanitize-recover=undefined"
mkdir -p build-fuzz
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Fuzz -DCMAKE_CXX_COMPILER=clang++ \
  -DTANGENT_FUZZ=ON -DTANGENT_BUILD_TESTS=OFF -DTANGENT_BUILD_BENCH=OFF -DTANGENT_WITH_OCCT=ON \
  -DTANGENT_WITH_MPI=OFF "-DCMAKE_CXX_FLAGS=$flags" \
  "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" > build-fuzz/configure.log 2>&1 ||
  { cat build-fuzz/configure.log; exit 1; }
seeders=(tangent-fuzz-seeds)
[[ " ${targets[*]} " == *" cad "* ]] && seeders+=(tangent-cad-seeds)
cmake --build build-fuzz --parallel "$(nproc)" --target "${seeders[@]}" \
  "${targets[@]/%/_fuzzer}"
[ -z "$build_only" ] || exit 0

# Open CASCADE's one-time allocations (static registries, never freed by design) are not ours.
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp"
cd build-fuzz
mkdir -p seeds/surface seeds/device
./fuzz/tangent-fuzz-seeds surface seeds/surface
./fuzz/tangent-fuzz-seeds device seeds/device
if [ -x fuzz/tangent-cad-seeds ] && [[ " ${targets[*]} " == *" cad "* ]]; then
  ./fuzz/tangent-cad-seeds seeds/cad > /dev/null
fi
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# Inputs up to the largest example (scenes, run files) or a few hundred ticks (device scripts).
# CAD files: the seeds are 10–40 kB.
max_len() { case "$1" in device) echo 4096 ;; cad) echo 131072 ;; *) echo 65536 ;; esac; }
# One target per core at a time (each gets its own core: -timeout is wall-clock time).
fuzz_one() {
  local t=$1 corpus=corpus/$1
  if ./fuzz/${t}_fuzzer "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len="$(max_len "$t")" -print_final_stats=1 "${seed_args[@]}" -artifact_prefix="findings/$t/" \
      > "fuzz-$t.log" 2>&1; then
    { grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "fuzz-$t.log" | tr '\n' ' '
      echo "-- $t: no finding"; } > "fuzz-$t.summary"
  else
    { tail -40 "fuzz-$t.log"
      echo "-- $t: FINDING in build-fuzz/findings/$t/ (log build-fuzz/fuzz-$t.log)"; } > "fuzz-$t.summary"
    return 1
  fi
}
jobs_max=$(nproc)
declare -A pid_of=()
for t in "${targets[@]}"; do
  corpus=corpus/$t
  mkdir -p "$corpus" "findings/$t"
  case $t in
    scene) find ../scenes -maxdepth 1 -name '*.json' ! -name '*.run.json' -exec cp -n {} "$corpus" \; ;;
    run) cp -n ../scenes/*.run.json "$corpus" ;;
    surface) cp -n seeds/surface/* "$corpus" ;;
    device) cp -n seeds/device/* "$corpus" ;;
    cad) cp -n seeds/cad/* "$corpus" ;;
  esac
  find "../fuzz/regressions/$t" -type f ! -name .keep -exec cp -n {} "$corpus" \;
  echo "fuzz.sh: $t for ${seconds} s ($(find "$corpus" -type f | wc -l) inputs in the corpus)"
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
  fuzz_one "$t" &
  pid_of[$t]=$!
done
failed=()
for t in "${targets[@]}"; do
  wait "${pid_of[$t]}" || failed+=("$t")
  cat "fuzz-$t.summary"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: findings in ${failed[*]}" >&2
  exit 1
fi
echo "fuzz.sh: ${targets[*]}: 0 findings in ${seconds} s each"
