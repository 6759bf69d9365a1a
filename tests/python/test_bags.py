"""Robot logs from Python: kccd.read_bag against what the fixture writer put in (tests/bags/write_mcap.mjs
with @mcap/core and @foxglove/rosmsg2-serialization: 200 JointState at 1 kHz with the joint order
rotating, 10 rgb8 images, stamps 2 and 35 ms behind the log times), kccd.overlay_recording(bag=...)
equal to `kccd overlay --bag`, and a kccd.batch recording given as a bag."""

import json
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import kccd
from conftest import ROOT

from kccd import batch

SEVEN = "kccd: 1\nname: seven\nsafety_margin: 0.02\njoints:\n" + "".join(
    f"  - {{name: joint{k}, parent: {'world' if k == 1 else f'joint{k - 1}'}, type: revolute, "
    f"origin: {{xyz: [0, 0, {0 if k == 1 else 0.12}]}}, axis: [0, 0, 1], limits: [-3, 3]}}\n" for k in range(1, 8)) + (
    "bodies:\n  - {name: base, frame: world, points: [[0.3, 0, 0], [0.3, 0, 0.5]], radius: 0.05}\n"
    "  - {name: tip, frame: joint7, points: [[0, 0, 0], [0.05, 0, 0.1]], radius: 0.03}\n")
CAMERA = ("%YAML:1.0\n---\nimage_width: 64\nimage_height: 48\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n"
          "   dt: d\n   data: [ 40, 0, 31.5, 0, 40, 23.5, 0, 0, 1 ]\ndistortion_coefficients: !!opencv-matrix\n   rows: 1\n"
          "   cols: 5\n   dt: d\n   data: [ 0, 0, 0, 0, 0 ]\nrvec: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n"
          "   data: [ 1.5707963267948966, 0, 0 ]\ntvec: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ 0, 0.5, 2 ]\n")


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> pathlib.Path:
    root = tmp_path_factory.mktemp("bags")
    node = shutil.which("node")
    assert node, "node is needed for the fixture writer (scripts/install-deps.sh --tests)"
    subprocess.run([node, str(ROOT / "tests" / "bags" / "write_mcap.mjs"), str(root)], check=True, capture_output=True)
    (root / "seven.yaml").write_text(SEVEN)
    (root / "cam.yaml").write_text(CAMERA)
    return root


def test_read_bag_gives_what_the_writer_wrote(bags: pathlib.Path) -> None:
    truth = json.loads((bags / "truth.json").read_text())
    model = kccd.Model.load(str(bags / "seven.yaml"))
    r = kccd.read_bag(str(bags / "joint_zstd.mcap"), model, frames=[0, 7])
    assert r["info"]["format"] == "MCAP" and r["info"]["messages"] == 211
    assert r["image_topic"] == "/camera/image_raw" and r["joint_topic"] == "/joint_states"
    assert r["state_names"] == [f"joint{k}" for k in range(1, 8)]
    stamp = lambda m: m["stamp_sec"] * 10**9 + m["stamp_nanosec"]  # noqa: E731
    origin = min(stamp(m) for m in truth["joint_states"] + truth["images"])
    assert r["origin_ns"] == origin
    joints = truth["joint_states"]
    assert r["states"].shape == (len(joints), 7)
    for row, m in zip(range(len(joints)), joints):
        want = [m["position"][m["name"].index(f"joint{k}")] for k in range(1, 8)]
        assert list(r["states"][row]) == want
        assert r["times"][row] == (stamp(m) - origin) / 1e9
    assert list(r["frame_times"]) == [(stamp(m) - origin) / 1e9 for m in truth["images"]]
    for image, index in zip(r["images"], (0, 7)):
        m = truth["images"][index]
        assert image.dtype == np.uint8 and image.shape == (48, 64, 3)
        assert list(image.reshape(-1)[:8]) == m["data_first8"] and int(image.sum()) == m["data_sum"]
    on_log = kccd.read_bag(str(bags / "joint_zstd.mcap"), model, time_source="log")
    assert on_log["origin_ns"] == int(truth["joint_states"][0]["log_time_ns"]) and r["warnings"] == []
    # Without a model: what the log holds, and frames on request.
    info = kccd.read_bag(str(bags / "joint_plain.mcap"))
    assert set(info) == {"info"} and sorted(t["topic"] for t in info["info"]["topics"]) == \
        ["/camera/camera_info", "/camera/image_raw", "/joint_states"]


