#!/usr/bin/env bash
# The multi-threaded render tests under ThreadSanitizer (CMake preset tsan, build/tsan, Clang).
# That build renders with std::thread workers and has Embree build its hierarchies on the calling
# thread (CMAM_STD_THREADS): the sanitizer cannot see the hand-offs inside Debian's
# uninstrumented oneTBB, and reports every one of them as a race. Any report fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset tsan >/dev/null
cmake --build build/tsan --target render_test -j "${JOBS:-$(nproc)}"
export TSAN_OPTIONS="${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1}"
build/tsan/tests/render_test --gtest_brief=1 \
  --gtest_filter='Determinism.*:Cmam.IdenticalImages*:Instancing.*:AreaLight.Images*:Memory.*'
