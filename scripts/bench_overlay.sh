#!/usr/bin/env bash
# Frames per second of `kccd overlay` (humanoid, 1280x720, static and --swept) next to a plain
# decode + encode of the same video with the same codec, measured in the same run.
# Usage: scripts/bench_overlay.sh [BUILD_DIR] [bench_overlay options: --frames N --jobs J --codec mp4v|MJPG|FFV1]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKCCD_BUILD_BENCHMARKS=ON >/dev/null
cmake --build "$build" -j "${KCCD_JOBS:-2}" --target bench_overlay kccd_cli
"$build/tests/bench/bench_overlay" "$build/overlay/kccd" "$@"
