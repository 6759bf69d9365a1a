#!/usr/bin/env bash
# Builds KCCD and runs the whole test suite: a Release build and its tests, the documentation site
# (scripts/docs.sh: a warning fails), then the same tests under
# AddressSanitizer + UndefinedBehaviorSanitizer, then every libFuzzer target briefly. The
# sanitizer build is GCC at -O1 -g1 (the reports' stacks keep files and lines; its tests run 1.3x
# faster than clang-14's ASan at -O1, 1.8x faster than with libFuzzer's coverage too, so the fuzz
# targets keep their own clang build, scripts/fuzz.sh; the numeric core, libkccd with its hull and
# modelling parts, at -O2: CMakeLists.txt's kccd_numeric_core), and its statistical tests draw fewer cases
# (tests/support/sanitized.hpp). After the Release build, scripts/lint.sh checks the C++ files of
# the last commit with clang-format and clang-tidy. GCC 12 at -O1 with the sanitizers warns falsely about
# std::function inside <regex> (maybe-uninitialized): that warning is off there. Each stage's time
# is printed at the end. Options:
#   --no-sanitize   skip the sanitizer build
#   --sanitize-only run only the sanitizer build and its tests, then the fuzz targets
#   --no-fuzz       skip the fuzz targets (scripts/fuzz.sh)
#   --packages      also build the Debian packages from the Release build (scripts/package.sh),
#                   install them on this machine, use them and remove them (scripts/package_test.sh;
#                   as root or through sudo: CI does it on its own machine)
# Environment: KCCD_JOBS (default 2), KCCD_SOAK=N for a long property-test soak.
set -euo pipefail
cd "$(dirname "$0")/.."
release=1 sanitize=1 fuzz=1 packages=0
for arg in "$@"; do
  case "$arg" in
    --no-sanitize) sanitize=0 ;;
    --sanitize-only) release=0 ;;
    --no-fuzz) fuzz=0 ;;
    --packages) packages=1 ;;
    *) echo "test.sh: unknown option $arg" >&2; exit 2 ;;
  esac
done
jobs=${KCCD_JOBS:-2}
stages=()
stage() {  # name, command...: runs the command and keeps its time for the summary
  local name=$1 start=$SECONDS; shift
  echo "== $name"
  local rc=0
  "$@" || rc=$?
  stages+=("$(printf '%5d s  %s%s' $((SECONDS - start)) "$name" "$([ $rc -eq 0 ] || echo ": FAILED ($rc)")")")
  [ $rc -eq 0 ] || exit $rc
}
summary() {
  echo "== Stage times"
  for s in "${stages[@]}"; do echo "$s"; done
  printf '%5d s  total\n' "$SECONDS"
}
trap summary EXIT
cmake_build() {  # build dir, cmake args...
  local dir=$1; shift
  cmake -S . -B "$dir" -G Ninja "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
}
deps=(--tests --docs)
[ $fuzz -eq 1 ] && deps+=(--fuzz)
stage "Installing dependencies" bash scripts/install-deps.sh "${deps[@]}"
if [ $release -eq 1 ]; then
  stage "Release build" cmake_build build -DCMAKE_BUILD_TYPE=Release
  stage "Lint: the last commit's C++ files (clang-format, clang-tidy)" bash scripts/lint.sh
  stage "Release tests" ctest --test-dir build -j "$jobs" --output-on-failure
  stage "Documentation site (warnings are errors)" bash scripts/docs.sh build
  if [ $packages -eq 1 ]; then
    stage "Debian packages (scripts/package.sh)" bash scripts/package.sh build
    stage "Packages installed, used as a user would, removed" bash scripts/package_test.sh
  fi
fi
if [ $sanitize -eq 1 ]; then
  stage "ASan + UBSan build" cmake_build build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKCCD_SANITIZE=ON \
    -DKCCD_BUILD_BENCHMARKS=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG -Wno-maybe-uninitialized"
  # intercept_tls_get_addr=0: with libraries opened at run time that use dynamic TLS (EGL's driver,
  # LLVM), GCC 12's LeakSanitizer recorded a bogus range for it here (from 0x2d8a) and its tracer
  # crashed at exit ("Tracer caught signal 11"); without the interception that TLS is not scanned,
  # which can only add leak reports (inside Mesa and LLVM: suppressed), never hide one.
  stage "ASan + UBSan tests" env ASAN_OPTIONS=detect_leaks=1:intercept_tls_get_addr=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 \
    ctest --test-dir build-asan -j "$jobs" --output-on-failure
fi
if [ $fuzz -eq 1 ]; then
  stage "libFuzzer targets (a fixed seed and number of inputs each)" bash scripts/fuzz.sh --ci
fi
