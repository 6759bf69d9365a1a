#!/usr/bin/env bash
# The project's C++ habits, checked on the files a change touches: clang-format (.clang-format) and
# clang-tidy (.clang-tidy: bugprone-*, performance-*). A change is what differs from BASE (default
# HEAD~1, the last commit; KCCD_LINT_BASE or the first argument sets another). Tests and
# third-party code are formatted too; clang-tidy reads the sources of the libraries, the command
# and the Python module (file by file: a configure-only tree in build-lint with unity builds off).
# Exit 0 when clean; else each finding, and 1.
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:-${KCCD_LINT_BASE:-HEAD~1}}
if ! git rev-parse --verify -q "$base^{commit}" >/dev/null; then
  echo "lint.sh: $base: no such commit (nothing to compare with): checking every file" >&2
  base=$(git hash-object -t tree /dev/null)
fi
mapfile -t changed < <(git diff --name-only --diff-filter=ACMR "$base" -- '*.cpp' '*.hpp' '*.h' | grep -v '^tests/e2e/' || true)
if [ ${#changed[@]} -eq 0 ]; then
  echo "lint.sh: no C++ file changed since $base"
  exit 0
fi
status=0
echo "== clang-format: ${#changed[@]} file(s) changed since $base"
for f in "${changed[@]}"; do
  if ! clang-format --dry-run --Werror "$f" 2>/tmp/kccd-lint-format.$$; then
    head -20 /tmp/kccd-lint-format.$$
    echo "$f: not formatted (clang-format -i $f)"
    status=1
  fi
done
rm -f /tmp/kccd-lint-format.$$
mapfile -t sources < <(printf '%s\n' "${changed[@]}" | grep -E '\.cpp$' | grep -Ev '^(tests|examples)/' || true)
if [ ${#sources[@]} -gt 0 ]; then
  echo "== clang-tidy: ${#sources[@]} source file(s)"
  cmake -S . -B build-lint -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
    -DKCCD_UNITY_BUILD=OFF -DKCCD_BUILD_TESTS=OFF -DKCCD_BUILD_BENCHMARKS=OFF >/dev/null
  for f in "${sources[@]}"; do
    if ! clang-tidy -p build-lint --quiet "$f" 2>/dev/null; then
      echo "$f: clang-tidy findings above"
      status=1
    fi
  done
fi
[ $status -eq 0 ] && echo "lint.sh: clean"
exit $status
