#!/usr/bin/env bash
# The demo: builds the kccd tool and runs it on the bundled sample robots.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build-demo -G Ninja -DCMAKE_BUILD_TYPE=Release -DKCCD_BUILD_TESTS=OFF >/dev/null
cmake --build build-demo -j "${KCCD_JOBS:-2}" --target kccd_cli
kccd=build-demo/overlay/kccd
step() { printf '\n\033[1m$ %s\033[0m\n' "$*"; "$@"; }

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
step $kccd query data/humanoid.yaml --lower $lower --upper $upper --type collision --json
# What a fixed camera sees (data/demo_camera.yaml: 1280x720, mild barrel distortion): the static
# volumes at one state, and the swept volumes of the swing above, coloured by status.
step $kccd render data/demo_arm.yaml --camera data/demo_camera.yaml --state 0.3,0.4,0.6 --labels -o build-demo/demo_static.png
step $kccd render data/demo_arm.yaml --camera data/demo_camera.yaml --lower -0.5,0,0 --upper 0.5,0,0 -o build-demo/demo_swept.png
step $kccd render data/demo_arm.yaml --camera data/demo_camera.yaml --lower -0.5,0,0 --upper 0.5,0,0 --mask -o build-demo/demo_swept_mask.png
# Calibration: the camera's pose from 16 labelled points (one misclicked), with its uncertainty,
# and a check image of every point, its reprojection and the model's volumes at the state.
step $kccd calib --intrinsics data/demo_camera.yaml --labels data/demo_labels.yaml --model data/demo_arm.yaml \
  --state 0.3,0.4,0.6 -o build-demo/calibrated_camera.yaml --check build-demo/calib_check.png \
  --truth data/demo_camera.yaml
# Modelling: a conservative SSCH for a CAD part (8 core points), and which pairs of the demo arm
# can never meet anywhere inside the joint limits (proven with the same sweeps).
step $kccd fit data/parts/gripper.iv --points 8 --name gripper --frame elbow -q
step $kccd pairs data/demo_arm.yaml -q
echo "images in build-demo/: demo_static.png, demo_swept.png (RGBA layers), demo_swept_mask.png (labels), calib_check.png"
