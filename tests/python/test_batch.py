"""kccd.batch on a local Dask cluster of 2 worker processes: three short synthetic recordings (one
with a corrupted video) give two outputs equal to `kccd overlay` on each and one reported failure;
a worker killed mid-run has its recording run again to completion; --resume runs only what is
missing or changed; manifest mistakes are named by line and start nothing."""

import dataclasses
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import threading
import time

import pytest

import kccd
from conftest import DATA

import distributed  # noqa: E402  (scripts/install-deps.sh installs it: the batch is tested, never skipped)
from kccd import batch  # noqa: E402


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> pathlib.Path:
    root = tmp_path_factory.mktemp("fleet")
    shutil.copy(DATA / "demo_arm.yaml", root / "arm.yaml")
    for name, seconds, seed in (("a", 1.0, 1), ("b", 1.0, 2), ("long", 6.0, 3)):
        kccd.synthesize_recording(str(root / "arm.yaml"), str(root / name), seconds=seconds, seed=seed)
    (root / "c").mkdir()
    shutil.copy(root / "b" / "states.csv", root / "c" / "states.csv")
    (root / "c" / "video.mkv").write_bytes((root / "b" / "video.mkv").read_bytes()[:4000])
    (root / "fleet.yaml").write_text(
        "kccd_batch: 1\n"
        "defaults: {model: arm.yaml, camera: a/camera_true.yaml, time_offset: 0.137}\n"
        "recordings:\n"
        "  - {id: cell-a, video: a/video.mkv, states: a/states.csv}\n"
        "  - {id: cell-b, video: b/video.mkv, states: b/states.csv, swept: true}\n"
        "  - {id: cell-c, video: c/video.mkv, states: c/states.csv}\n")
    return root


@pytest.fixture(scope="module")
def client():  # type: ignore[no-untyped-def]
    import dask

    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                      silence_logs=40) as cluster, distributed.Client(cluster) as c:
            yield c


def visible(folder: pathlib.Path) -> list[str]:
    """What a folder holds, without its hidden names (the batch's lock file)."""
    return sorted(n for n in os.listdir(folder) if not n.startswith("."))


def cli_report(cli: pathlib.Path, fleet: pathlib.Path, rec: str, out: pathlib.Path, swept: bool) -> dict:
    args = [str(cli), "overlay", str(fleet / "arm.yaml"), "--camera", str(fleet / "a" / "camera_true.yaml"), "--video",
            str(fleet / rec / "video.mkv"), "--states", str(fleet / rec / "states.csv"), "--time-offset", "0.137",
            "--report", str(out / "report.json"), "-o", str(out / "overlay.mp4"), "--quiet"]
    subprocess.run(args + (["--swept"] if swept else []), check=True)
    return json.loads((out / "report.json").read_text())


