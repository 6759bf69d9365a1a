#!/usr/bin/env bash
# Start-up time of the light subcommands: `kccd --version`, `kccd info` and `kccd query` (the
# launcher, which loads libkccd's few libraries) next to the same command lines run by kccd-all
# (the whole program, every library of the suite loaded: what `kccd` was before the launcher), in
# one run, interleaved, the median and 90th percentile of N runs each (default 25), wall time.
# Usage: scripts/bench_startup.sh [BUILD_DIR] [N]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
runs=${2:-25}
cmake --build "$build" -j "${KCCD_JOBS:-2}" --target kccd_cli >/dev/null
/usr/bin/python3 - "$build/overlay/kccd" "$build/overlay/kccd-all" "$runs" <<'PY'
import statistics, subprocess, sys, time
light, whole, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
cases = [("--version", ["--version"]), ("info", ["info", "data/humanoid.yaml"]),
         ("query", ["query", "data/humanoid.yaml", "--state", ",".join(["0"] * 20)])]
def once(program, args):
    t = time.perf_counter()
    subprocess.run([program] + args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t
print(f"{'command':<12}{'kccd-all median':>18}{'kccd median':>14}{'kccd p90':>11}{'ratio':>8}")
for name, args in cases:
    times = {light: [], whole: []}
    for _ in range(runs):
        for program in (whole, light):
            times[program].append(once(program, args))
    w, l = statistics.median(times[whole]), statistics.median(times[light])
    p90 = sorted(times[light])[int(0.9 * (runs - 1))]
    print(f"{'kccd ' + name:<12}{w * 1e3:>15.1f} ms{l * 1e3:>11.1f} ms{p90 * 1e3:>8.1f} ms{w / l:>7.1f}x")
PY
