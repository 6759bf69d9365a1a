#!/usr/bin/env bash
# Reading a recording from a robot log (MCAP: JPEG frames, 1 kHz joint states) against reading the
# same frames from a video file and the states from a CSV, and `kccd overlay --bag` against the
# overlay of the files, measured in the same run.
# Usage: scripts/bench_bag.sh [BUILD_DIR] [bench_bag options: --frames N --repeat R --dir D]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
[ -d tests/bags/node_modules ] || (cd tests/bags && npm ci --no-audit --no-fund >/dev/null)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKCCD_BUILD_BENCHMARKS=ON >/dev/null
cmake --build "$build" -j "${KCCD_JOBS:-2}" --target bench_bag kccd_cli
"$build/tests/bench/bench_bag" "$build/overlay/kccd" "$(command -v node)" tests/bags/write_recording.mjs "$@"