def test_overlay_of_a_bag_from_python_is_the_commands(cli, bags: pathlib.Path, tmp_path: pathlib.Path) -> None:
    model = kccd.Model.load(str(bags / "seven.yaml"))
    camera = kccd.Camera.load(str(bags / "cam.yaml"))
    mine = kccd.overlay_recording(model, camera, bag=str(bags / "joint_lz4.mcap"), time_source="log",
                                  report=str(tmp_path / "py.json"), timeline=str(tmp_path / "timeline.png"))
    subprocess.run([str(cli), "overlay", str(bags / "seven.yaml"), "--camera", str(bags / "cam.yaml"), "--bag",
                    str(bags / "joint_lz4.mcap"), "--time-source", "log", "--report", str(tmp_path / "cli.json"), "-q"], check=True)
    ref = json.loads((tmp_path / "cli.json").read_text())
    assert mine["frames"] == ref["frames"] and mine["source"] == ref["source"]
    assert mine["source"]["time_source"] == "log" and (tmp_path / "timeline.png").stat().st_size > 1000
    with pytest.raises(ValueError, match="^video: not with bag "):
        kccd.overlay_recording(model, camera, "v.mkv", "s.csv", bag=str(bags / "joint_lz4.mcap"))
    with pytest.raises(ValueError, match="^give video and states, bag \\(a robot log\\) or lerobot"):
        kccd.overlay_recording(model, camera, "v.mkv")
    with pytest.raises(ValueError, match="^time_source: expected 'header' or 'log', got 'wall'"):
        kccd.overlay_recording(model, camera, bag=str(bags / "joint_lz4.mcap"), time_source="wall")
    with pytest.raises(kccd.InputError, match="not a robot log"):
        kccd.read_bag(str(bags / "truth.json"), model)


def test_a_batch_recording_given_as_a_bag(cli, bags: pathlib.Path, tmp_path: pathlib.Path) -> None:
    (bags / "fleet.yaml").write_text(
        "kccd_batch: 1\n"
        "defaults: {model: seven.yaml, camera: cam.yaml, time_source: log}\n"
        "recordings:\n"
        "  - {id: from-bag, bag: joint_zstd.mcap, image_topic: /camera/image_raw}\n")
    [rec] = batch.read_manifest(str(bags / "fleet.yaml"))
    assert rec.bag == str(bags / "joint_zstd.mcap") and rec.video == "" and rec.time_source == "log"
    line = batch.run_recording(rec, str(tmp_path / "out"))
    folder = tmp_path / "out" / "from-bag"
    assert sorted(p.name for p in folder.iterdir()) == sorted(batch.OUTPUT_FILES)
    subprocess.run([str(cli), "overlay", str(bags / "seven.yaml"), "--camera", str(bags / "cam.yaml"), "--bag",
                    str(bags / "joint_zstd.mcap"), "--time-source", "log", "--report", str(tmp_path / "cli.json"), "-q"], check=True)
    unwritten = lambda path: [{k: v for k, v in f.items() if k != "written"}  # noqa: E731 - the batch writes a video
                              for f in json.loads(path.read_text())["frames"]]
    assert unwritten(folder / "report.json") == unwritten(tmp_path / "cli.json")
    assert line["frames_total"] == 10
    made = json.loads((folder / "inputs.json").read_text())
    assert sorted(made["inputs"]) == ["bag", "camera", "model"] and made["bag"]["time_source"] == "log"
    assert batch.complete_summary(rec, str(tmp_path / "out")) is not None  # --resume skips it
    for body, where in (
        ("  - {id: x, bag: joint_zstd.mcap, video: v.mkv}\n", "recordings[0].video: not with bag"),
        ("  - {id: x, video: v.mkv, states: s.csv, image_topic: /c}\n", "recordings[0].image_topic: goes with bag"),
        ("  - {id: x, bag: missing.mcap}\n", "recordings[0].bag: "),
        ("  - {id: x, bag: joint_zstd.mcap, time_source: wall}\n", "recordings[0].time_source: expected header or log"),
    ):
        (bags / "bad.yaml").write_text("kccd_batch: 1\ndefaults: {model: seven.yaml, camera: cam.yaml}\nrecordings:\n" + body)
        with pytest.raises(batch.ManifestError, match=where.replace("[", r"\[").replace("]", r"\]")):
            batch.read_manifest(str(bags / "bad.yaml"))
