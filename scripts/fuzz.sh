#!/usr/bin/env bash
# Builds the libFuzzer targets (clang-14, ASan + UBSan, in build-fuzz/) and runs each for a while
# on a fresh copy of its seed corpus (tests/fuzz/corpus/NAME plus sample files from data/),
# KCCD_JOBS targets at a time. A crash, sanitizer report, leak, per-input time-out (an input that
# runs longer than the target's bound: a hang) or memory blow-up fails the run and leaves the
# input in build-fuzz/artifacts/ and the log in build-fuzz/NAME.log.
#   scripts/fuzz.sh [--seconds N] [TARGET...]   explore: N seconds each (default 15), a new seed each run
#   scripts/fuzz.sh --ci [TARGET...]            CI: a fixed seed and a fixed number of inputs per
#                                               target (15-40 s each here), so runs are comparable
# In --ci mode a target also stops at a time cap (60 s; KCCD_FUZZ_SECONDS): one that reaches the
# cap before its count is reported with its rate as a warning, never a failure, since machines
# differ by 3x. Only what a finding is fails: the speed of the machine does not.
# Environment: KCCD_JOBS (default 2), KCCD_FUZZ_SECONDS (the --ci cap).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=15
ci=0
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --seconds=*) seconds=${1#*=}; shift ;;
    --ci) ci=1; seconds=${KCCD_FUZZ_SECONDS:-60}; shift ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
# The slowest first, so that the jobs end together.
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_urdf fuzz_part fuzz_model fuzz_states fuzz_frame_times fuzz_camera fuzz_tags fuzz_labels fuzz_labels_json fuzz_golden_manifest fuzz_frame fuzz_mask fuzz_video fuzz_mcap fuzz_ros_message fuzz_ros1_bag fuzz_db3 fuzz_parquet fuzz_lerobot fuzz_joint_map)
bash scripts/install-deps.sh --fuzz
# -O1 with line tables only: the fuzzers' stacks keep files and lines, and the build is much shorter.
CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG" \
  -DKCCD_BUILD_FUZZERS=ON -DKCCD_BUILD_TESTS=OFF -DKCCD_BUILD_BENCHMARKS=OFF >/dev/null
jobs=${KCCD_JOBS:-2}
cmake --build build-fuzz -j "$jobs" --target "${targets[@]}"
out=build-fuzz

ci_runs() {  # inputs per target in --ci mode (15-40 s each on this project's machines)
  case "$1" in
    fuzz_model) echo 30000 ;;
    fuzz_states) echo 180000 ;;
    fuzz_frame_times) echo 200000 ;;
    fuzz_frame) echo 3000 ;;
    fuzz_video) echo 3000 ;;
    fuzz_mask) echo 20000 ;;
    fuzz_camera) echo 100000 ;;  # read by yaml-cpp since OpenCV's parser hung: about 3,800 inputs/s
    fuzz_tags) echo 140000 ;;
    fuzz_labels) echo 130000 ;;
    fuzz_labels_json) echo 100000 ;;
    fuzz_golden_manifest) echo 100000 ;;
    fuzz_part) echo 2000 ;;   # 60 inputs/s: a quarter of them are split into convex pieces
    fuzz_urdf) echo 800 ;;    # 20 inputs/s: every model imported is fitted
    fuzz_mcap) echo 40000 ;;
    fuzz_ros_message) echo 200000 ;;
    fuzz_ros1_bag) echo 40000 ;;
    fuzz_db3) echo 4000 ;;    # about 120 inputs/s: each input is opened by SQLite
    fuzz_parquet) echo 80000 ;;  # about 3,500 inputs/s on a core of its own
    fuzz_lerobot) echo 20000 ;;
    fuzz_joint_map) echo 100000 ;;
  esac
}

