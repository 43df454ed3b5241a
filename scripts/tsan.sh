#!/usr/bin/env bash
# ThreadSanitizer over the threaded code (docs/reliability.md "ThreadSanitizer"): the lock-free
# handoffs, the engine (servo and global-stage threads), the servo, the solver's one-problem-
# many-threads test, the design runner's threads, the LCM bridge's conversions and the LCM
# integration cases (tangentd and tangent-phantom, both instrumented, over real LCM in a private
# network namespace). Builds build-tsan/ with gcc's -fsanitize=thread; any report fails.
#   bash scripts/tsan.sh [ctest arguments]
# Our code needs no suppression: the seqlock holds its value in atomic words (server/lockfree.h
# says why). scripts/tsan.supp excuses one report inside GLib (not instrumented; LCM uses it),
# with its reason.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
flags="-fsanitize=thread -fno-omit-frame-pointer -g -O1"
tests=(lockfree_test engine_test servo_test servo_safety_test lcm_convert_test solver_test study_test)
mkdir -p build-tsan
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=TSan -DTANGENT_BUILD_BENCH=OFF \
  -DTANGENT_WITH_OCCT=OFF "-DCMAKE_CXX_FLAGS=$flags" "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=thread" \
  > build-tsan/configure.log 2>&1 || { cat build-tsan/configure.log; exit 1; }
cmake --build build-tsan --parallel "$(nproc)" --target "${tests[@]}" tangentd tangent-phantom
# halt_on_error: the first report ends the program with exit code 66 and fails its test.
export TSAN_OPTIONS="halt_on_error=1 exitcode=66 second_deadlock_stack=1 suppressions=$PWD/scripts/tsan.supp"
export TANGENT_SANITIZER_RUN=1
cd build-tsan
if [ $# -eq 0 ]; then
  set -- -R "^(LockFreeTest|EngineTest|ServoTest|ServoSafetyTest|LcmConvertTest|SolverTest\.OneProblem|StudyTest|server_integration)"
fi
ctest --output-on-failure --timeout 1200 "$@"