def test_batch_equals_overlay_and_reports_the_failure(cli, fleet: pathlib.Path, client, tmp_path: pathlib.Path) -> None:
    seen: list[batch.BatchProgress] = []
    result = batch.run_batch(str(fleet / "fleet.yaml"), str(tmp_path / "out"), client=client, progress=seen.append)
    out = tmp_path / "out"
    assert result.failed == ["cell-c"]
    s = json.loads((out / "summary.json").read_text())
    by_id = {r["id"]: r for r in s["recordings"]}
    assert [r["id"] for r in s["recordings"]] == ["cell-a", "cell-b", "cell-c"]
    assert by_id["cell-c"]["status"] == "failed" and "c/video.mkv" in by_id["cell-c"]["reason"]
    assert "\n" not in by_id["cell-c"]["reason"]
    assert not (out / "cell-c").exists()
    assert visible(out) == ["cell-a", "cell-b", "colliding_frames.png", "summary.json", "summary.md"]
    assert sorted(os.listdir(out)) == [".kccd-batch.lock"] + visible(out), "no staging folder is left"
    total = {"frames_total": 0, "colliding": 0, "within_margin": 0, "clear": 0}
    for rec, swept in (("a", False), ("b", True)):
        rid = f"cell-{rec}"
        assert sorted(os.listdir(out / rid)) == sorted(batch.OUTPUT_FILES)
        mine = json.loads((out / rid / "report.json").read_text())
        ref_dir = tmp_path / f"ref-{rec}"
        ref_dir.mkdir()
        ref = cli_report(cli, fleet, rec, ref_dir, swept)
        assert mine["video"] == "overlay.mp4" and mine["contact_sheet"] == "contact_sheet.png" and mine["timeline"] == "timeline.png"
        for key in set(ref) | set(mine):
            if key not in ("video", "contact_sheet", "timeline"):
                assert mine[key] == ref[key], key
        # The same frames drawn: the videos decode to the same pictures.
        n = ref["frames_total"]
        picks = [0, n // 2, n - 1]
        for x, y in zip(kccd.read_frames(str(out / rid / "overlay.mp4"), picks),
                        kccd.read_frames(str(ref_dir / "overlay.mp4"), picks)):
            assert (x == y).all()
        line = by_id[rid]
        assert line["status"] == "done" and line["frames_total"] == n
        assert line["colliding"] == sum(f["status"] == "colliding" for f in ref["frames"])
        assert line["clear"] + line["within_margin"] + line["colliding"] + line["no_state"] == n
        intervals = line["colliding_intervals"]
        assert sum(i["last_frame"] - i["first_frame"] + 1 for i in intervals) == line["colliding"]
        for i in intervals:
            assert ref["frames"][i["first_frame"]]["status"] == "colliding"
            assert ref["frames"][i["first_frame"]]["time"] == i["start_s"]
            assert i["first_frame"] == 0 or ref["frames"][i["first_frame"] - 1]["status"] != "colliding"
        for k in total:
            total[k] += line[k]
    for k, v in total.items():
        assert s["totals"][k] == v
    assert s["totals"]["done"] == 2 and s["totals"]["failed"] == 1
    assert set(s["needs_look"]) >= {"cell-c"}
    md = (out / "summary.md").read_text()
    assert "cell-c" in md and "failed" in md and "colliding_frames.png" in md
    assert s["colliding_frames"]["file"] == "colliding_frames.png" and s["colliding_frames"]["frames"]
    assert seen and seen[-1].done == 2 and seen[-1].failed == 1 and seen[-1].frames_done >= total["frames_total"]


def test_killed_worker_is_retried(fleet: pathlib.Path, client, tmp_path: pathlib.Path) -> None:
    manifest = tmp_path / "one.yaml"
    manifest.write_text(f"kccd_batch: 1\nrecordings:\n  - {{id: long, video: {fleet}/long/video.mkv, states: "
                        f"{fleet}/long/states.csv, model: {fleet}/arm.yaml, camera: {fleet}/a/camera_true.yaml, "
                        "time_offset: 0.137}\n")
    result: list[batch.BatchResult] = []
    frames: list[int] = []
    job = threading.Thread(target=lambda: result.append(batch.run_batch(
        str(manifest), str(tmp_path / "out"), client=client, jobs=1, progress=lambda p: frames.append(p.frames_done))))
    job.start()
    pids = client.run(os.getpid)
    victim = None
    deadline = time.monotonic() + 60
    while victim is None and time.monotonic() < deadline:
        time.sleep(0.05)
        if frames and frames[-1] >= 10:
            victim = next((w for w, keys in client.processing().items() if keys), None)
    assert victim is not None, "the recording never started"
    before = frames[-1]
    os.kill(pids[victim], signal.SIGKILL)
    killed_at = len(frames)
    job.join(timeout=240)
    assert not job.is_alive() and result
    # The task ran again from its first frame: the progress fell back below where it was.
    assert min(frames[killed_at:]) < before < 150, (before, frames)
    s = result[0].summary
    assert s["recordings"][0]["status"] == "done", s["recordings"][0]
    assert s["recordings"][0]["frames_total"] == 150
    assert sorted(os.listdir(tmp_path / "out" / "long")) == sorted(batch.OUTPUT_FILES)
    # The killed worker's staging folder is gone, and nothing but the outputs is there.
    assert [n for n in os.listdir(tmp_path / "out") if n.startswith(".")] == [".kccd-batch.lock"]


def test_resume_runs_only_what_is_missing(fleet: pathlib.Path, client, tmp_path: pathlib.Path) -> None:
    work = tmp_path / "fleet"
    shutil.copytree(fleet, work, ignore=shutil.ignore_patterns("long", "c"))
    text = (work / "fleet.yaml").read_text()
    (work / "fleet.yaml").write_text(text[: text.index("  - {id: cell-c")])
    out = tmp_path / "out"
    batch.run_batch(str(work / "fleet.yaml"), str(out), client=client, only="cell-a")
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["cell-a"]
    # Another run into the same folder while this one holds it is refused.
    import fcntl

    with open(out / ".kccd-batch.lock", "a") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        with pytest.raises(batch.BatchError, match="another kccd.batch run"):
            batch.run_batch(str(work / "fleet.yaml"), str(out), client=client)
    first = (out / "cell-a" / "overlay.mp4").stat()
    # An interrupted run leaves a staging folder; resuming removes it and runs only cell-b.
    (out / ".cell-b.partial-0123abcd").mkdir()
    (out / ".cell-b.partial-0123abcd" / "overlay.mp4").write_bytes(b"half")
    r = batch.run_batch(str(work / "fleet.yaml"), str(out), client=client, resume=True)
    kept = {x["id"]: x.get("skipped", False) for x in r.summary["recordings"]}
    assert kept == {"cell-a": True, "cell-b": False}
    assert (out / "cell-a" / "overlay.mp4").stat().st_ino == first.st_ino
    assert not any(".partial-" in n for n in os.listdir(out))
    # A touched input with the same content is still the same input; a changed one runs again.
    os.utime(work / "a" / "states.csv")
    r = batch.run_batch(str(work / "fleet.yaml"), str(out), client=client, resume=True)
    assert all(x.get("skipped") for x in r.summary["recordings"])
    states = (work / "a" / "states.csv").read_text().splitlines()
    states[5] = states[5][:-1] + ("1" if states[5][-1] != "1" else "2")
    (work / "a" / "states.csv").write_text("\n".join(states) + "\n")
    r = batch.run_batch(str(work / "fleet.yaml"), str(out), client=client, resume=True)
    assert {x["id"]: x.get("skipped", False) for x in r.summary["recordings"]} == {"cell-a": False, "cell-b": True}
    assert (out / "cell-a" / "overlay.mp4").stat().st_ino != first.st_ino
    # Other options are other outputs: a different contact sheet runs both again.
    r = batch.run_batch(str(work / "fleet.yaml"), str(out), client=client, resume=True, contact_frames=4)
    assert not any(x.get("skipped") for x in r.summary["recordings"])


@pytest.mark.parametrize("body, where", [
    ("kccd_batch: 2\nrecordings: []\n", "1: kccd_batch: unsupported version"),
    ("kccd_batch: 1\nrecordings:\n  - {id: x, video: a/video.mkv, states: a/states.csv, model: arm.yaml, "
     "camera: a/camera_true.yaml}\n  - {id: x, video: b/video.mkv, states: b/states.csv, model: arm.yaml, "
     "camera: a/camera_true.yaml}\n", "4: recordings[1].id: 'x' is also the id on line 3"),
    ("kccd_batch: 1\nrecordings:\n  -\n    video: a/video.mkv\n    id: x\n    states: a/states.csv\n    model: arm.yaml\n"
     "    camera: a/camera_true.yaml\n  - {id: x, video: b/video.mkv, states: b/states.csv, model: arm.yaml, "
     "camera: a/camera_true.yaml}\n", "9: recordings[1].id: 'x' is also the id on line 5"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv, colour: red}\n", "4: recordings[0].colour: unknown field"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, states: a/states.csv}\n", "4: recordings[0].video: missing"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: ../x, video: a/video.mkv, states: a/states.csv}\n", "4: recordings[0].id: '../x' is not a folder name"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml, time_offset: soon}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv}\n", "2: defaults.time_offset: expected a finite number"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/missing.mkv, states: a/states.csv}\n", "4: recordings[0].video: "),
    ("kccd_batch: 1\ndefaults: {model: a/states.csv, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv}\n", "2: defaults.model: "),
    ("kccd_batch: 1\nrecordings:\n  - {id: x, video: a/video.mkv, states: a/states.csv}\n",
     "3: recordings[0].model: missing (give it here or in defaults)"),
    ("kccd_batch: 1\nrecordings: [\n", "yaml: "),
    ("kccd_batch: !!int one\nrecordings: []\n", "1: kccd_batch: "),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml, time_offset: 1" + "0" * 400 + "}\n"
     "recordings:\n  - {id: x, video: a/video.mkv, states: a/states.csv}\n", "2: defaults.time_offset: "),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: Summary.JSON, video: a/video.mkv, states: a/states.csv}\n", "4: recordings[0].id: 'Summary.JSON' is the name"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/frame_%06d.png, states: a/states.csv}\n", "4: recordings[0].video: "),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv, braking: {deceleration: 0}}\n",
     "4: recordings[0].braking.deceleration: must be in [1e-09, 1000000000], got 0"),
    # The overlay's own checks (kccd.check_overlay_request), placed at the value's line.
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv,\n     fps: -1}\n",
     "5: recordings[0].fps: must be in [1e-06, 1000000], got -1"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml, mask_bodies: [upper_arm]}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv}\n", "2: defaults.mask_bodies: goes with masks"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv, time_offset: 'auto:2:1'}\n",
     "4: recordings[0].time_offset: expected auto:A:B with A < B"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv, visuals: true}\n",
     "4: recordings[0].visuals: the model has no visuals:"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv, masks: auto, mask_bodies: [arm]}\n",
     "4: recordings[0].mask_bodies: 'arm' is not a body of"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv, frame_times: a/none.csv}\n",
     "4: recordings[0].frame_times: "),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv, max_gap: 1e400}\n",
     "4: recordings[0].max_gap: expected a finite number"),
    ("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml, legend: left}\nrecordings:\n"
     "  - {id: x, video: a/video.mkv, states: a/states.csv}\n",
     "2: defaults.legend: expected 'auto', 'outside', 'off', 'top-left', 'top-right', 'bottom-left' or "
     "'bottom-right', got 'left'"),
])
def test_manifest_mistakes(fleet: pathlib.Path, tmp_path: pathlib.Path, body: str, where: str) -> None:
    manifest = fleet / f"bad-{abs(hash(body))}.yaml"
    manifest.write_text(body)
    with pytest.raises(batch.ManifestError) as e:
        batch.read_manifest(str(manifest))
    assert str(e.value).startswith(f"{manifest}:") and where in str(e.value), str(e.value)
    assert "\n" not in str(e.value)
    run = subprocess.run([sys.executable, "-m", "kccd.batch", str(manifest), "--out", str(tmp_path / "out")],
                         capture_output=True, text=True)
    assert run.returncode == 2 and where in run.stderr and not (tmp_path / "out").exists()