seeds() {  # extra seed files from data/ per target
  case "$1" in
    fuzz_model) ls data/*.yaml | grep -v camera ;;
    fuzz_states) ;;
    fuzz_frame_times) ;;
    fuzz_camera) ls data/*camera*.yaml ;;
    fuzz_tags) ;;
    fuzz_labels) ;;
    fuzz_labels_json) ;;
    fuzz_golden_manifest) ;;
    fuzz_frame) ;;
    fuzz_video) ;;
    fuzz_mask) ;;
    fuzz_part) ls data/parts/* ;;
    fuzz_urdf) ls tests/data/urdf/*.urdf ;;
    fuzz_mcap) ;;
    fuzz_ros_message) ;;
    fuzz_ros1_bag) ;;
    fuzz_db3) ;;
    fuzz_parquet) ;;
    fuzz_lerobot) ;;
    fuzz_joint_map) ;;
  esac
}
input_timeout() {  # seconds one input may take before it counts as a hang: far above the slowest
  # legitimate input measured (tests/reader_bounds, docs/development/fuzzing.md), on a machine 3x slower under ASan
  case "$1" in
    fuzz_urdf|fuzz_part|fuzz_video|fuzz_frame) echo 60 ;;
    *) echo 30 ;;
  esac
}
mkdir -p $out/artifacts
fuzz_one() {  # target: runs it, then prints its one-line result (and the log's end on failure)
  local t=$1 corpus=$out/corpus/$1
  rm -rf "$corpus" && mkdir -p "$corpus"
  [ -d "tests/fuzz/corpus/${t#fuzz_}" ] && cp -r "tests/fuzz/corpus/${t#fuzz_}/." "$corpus/"
  for f in $(seeds "$t"); do cp "$f" "$corpus/"; done
  # Leaks: checked for the model loader and the state log reader (our code only); the readers
  # built on Coin3D, OpenCV and urdfdom keep per-process caches the leak checker would report on
  # every input (the ASan test suite checks our own code on those paths, with tests/lsan.supp).
  local leaks=0; case "$t" in fuzz_model|fuzz_states|fuzz_frame_times) leaks=1 ;; esac
  local limits=(-max_total_time="$seconds") what="${seconds} s"
  if [ $ci -eq 1 ]; then
    limits+=(-seed=1 -runs="$(ci_runs "$t")")
    what="$(ci_runs "$t") inputs (seed 1)"
  fi
  what="$what from $(ls "$corpus" | wc -l) seeds"
  # An out-of-memory stop under ASan can leave libFuzzer stuck: the outer timeout kills it.
  local start=$SECONDS rc=0
  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 \
  LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 \
    timeout -s KILL $((seconds + 3 * $(input_timeout "$t"))) "build-fuzz/tests/fuzz/$t" "${limits[@]}" \
      -timeout="$(input_timeout "$t")" -rss_limit_mb=2048 -malloc_limit_mb=1024 -max_len=65536 -print_final_stats=1 \
      -detect_leaks=$leaks -artifact_prefix="$out/artifacts/$t-" "$corpus" > "$out/$t.log" 2>&1 || rc=$?
  local took=$((SECONDS - start))
  # The fuzzer's own statistics are the log's last: a reader that runs a library in a child
  # process (Assimp in fuzz_part) can have that child crash on an input by design (the parent
  # reports a read error and goes on), and the child, a copy of the fuzzer, prints its statistics
  # too when its sanitizer stops it.
  local ran; ran=$(grep -oE "stat::number_of_executed_units: *[0-9]+" "$out/$t.log" | tail -1 | grep -oE "[0-9]+$" || true)
  local added; added=$(grep -oE "stat::new_units_added: *[0-9]+" "$out/$t.log" | tail -1 | grep -oE "[0-9]+$" || true)
  ran=${ran:-0} added=${added:-0}
  if [ $rc -ne 0 ]; then
    local why="exit $rc"
    [ $rc -eq 137 ] && why="killed after $took s (stuck past its time cap)"
    grep -q "ERROR: libFuzzer: timeout" "$out/$t.log" && why="an input ran past the per-input bound of $(input_timeout "$t") s (a hang)"
    grep -q "ERROR: AddressSanitizer\|ERROR: LeakSanitizer\|runtime error:" "$out/$t.log" && why="a sanitizer report"
    grep -q "ERROR: libFuzzer: out-of-memory" "$out/$t.log" && why="out of memory"
    grep -q "deadly signal" "$out/$t.log" && why="a crash"
    echo "fuzz.sh: $t FAILED: $why, $what (log: $out/$t.log, inputs: $out/artifacts/)"; tail -40 "$out/$t.log"
    return 1
  fi
  local rate=$(( ran / (took > 0 ? took : 1) ))
  echo "== $t: $what: $ran inputs in $took s ($rate/s), $added new units"
  if [ $ci -eq 1 ] && [ "$ran" -lt "$(ci_runs "$t")" ]; then
    echo "fuzz.sh: warning: $t reached its ${seconds} s cap after $ran of $(ci_runs "$t") inputs ($rate/s): a slower or busier machine, or a slower target (not a failure)"
  fi
}
# KCCD_JOBS targets at a time; each prints its result when it ends.
status=0
running=0
for t in "${targets[@]}"; do
  if [ $running -ge "$jobs" ]; then
    wait -n || status=1
    running=$((running - 1))
  fi
  fuzz_one "$t" &
  running=$((running + 1))
done
while [ $running -gt 0 ]; do
  wait -n || status=1
  running=$((running - 1))
done
exit $status
