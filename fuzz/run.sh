#!/usr/bin/env bash
# The fuzz targets' driver, for `make fuzz` and the fuzz.* tests.
#   fuzz/run.sh build                      configure the fuzz preset (Clang) and build the targets
#   fuzz/run.sh replay TARGET              run every seed and every regression input once
#   fuzz/run.sh unit                       build the unit tests in the same build (Clang, ASan,
#                                          UBSan) and run them: texture, pbrt and render tests
#   fuzz/run.sh fuzz TARGET SECONDS [ci]   fuzz for SECONDS with the seeds and the dictionary;
#                                          crashing inputs go to fuzz/regressions/TARGET (with
#                                          ci: to build/fuzz/artifacts/TARGET; the corpus then
#                                          starts from the seeds each time)
# TARGET is parse, scene, ply, image, bsdf or filter; the binaries are build/fuzz/fuzz/fuzz_TARGET.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=build/fuzz

seeds() {  # the target's seed corpora (scene starts from the parser's scenes)
  case "$1" in
    scene) echo fuzz/corpus/parse ;;
    *) echo "fuzz/corpus/$1" ;;
  esac
}
dict() {
  case "$1" in
    parse | scene) echo "-dict=fuzz/parse.dict" ;;
    ply | image) echo "-dict=fuzz/$1.dict" ;;
  esac
}
regressions() { [[ -d "fuzz/regressions/$1" ]] && echo "fuzz/regressions/$1" || true; }

# Per input: 10 s at most, 1 GB per allocation and 2 GB in all, so hostile sizes fail fast.
LIMITS=(-timeout=10 -malloc_limit_mb=1024 -rss_limit_mb=2048)
export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=0:detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0}"

case "${1:-}" in
  build)
    cmake --preset fuzz >/dev/null
    cmake --build "$BUILD" --target cmam_fuzzers -j "${JOBS:-$(nproc)}"
    ;;
  unit)
    # scene_memory_test replaces operator new, which the sanitizers own: not run here.
    tests=(texture_test pbrt_test render_test)
    cmake --build "$BUILD" --target "${tests[@]}" -j "${JOBS:-$(nproc)}"
    for t in "${tests[@]}"; do
      echo "== $t (ASan, UBSan)"
      "$BUILD/tests/$t" --gtest_brief=1
    done
    ;;
  replay)
    t=$2
    # shellcheck disable=SC2046
    "$BUILD/fuzz/fuzz_$t" "${LIMITS[@]}" -runs=0 $(seeds "$t") $(regressions "$t")
    ;;
  fuzz)
    t=$2 seconds=$3
    extra=()
    if [[ "${4:-}" == ci ]]; then
      work="$BUILD/ci-corpus/$t" artifacts="$BUILD/artifacts/$t"
      rm -rf "$work"
      # A fixed seed: CI explores the same inputs on every run, so its result is reproducible.
      extra=(-seed=1)
    else
      work="$BUILD/corpus/$t" artifacts="fuzz/regressions/$t"
    fi
    mkdir -p "$work" "$artifacts"
    # New inputs go to the first directory (under build/), never to the seeds.
    # shellcheck disable=SC2046
    "$BUILD/fuzz/fuzz_$t" "${LIMITS[@]}" "${extra[@]}" $(dict "$t") -max_total_time="$seconds" \
      -print_final_stats=1 -artifact_prefix="$artifacts/" "$work" $(seeds "$t") $(regressions "$t")
    ;;
  *)
    sed -n '2,10p' "$0" >&2
    exit 2
    ;;
esac
