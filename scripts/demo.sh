#!/usr/bin/env bash
# The demo: builds the kccd tool and runs the suite's main job on a generated recording:
# synthesise a recording of the humanoid with ground truth, calibrate the camera from its
# AprilTags, overlay the collision volumes (static and swept) driven by the state log. Then a
# short tour of the other commands on the bundled samples.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build-demo -G Ninja -DCMAKE_BUILD_TYPE=Release -DKCCD_BUILD_TESTS=OFF >/dev/null
cmake --build build-demo -j "${KCCD_JOBS:-2}" --target kccd_cli
kccd=build-demo/overlay/kccd
out=build-demo/main-job
rec=$out/recording
mkdir -p "$out"
step() { printf '\n\033[1m$ %s\033[0m\n' "$*"; "$@"; }

# 1. A 4 s recording of the humanoid (1280x720, 25 fps): shaded visible geometry inside its
#    SSCHs, a room with 18 AprilTags, lens distortion, blur and noise; a state log at 125 Hz
#    whose clock runs 0.137 s ahead of the video; near-collisions and one real collision.
step $kccd synth data/humanoid.yaml -o $rec --seconds 4 --force
# 2. The camera's pose from the tags in frame 0, checked against the true camera.
step $kccd calib --intrinsics $rec/intrinsics.yaml --video $rec/video.mkv --frame 0 --tags $rec/tags.yaml \
  --model data/humanoid.yaml --states $rec/states.csv --time 0.137 \
  -o $out/camera.yaml --check $out/calib_check.png --truth $rec/camera_true.yaml
# 3. The volumes at each frame's logged state, coloured by the library's distance query ...
step $kccd overlay data/humanoid.yaml --camera $out/camera.yaml --video $rec/video.mkv --states $rec/states.csv \
  --time-offset 0.137 -o $out/overlay.mp4 --report $out/report.json --contact-sheet $out/contact_sheet.png
# ... and the braking-interval swept volumes the safety check tests (10 ms latency, 5 rad/s^2).
step $kccd overlay data/humanoid.yaml --camera $out/camera.yaml --video $rec/video.mkv --states $rec/states.csv \
  --time-offset 0.137 --swept -o $out/overlay_swept.mp4 --report $out/report_swept.json \
  --contact-sheet $out/contact_sheet_swept.png --timeline $out/timeline_swept.png

# The tour: queries on the bundled robots, a single rendered frame, labelled-point calibration,
# fitting a CAD part and proving pairs that never meet.
step $kccd info data/demo_arm.yaml
# A fast swing of the stretched arm past the pole in front of it: both end poses are clear ...
step $kccd query data/demo_arm.yaml --state -0.5,0,0 --type closest
step $kccd query data/demo_arm.yaml --state 0.5,0,0 --type closest
# ... but the motion between them is not: KCCD checks the whole interval box at once.
step $kccd query data/demo_arm.yaml --lower -0.5,0,0 --upper 0.5,0,0 --type distances
# The humanoid (26 bodies, 20 joints) braking with 2-6 degree intervals per joint.
lower=-0.05,0.05,0.05,0.05,-0.05,0.0,0.2,-0.9,0.3,1.2,0.0,0.3,0.0,-0.2,-0.9,-0.3,1.2,0.0,0.3,0.0
upper=0.0,0.1,0.1,0.1,0.0,0.05,0.3,-0.8,0.35,1.3,0.1,0.4,0.1,-0.1,-0.8,-0.25,1.3,0.1,0.4,0.1
step $kccd query data/humanoid.yaml --lower $lower --upper $upper --type nclosest --n 3
step $kccd render data/demo_arm.yaml --camera data/demo_camera.yaml --lower -0.5,0,0 --upper 0.5,0,0 -o build-demo/demo_swept.png
# Calibration from 16 hand-labelled points (one misclicked, rejected), with a check image.
step $kccd calib --intrinsics data/demo_camera.yaml --labels data/demo_labels.yaml --model data/demo_arm.yaml \
  --state 0.3,0.4,0.6 -o build-demo/calibrated_camera.yaml --check build-demo/calib_check_labels.png \
  --truth data/demo_camera.yaml
step $kccd fit data/parts/gripper.iv --points 8 --name gripper --frame elbow -q
step $kccd pairs data/demo_arm.yaml -q

printf '\n\033[1mThe main job wrote, in %s/:\033[0m\n' "$out"
printf '  overlay.mp4, overlay_swept.mp4     the recording with the static / swept volumes\n'
printf '  contact_sheet.png, contact_sheet_swept.png   selected frames side by side\n'
printf '  timeline_swept.png                 the swept run over time: bound, margin, spans and the pairs responsible\n'
printf '  report.json, report_swept.json     per frame: state match, status, min distance, pairs\n'
printf '  calib_check.png, camera.yaml       the calibration: check image and camera file\n'
printf '  recording/                         the synthetic input and its truth (synth.json)\n'
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
for name in ("report.json", "report_swept.json"):
    r = json.load(open(f"{out}/{name}"))
    print(f"{name}: {r['frames_total']} frames, {r['frames_written']} written; clear "
          f"{r['frames_total'] - r['colliding'] - r['within_margin'] - r['no_state']}, within margin {r['within_margin']}, "
          f"colliding {r['colliding']}, no state {r['no_state']}")
truth = json.load(open(f"{out}/recording/synth.json"))["collision"]["frames"]
seen = [f["index"] for f in json.load(open(f"{out}/report.json"))["frames"] if f["status"] == "colliding"]
print(f"colliding frames: overlay {seen}, the recording's truth {truth}")
PY