def test_manifest_takes_the_overlays_options(cli, fleet: pathlib.Path, tmp_path: pathlib.Path) -> None:
    # Options beyond the clock and braking reach the overlay as kccd overlay's flags do: the same report.
    (fleet / "a" / "times.csv").write_text("frame,time\n" + "".join(f"{i},{i * 0.041:.3f}\n" for i in range(25)))
    manifest = fleet / "options.yaml"
    manifest.write_text("kccd_batch: 1\ndefaults: {model: arm.yaml, camera: a/camera_true.yaml, plain: true}\n"
                        "recordings:\n  - {id: opts, video: a/video.mkv, states: a/states.csv, frame_times: a/times.csv,\n"
                        "     max_gap: 0.05, time_offset: 'auto:0:0.3', frames: '0:25:5'}\n")
    [rec] = batch.read_manifest(str(manifest))
    assert rec.frame_times == str(fleet / "a" / "times.csv") and "frame_times" in rec.input_keys()
    assert dict(rec.options) == {"plain": True, "max_gap": 0.05, "frames": "0:25:5"}
    summary = batch.run_recording(rec, str(tmp_path / "out"), jobs=1)
    assert summary["status"] == "done" and summary["frames_total"] == 25
    mine = json.loads((tmp_path / "out" / "opts" / "report.json").read_text())
    made = json.loads((tmp_path / "out" / "opts" / "inputs.json").read_text())
    assert made["options"] == {"plain": True, "max_gap": 0.05, "frames": "0:25:5"} and "frame_times" in made["inputs"]
    subprocess.run([str(cli), "overlay", str(fleet / "arm.yaml"), "--camera", str(fleet / "a" / "camera_true.yaml"),
                    "--video", str(fleet / "a" / "video.mkv"), "--states", str(fleet / "a" / "states.csv"),
                    "--frame-times", str(fleet / "a" / "times.csv"), "--max-gap", "0.05", "--time-offset", "auto:0:0.3",
                    "--frames", "0:25:5", "--plain", "--report", str(tmp_path / "cli.json"), "-q"], check=True)
    ref = json.loads((tmp_path / "cli.json").read_text())
    assert [f["written"] for f in mine["frames"]] == [i % 5 == 0 for i in range(25)]  # frames 0:25:5 into the video

    def checked(report: dict) -> list[dict]:  # what each frame was found (the command wrote no video)
        return [{k: v for k, v in f.items() if k != "written"} for f in report["frames"]]

    assert checked(mine) == checked(ref) and mine["time_offset"] == ref["time_offset"] and mine["max_gap"] == 0.05
    assert batch.complete_summary(rec, str(tmp_path / "out")) is not None
    changed = dataclasses.replace(rec, options=(("plain", True), ("max_gap", 0.06), ("frames", "0:25:5")))
    assert batch.complete_summary(changed, str(tmp_path / "out")) is None, "another option: run again"


