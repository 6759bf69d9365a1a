"""LeRobot datasets from Python: kccd.read_lerobot, kccd.check_log and overlay_recording(lerobot=)
against the command line on a dataset written by other projects' tools (tests/datasets)."""

import json
import re
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import kccd

from conftest import DATA, ROOT


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> tuple[pathlib.Path, pathlib.Path]:
    """A two-episode v2.1 dataset (h264) made from a synthetic recording, and the recording."""
    node = shutil.which("node")
    assert node, "node not found: install nodejs (scripts/install-deps.sh --tests)"
    work = tmp_path_factory.mktemp("lerobot")
    rec = work / "rec"
    kccd.synthesize_recording(str(DATA / "demo_arm.yaml"), str(rec), seconds=2.0, fps=10.0, width=640, height=480)
    subprocess.run([node, str(ROOT / "tests/datasets/write_lerobot.mjs"), str(work / "ds"), "--from-synth", str(rec),
                    "--episodes", "2", "--codec", "libx264"], check=True, capture_output=True)
    return work / "ds", rec


def test_read_lerobot_gives_the_info_and_the_rows(dataset: tuple[pathlib.Path, pathlib.Path], arm: kccd.Model) -> None:
    ds, _ = dataset
    info = kccd.read_lerobot(str(ds))["info"]
    assert info["version"] == "v2.1" and info["episodes"] == 2 and info["frames"] == 20
    assert info["cameras"][0]["codec"] == "h264"
    episode = kccd.read_lerobot(str(ds), arm, episode=1)
    assert episode["state_names"] == ["shoulder_yaw", "shoulder_pitch", "elbow"]
    assert episode["frame_by"] == "timestamp"
    np.testing.assert_array_equal(episode["times"], np.arange(10) / 10.0)
    truth = np.loadtxt(ds / "truth/episode_1.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(episode["states"], truth[:, 1:])
    with pytest.raises(kccd.InputError, match="episode 5: not in the dataset"):
        kccd.read_lerobot(str(ds), arm, episode=5)


def test_check_log_and_overlay_agree_with_the_command(dataset: tuple[pathlib.Path, pathlib.Path], arm: kccd.Model,
                                                      cli: pathlib.Path, tmp_path: pathlib.Path) -> None:
    ds, rec = dataset
    summary = kccd.check_log(arm, lerobot=str(ds), episode=0, report=str(tmp_path / "py.json"))
    run = subprocess.run([str(cli), "check", str(DATA / "demo_arm.yaml"), "--lerobot", str(ds), "--episode", "0",
                          "--report", str(tmp_path / "cli.json"), "-q"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    py, cl = (json.loads((tmp_path / n).read_text()) for n in ("py.json", "cli.json"))
    assert py["frames"] == cl["frames"] and summary["samples"] == 10
    overlay = kccd.overlay_recording(arm, kccd.Camera.load(str(rec / "camera_true.yaml")), lerobot=str(ds), episode=0,
                                     report=str(tmp_path / "overlay.json"))
    for checked, drawn in zip(py["frames"], overlay["frames"]):
        assert checked["min_distance"] == drawn["min_distance"] and checked["status"] == drawn["status"]
    with pytest.raises(kccd.InputError, match="^episode: goes with lerobot"):
        kccd.check_log(arm, str(rec / "states.csv"), episode=1)
    with pytest.raises(kccd.InputError, match="^frame_by: expected"):
        kccd.check_overlay_request(arm, lerobot=str(ds), episode=0, frame_by="nearest")


def test_a_manifest_runs_every_episode(dataset: tuple[pathlib.Path, pathlib.Path], tmp_path: pathlib.Path) -> None:
    from kccd import batch

    ds, rec = dataset
    manifest = tmp_path / "episodes.yaml"
    manifest.write_text(f"kccd_batch: 1\ndefaults: {{model: {DATA / 'demo_arm.yaml'}, camera: {rec / 'camera_true.yaml'}}}\n"
                        f"recordings:\n  - {{id: demo, lerobot: {ds}}}\n  - {{id: one, lerobot: {ds}, episodes: [1]}}\n")
    recordings = batch.read_manifest(str(manifest))
    assert [(r.id, r.episode) for r in recordings] == [("demo-000000", 0), ("demo-000001", 1), ("one-000001", 1)]
    first = recordings[1]
    assert first.input_keys() == ("lerobot_info", "lerobot_data", "lerobot_video", "model", "camera")
    assert first.lerobot_video.endswith("episode_000001.mp4")
    summary = batch.run_recording(first, str(tmp_path / "out"), jobs=1)
    assert summary["status"] == "done" and summary["frames_total"] == 10
    mine = json.loads((tmp_path / "out" / "demo-000001" / "report.json").read_text())
    ref = kccd.check_log(kccd.Model.load(str(DATA / "demo_arm.yaml")), lerobot=str(ds), episode=1,
                         report=str(tmp_path / "check.json"))
    checked = json.loads((tmp_path / "check.json").read_text())
    assert [f["status"] for f in mine["frames"]] == [f["status"] for f in checked["frames"]] and ref["samples"] == 10
    assert batch.complete_summary(first, str(tmp_path / "out")) is not None
    for text, problem in [
        (f"  - {{id: x, lerobot: {ds}, episodes: [4]}}\n", "recordings[0].episodes[0]: 4 is not an episode of"),
        (f"  - {{id: x, lerobot: {ds}, episodes: '5:9'}}\n", "recordings[0].episodes: no episode of"),
        (f"  - {{id: x, video: a.mkv, states: s.csv, episodes: all}}\n", "recordings[0].episodes: goes with lerobot"),
        (f"  - {{id: x, lerobot: {ds}, camera_key: observation.images.top}}\n", "camera_key"),
        (f"  - {{id: x, lerobot: {tmp_path}}}\n", "recordings[0].lerobot: "),
    ]:
        manifest.write_text(f"kccd_batch: 1\ndefaults: {{model: {DATA / 'demo_arm.yaml'}, camera: {rec / 'camera_true.yaml'}}}\n"
                            "recordings:\n" + text)
        with pytest.raises(batch.ManifestError, match=re.escape(problem)):
            batch.read_manifest(str(manifest))
