#!/usr/bin/env bash
# Builds the whole project with AddressSanitizer and UndefinedBehaviorSanitizer (gcc's; any
# finding aborts the test that made it) in build-asan/ and runs every test there.
#   bash scripts/sanitize.sh [ctest arguments, e.g. -R nurbs]
# Without arguments every test runs except the LCM process tests (server_integration.*,
# server_adversary.*): the instrumented tangentd answers a quarter fewer device states, so their
# answered-fraction criteria fail for speed, not for a finding. Run those for findings alone with
#   bash scripts/sanitize.sh -R "server_integration|server_adversary"
# and read the output for sanitizer reports (there were none on 2026-12-01).
# ASAN_OPTIONS/UBSAN_OPTIONS below make every report fatal and printed with a stack.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -DTANGENT_DEBUG_CHECKS"
TANGENT_BUILD_DIR=build-asan bash scripts/build.sh -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS=$flags" "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined"
# alloc_dealloc_mismatch=0: testing/alloc_counter.cc replaces operator new/delete with
# malloc/free for its counts; inline code in a shared library (FCL's BVH) can then allocate
# through the sanitizer's operator new[] and free through ours (free), a mismatch in name only.
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:strict_string_checks=1:alloc_dealloc_mismatch=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp"
cd build-asan
if [ $# -eq 0 ]; then set -- -E "server_integration|server_adversary"; fi
ctest --output-on-failure --parallel "$(nproc)" --timeout 1200 "$@"
