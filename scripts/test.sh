#!/usr/bin/env bash
# Builds KCCD and runs the whole test suite: a Release build, then the same tests under
# AddressSanitizer + UndefinedBehaviorSanitizer, then every libFuzzer target briefly. The
# sanitizer build is -O1 -g1 (the reports' stacks keep files and lines; with GCC 12 the heaviest
# file compiles in 30 s instead of 61 s at -O2 -g), and its statistical tests draw fewer cases
# (tests/support/sanitized.hpp). GCC 12 at -O1 with the sanitizers warns falsely about
# std::function inside <regex> (maybe-uninitialized): that warning is off there. Options:
#   --no-sanitize   skip the sanitizer build
#   --sanitize-only run only the sanitizer build
#   --no-fuzz       skip the fuzz targets (scripts/fuzz.sh)
# Environment: KCCD_JOBS (default 2), KCCD_SOAK=N for a long property-test soak.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh --tests
jobs=${KCCD_JOBS:-2}
release=1 sanitize=1 fuzz=1
for arg in "$@"; do
  case "$arg" in
    --no-sanitize) sanitize=0 ;;
    --sanitize-only) release=0 ;;
    --no-fuzz) fuzz=0 ;;
    *) echo "test.sh: unknown option $arg" >&2; exit 2 ;;
  esac
done
run() {  # build dir, extra cmake args...
  local dir=$1; shift
  cmake -S . -B "$dir" -G Ninja "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
  ctest --test-dir "$dir" -j "$jobs" --output-on-failure
}
if [ $release -eq 1 ]; then
  echo "== Release build and tests"
  run build -DCMAKE_BUILD_TYPE=Release
fi
if [ $sanitize -eq 1 ]; then
  echo "== ASan + UBSan build and tests"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 \
    run build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKCCD_SANITIZE=ON -DKCCD_BUILD_BENCHMARKS=OFF \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG -Wno-maybe-uninitialized"
fi
if [ $fuzz -eq 1 ]; then
  echo "== libFuzzer targets (a fixed seed and number of inputs each)"
  bash scripts/fuzz.sh --ci
fi