def test_only_and_usage(fleet: pathlib.Path, tmp_path: pathlib.Path) -> None:
    with pytest.raises(batch.ManifestError, match="no recording id matches"):
        batch.run_batch(str(fleet / "fleet.yaml"), str(tmp_path / "out"), only="nothing-*")
    assert not (tmp_path / "out").exists()
    run = subprocess.run([sys.executable, "-m", "kccd.batch", "--help"], capture_output=True, text=True)
    assert run.returncode == 0 and "--scheduler" in run.stdout and "Exit status" in run.stdout
    for bad, word in ((["--workers", "0"], "--workers"), (["--contact-frames", "65"], "--contact-frames"),
                      (["--scheduler", "nonsense://x"], "--scheduler nonsense://x: cannot connect")):
        run = subprocess.run([sys.executable, "-m", "kccd.batch", str(fleet / "fleet.yaml"), "--out",
                              str(tmp_path / "o")] + bad, capture_output=True, text=True, timeout=120)
        assert run.returncode == 2 and word in run.stderr and "Traceback" not in run.stderr, run.stderr


def test_command_on_its_own_local_cluster(fleet: pathlib.Path, tmp_path: pathlib.Path) -> None:
    run = subprocess.run([sys.executable, "-m", "kccd.batch", str(fleet / "fleet.yaml"), "--out", str(tmp_path / "o"),
                          "--workers", "2", "--only", "cell-[ac]"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 1, run.stderr  # cell-c fails
    assert "1 of 2 recordings done, 1 failed" in run.stdout
    assert "Dask dashboard: http" in run.stderr and "cell-c: failed: " in run.stderr
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert [r["id"] for r in s["recordings"]] == ["cell-a", "cell-c"] and s["run"]["workers"] == 2
    assert sorted(os.listdir(tmp_path / "o" / "cell-a")) == sorted(batch.OUTPUT_FILES)
    assert "cell-a" in visible(tmp_path / "o")


def test_manifest_reader_survives_mutations(fleet: pathlib.Path, tmp_path: pathlib.Path) -> None:
    """The manifest reader's fuzz test: 3,000 random mutations of a valid manifest (bytes flipped,
    inserted, deleted, lines swapped or repeated, YAML specials spliced in) each either read or
    refused with one ManifestError line naming the file; nothing else escapes."""
    import random

    good = (fleet / "fleet.yaml").read_bytes()
    specials = [b"{", b"}", b"[", b"]", b":", b"- ", b"&a", b"*a", b"!!binary", b"\t", b"\x00", b"\xff", b"'",
                b'"', b"%YAML 1.1\n", b"---\n", b"1e999", b"-.inf", b".nan", b"~", b"<<: *a", b"\n  ", b"#",
                b"!!int ", b"!!float ", b"!!bool ", b"!!timestamp ", b"1" + b"0" * 400, b"%"]
    rng = random.Random(11)
    path = fleet / "mutant.yaml"
    outcomes = {"read": 0, "refused": 0}
    for _ in range(3000):
        b = bytearray(good)
        for _ in range(rng.randint(1, 4)):
            op = rng.randrange(5)
            at = rng.randrange(len(b) + 1)
            if op == 0 and b:
                b[min(at, len(b) - 1)] = rng.randrange(256)
            elif op == 1:
                b[at:at] = rng.choice(specials)
            elif op == 2:
                del b[at:at + rng.randint(1, 8)]
            else:
                lines = bytes(b).split(b"\n")
                i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
                if op == 3:
                    lines[i], lines[j] = lines[j], lines[i]
                else:
                    lines.insert(i, lines[j])
                b = bytearray(b"\n".join(lines))
        path.write_bytes(bytes(b))
        try:
            batch.read_manifest(str(path))
            outcomes["read"] += 1
        except batch.ManifestError as e:
            assert str(e).startswith(str(path)) and "\n" not in str(e), str(e)
            outcomes["refused"] += 1
    assert outcomes["read"] > 0 and outcomes["refused"] > 1000, outcomes
    big = tmp_path / "big.yaml"
    big.write_bytes(good + b"#" * batch.MAX_MANIFEST_BYTES)
    with pytest.raises(batch.ManifestError, match="more than"):
        batch.read_manifest(str(big))
    with pytest.raises(batch.ManifestError, match="not a regular file"):
        batch.read_manifest(str(tmp_path))
