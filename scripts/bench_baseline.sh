#!/usr/bin/env bash
# Query times of the current tree against a baseline commit, both builds measured in one run:
# builds bench_engine of REF in a temporary git worktree and build folder, builds the current
# tree's bench_engine, then runs the two alternately (ROUNDS rounds each, the order flipped every
# round so that a change in machine load hits both alike) and prints per benchmark the median of
# the rounds' p50 for each build and the ratio current / baseline (< 1: the current tree is faster).
#
# Usage: scripts/bench_baseline.sh [REF]
#   REF      baseline commit (default f4000ba, main when this script was written)
# Environment:
#   BUILD               the current tree's build folder (default build; configured if missing)
#   ROUNDS              runs of each binary (default 3)
#   KCCD_BENCH_BUDGET   point budget given to both builds (default 12, the sample models' own)
#   FILTER              bench_engine benchmarks to run (default: collision and distances queries)
#   KCCD_JOBS           build jobs (default 2)
#   KCCD_BUILD_LOCK     lock file every build holds (default /tmp/kccd-build.lock)
#   KEEP=1              keep the temporary worktree and build folder (their path is printed)
# Each build uses its own data/ models (compiled in); when REF's models differ, so do the queries.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

ref=${1:-f4000bad58df6c4fc96ae5c24cc8587437688f3a}
build=${BUILD:-build}
rounds=${ROUNDS:-3}
export KCCD_BENCH_BUDGET=${KCCD_BENCH_BUDGET:-12}
filter=${FILTER:-'BM_Query/.*/type:(0|3)/'}
jobs=${KCCD_JOBS:-2}
lock=${KCCD_BUILD_LOCK:-/tmp/kccd-build.lock}

commit=$(git rev-parse --verify --quiet "$ref^{commit}") || { echo "bench_baseline: unknown commit '$ref'" >&2; exit 2; }
case $rounds in '' | *[!0-9]* | 0) echo "bench_baseline: ROUNDS must be a whole number >= 1, got '$rounds'" >&2; exit 2 ;; esac

tmp=$(mktemp -d /tmp/kccd-baseline.XXXXXX)
cleanup() {
  if [[ ${KEEP:-0} == 1 ]]; then
    echo "bench_baseline: kept $tmp" >&2
  else
    git -C "$root" worktree remove --force "$tmp/src" 2>/dev/null || true
    rm -rf "$tmp"
  fi
}
trap cleanup EXIT

echo "bench_baseline: baseline $(git log -1 --format='%h %s' "$commit" | cut -c1-90)" >&2
git worktree add --quiet --detach "$tmp/src" "$commit"
if ! grep -q KCCD_BENCH_BUDGET "$tmp/src/tests/bench/bench_engine.cpp"; then
  echo "bench_baseline: warning: the baseline's bench_engine ignores KCCD_BENCH_BUDGET (uses its models' budget)" >&2
fi

# Only libkccd and the benchmark are needed for the baseline: the other parts stay off.
cmake -S "$tmp/src" -B "$tmp/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKCCD_BUILD_TOOLS=OFF >/dev/null
[[ -f $build/CMakeCache.txt ]] || cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
echo "bench_baseline: building (waiting for $lock)" >&2
flock "$lock" cmake --build "$tmp/build" -j "$jobs" --target bench_engine >/dev/null
flock "$lock" cmake --build "$build" -j "$jobs" --target bench_engine >/dev/null

baseline_bin=$tmp/build/tests/bench/bench_engine
current_bin=$build/tests/bench/bench_engine
run() {  # which round
  local bin=$baseline_bin
  [[ $1 == current ]] && bin=$current_bin
  echo "bench_baseline: round $2, $1" >&2
  if ! "$bin" --benchmark_filter="$filter" --benchmark_out="$tmp/$1.$2.json" --benchmark_out_format=json \
      >/dev/null 2>"$tmp/$1.$2.log"; then
    cat "$tmp/$1.$2.log" >&2
    echo "bench_baseline: the $1 bench_engine failed" >&2
    exit 1
  fi
}
for ((r = 1; r <= rounds; ++r)); do
  if ((r % 2 == 1)); then run baseline "$r"; run current "$r"; else run current "$r"; run baseline "$r"; fi
done

python3 - "$tmp" "$rounds" "$commit" "$KCCD_BENCH_BUDGET" <<'EOF'
import json, statistics, sys

folder, rounds, commit, budget = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]

def p50s(which):
    """Per benchmark label: the p50_us of every round."""
    out = {}
    for r in range(1, rounds + 1):
        with open(f"{folder}/{which}.{r}.json") as f:
            for b in json.load(f)["benchmarks"]:
                if "p50_us" in b:
                    out.setdefault(b.get("label") or b["name"], []).append(b["p50_us"])
    return out

base, cur = p50s("baseline"), p50s("current")
print(f"bench_engine, both builds measured in one run: baseline {commit[:10]}, current tree; "
      f"point budget {budget}; {rounds} rounds each, alternating")
print()
print("| benchmark | baseline p50 µs (median, range) | current p50 µs (median, range) | current / baseline |")
print("|---|---|---|---|")
for label in cur:
    if label not in base:
        print(f"| {label} | - | {statistics.median(cur[label]):.1f} | - |")
        continue
    b, c = base[label], cur[label]
    mb, mc = statistics.median(b), statistics.median(c)
    print(f"| {label} | {mb:.1f} ({min(b):.1f}-{max(b):.1f}) | {mc:.1f} ({min(c):.1f}-{max(c):.1f}) | {mc / mb:.2f} |")
for label in base:
    if label not in cur:
        print(f"| {label} | {statistics.median(base[label]):.1f} | - | - |")
EOF
