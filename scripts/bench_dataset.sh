#!/usr/bin/env bash
# `kccd check` on a 1 kHz joint log (default one hour, 3.6 M samples, static collision query) against
# the plain query loop over the same samples, and a LeRobot episode's state rows read from Parquet
# against the same rows parsed from a CSV, measured in the same run.
# Usage: scripts/bench_dataset.sh [BUILD_DIR] [bench_dataset options: --model M --samples N --rows R --repeat K --dir D]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
[ -d tests/datasets/node_modules/parquet-wasm ] || (cd tests/datasets && npm ci --no-audit --no-fund >/dev/null)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKCCD_BUILD_BENCHMARKS=ON >/dev/null
cmake --build "$build" -j "${KCCD_JOBS:-2}" --target bench_dataset
"$build/tests/bench/bench_dataset" "$(command -v node)" tests/datasets/write_lerobot.mjs "$@"
