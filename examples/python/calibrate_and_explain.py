"""KCCD from Python, the operator's loop: a recording's camera calibrated from its AprilTags, the
model drawn over a frame with that camera, and a flagged braking box explained.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/calibrate_and_explain.py [OUT.png]

It makes its own short synthetic recording (kccd.synthesize_recording) in a temporary folder.
"""

import pathlib
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import kccd  # noqa: E402

DATA = pathlib.Path(__file__).resolve().parents[2] / "data"


def main(out: str) -> None:
    model = kccd.Model.load(str(DATA / "demo_arm.yaml"))
    with tempfile.TemporaryDirectory() as tmp:
        rec = kccd.synthesize_recording(str(DATA / "demo_arm.yaml"), tmp + "/rec", seconds=0.2)
        folder = pathlib.Path(rec["folder"])
        frame = kccd.read_frame(rec["video"], 0)
        tags = kccd.detect_tags(frame)
        points = kccd.tag_correspondences(tags, kccd.TagLayout.load(str(folder / "tags.yaml")), "frame 0")
        intrinsics = kccd.Camera.load(str(folder / "intrinsics.yaml"), require_pose=False)
        pose = kccd.solve_pose(intrinsics, points["pixels"], points["world"], points["names"])
        print(f"{len(tags)} tags: {pose['status'].name.lower()}: {pose['message']}")
        camera = pose["camera"]
        if camera is None:
            raise SystemExit("no pose: add labelled points or another frame")
        # The logged state nearest frame 0 (log time = frame time + time offset).
        log = np.loadtxt(rec["states"], delimiter=",", skiprows=1)
        state = log[np.argmin(np.abs(log[:, 0] - rec["time_offset"])), 1 : 1 + model.state_size]
    drawn = kccd.render(model, camera, state=state)["rgba"].astype(np.float64) / 255.0
    alpha = drawn[..., 3:4]
    composite = frame / 255.0 * (1 - alpha) + drawn[..., :3] * alpha

    # A braking box the arm may sweep: which flags are real?
    lower, upper = np.array([0.3, 0.4, 0.6]), np.array([0.5, 1.2, 1.4])
    for e in kccd.explain(model, lower, upper):
        print(f"  {e['a']:>9} - {e['b']:<9} bound {e['bound']:.3f} m, found {e['distance']:.3f} m: {e['verdict']}")

    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.imshow(composite)
    for t in tags:
        ax.plot(*np.vstack([t.corners, t.corners[:1]]).T, color="yellow", linewidth=1)
    ax.set_title(f"calibrated from {len(tags)} tags, RMS {pose['reprojection_rms_px']:.2f} px")
    ax.axis("off")
    fig.savefig(out, dpi=100, bbox_inches="tight")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "kccd_calibration.png")
