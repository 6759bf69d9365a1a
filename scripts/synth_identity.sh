#!/usr/bin/env bash
# Byte-identity check of `kccd synth` between two builds (for refactors that must not change its
# output): runs the same cases with both programs and compares every file written, stdout, stderr
# and the exit status, byte for byte, except what differs between two runs of one program too:
# the values in synth.json's "timing", the "in N s" of the summary line, progress lines on stderr,
# and the random SegmentUID/TrackUID (with their CRC-32s) FFmpeg's Matroska muxer writes into the
# first bytes of video.mkv (the size and every byte after the first KiB must agree).
#   scripts/synth_identity.sh OLD_KCCD NEW_KCCD [WORK_DIR]
# Exit status 0 when every file agrees. About a minute per program on a quiet 2-core machine.
set -u
[ $# -ge 2 ] || { echo "usage: $0 OLD_KCCD NEW_KCCD [WORK_DIR]" >&2; exit 2; }
old=$(realpath "$1") new=$(realpath "$2")
work=${3:-$(mktemp -d)}
data=$(realpath "$(dirname "$0")/../data")

capture() {  # program, folder
  local K=$1 O=$2
  rm -rf "$O"; mkdir -p "$O/work"
  (
    cd "$O/work" || exit 1
    # A model with visuals (as tests/test_synth.cpp builds it) and one whose visual mesh is missing.
    for i in 0 1 2 3 4 5 6 7; do
      echo "v $([ $((i & 1)) -ne 0 ] && echo 0.4 || echo 0.0) $([ $((i & 2)) -ne 0 ] && echo 0.04 || echo -0.04) $([ $((i & 4)) -ne 0 ] && echo 0.04 || echo -0.04)"
    done > upper_arm.obj
    printf 'f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n' >> upper_arm.obj
    { cat "$data/demo_arm.yaml"; printf 'visuals:\n  - frame: world\n    cylinder: {radius: 0.08, length: 0.35}\n    origin: {xyz: [0, 0, 0.175]}\n  - frame: shoulder_pitch\n    mesh: upper_arm.obj\n    colour: [0.9, 0.4, 0.1]\n  - frame: elbow\n    box: [0.4, 0.07, 0.07]\n    origin: {xyz: [0.2, 0, 0]}\n'; } > visual_arm.yaml
    { cat "$data/demo_arm.yaml"; printf 'visuals:\n  - frame: world\n    mesh: missing.obj\n'; } > broken_visual.yaml
    mkdir -p full h; echo mine > full/keep.txt
    run() {  # name, args... (argv[0] "kccd" for both programs: --help prints it)
      local name=$1; shift
      (exec -a kccd "$K" "$@") > "$O/$name.out" 2> "$O/$name.err"; echo $? > "$O/$name.rc"
    }
    D=$data
    run a synth "$D/humanoid.yaml" -o a --seconds 2.4 --fps 25 --seed 3
    run b synth "$D/humanoid.yaml" -o b --seconds 1 --fps 20 --seed 5 --no-collision --width 640 --height 480 -q
    run c synth "$D/demo_arm.yaml" -o c --seconds 1 --width 640 --height 480 --codec mjpg --seed 2
    run d synth visual_arm.yaml -o d --seconds 0.4 --fps 10 --seed 2 --no-collision --codec mp4v -q
    run e synth "$D/humanoid.yaml" -o e --camera b/camera_true.yaml --seconds 1 --blur 0 --noise 0 --visible-scale 0.5 --log-rate 100 --time-offset 0.3 --appearance volumes -q
    run f synth visual_arm.yaml -o f --seconds 0.6 --appearance volumes --width 640 --height 480 --seed 4 -q
    run f2 synth visual_arm.yaml -o f2 --seconds 0.6 --appearance volumes --width 960 --height 720 --seed 4 -q
    run g synth "$D/industrial_cell.yaml" -o g --seconds 1 --width 640 --height 480 --seed 1 -q
    run g2 synth "$D/industrial_cell.yaml" -o g2 --seconds 1 --width 640 --height 480 --seed 1 --no-collision -q
    run h synth "$D/demo_arm.yaml" -o h --seconds 1 --width 640 --height 480 --seed 7 --force -q
    run x1 synth "$D/no_such_model.yaml" -o x
    run x2 synth "$D/humanoid.yaml" -o x --codec h265
    run x3 synth "$D/humanoid.yaml" -o x --fps 0
    run x4 synth "$D/humanoid.yaml" -o x --log-rate 25
    run x5 synth "$D/humanoid.yaml" -o nowhere/x
    run x6 synth "$D/humanoid.yaml" -o full
    run x7 synth "$D/humanoid.yaml" -o x --camera nothing.yaml
    run x8 synth "$D/humanoid.yaml" -o x --camera b/camera_true.yaml --width 640
    run x9 synth visual_arm.yaml -o x --seconds 0.2 --visible-scale 0.5 -q
    run x10 synth broken_visual.yaml -o x --seconds 0.2 -q
    run x11 synth "$D/demo_arm.yaml" -o x --appearance visuals -q
    run x12 synth "$D/humanoid.yaml" -o x --seconds 0.01 -q
    run x13 synth "$D/humanoid.yaml" -o .
    run x14 synth "$D/humanoid.yaml" -o x --seconds 0.3 --width 64 --height 64 -q
    run help synth --help
    ls -la x > "$O/x_exists" 2>&1
  )
}

norm() {  # file -> normalised bytes on stdout
  case "$1" in
    */synth.json) python3 - "$1" <<'PY'
import re, sys
t = open(sys.argv[1], 'rb').read().decode()
i = t.find('"timing": {')
if i >= 0:
    j = t.index('\n }', i)
    t = t[:i] + re.sub(r'(": )-?[0-9.e+-]+', r'\1N', t[i:j]) + t[j:]
sys.stdout.write(t)
PY
    ;;
    *.out) sed -E 's/, in [0-9.e+-]+ s$/, in N s/' "$1" ;;
    *.err) grep -Ev '^synth: [0-9]+%$' "$1" ;;
    *.mkv) stat -c 'size %s' "$1"; tail -c +1025 "$1" ;;
    *) cat "$1" ;;
  esac
}

capture "$old" "$work/old"
capture "$new" "$work/new"
bad=0
(cd "$work/old" && find . -type f | sort) > "$work/old.list"
(cd "$work/new" && find . -type f | sort) > "$work/new.list"
if ! diff "$work/old.list" "$work/new.list"; then echo "the file lists differ"; bad=1; fi
n=0 raw=0
while read -r f; do
  [ -f "$work/new/$f" ] || continue
  n=$((n + 1))
  if cmp -s "$work/old/$f" "$work/new/$f"; then raw=$((raw + 1)); continue; fi
  if ! cmp -s <(norm "$work/old/$f") <(norm "$work/new/$f"); then echo "DIFFERS: $f"; bad=1; fi
done < "$work/old.list"
echo "$n files compared in $work: $raw identical as they are, the rest once run times and the MKV UIDs are masked: $([ $bad -eq 0 ] && echo SAME || echo DIFFERENT)"
exit $bad
