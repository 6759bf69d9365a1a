"""kccd.render, kccd.Camera and the main job from Python: images as NumPy arrays, the overlay of a
short synthetic recording equal to `kccd overlay`'s report, progress callbacks, errors."""

import json
import pathlib
import re
import subprocess

import numpy as np
import pytest

import kccd
from conftest import DATA


def test_render_rgba_and_labels(arm: kccd.Model, camera: kccd.Camera) -> None:
    img = kccd.render(arm, camera, state=[0.3, -0.5, 0.8], mask=True)
    rgba, labels = img["rgba"], img["labels"]
    assert labels is not None
    assert rgba.shape == (camera.height, camera.width, 4) and rgba.dtype == np.uint8 and rgba.flags["C_CONTIGUOUS"]
    assert labels.shape == (camera.height, camera.width) and labels.dtype == np.uint8
    drawn = set(np.unique(labels)) - {0}
    assert drawn and max(drawn) <= len(arm.bodies)
    assert img["status"] == ["clear"] * len(arm.bodies)
    # A clear volume is tinted green: where a label is, green dominates red (RGBA order).
    inside = (labels > 0) & (rgba[..., 3] > 0)
    assert inside.any()
    assert rgba[..., 1][inside].mean() > rgba[..., 0][inside].mean()
    assert kccd.render(arm, camera, state=[0.3, -0.5, 0.8])["labels"] is None


def test_render_swept_box_and_errors(arm: kccd.Model, camera: kccd.Camera) -> None:
    still = kccd.render(arm, camera, state=[0.3, -0.5, 0.8], mask=True)["labels"]
    swept = kccd.render(arm, camera, lower=[0.0, -0.7, 0.6], upper=[0.6, -0.3, 1.0], mask=True)["labels"]
    assert still is not None and swept is not None
    assert (swept > 0).sum() > (still > 0).sum()  # the swept arm covers more of the image
    with pytest.raises(ValueError, match="lower, upper"):
        kccd.render(arm, camera, lower=[0.0] * 3)
    with pytest.raises(ValueError, match="state"):
        kccd.render(arm, camera, state=[0.0])


def test_camera_round_trip_and_errors(camera: kccd.Camera, tmp_path: pathlib.Path) -> None:
    camera.save(str(tmp_path / "cam.yaml"))
    again = kccd.Camera.load(str(tmp_path / "cam.yaml"))
    assert np.array_equal(again.camera_matrix, camera.camera_matrix)
    assert np.array_equal(again.rvec, camera.rvec) and np.array_equal(again.tvec, camera.tvec)
    (tmp_path / "bad.yaml").write_text((DATA / "demo_camera.yaml").read_text().replace("width:", "wdth:"))
    with pytest.raises(kccd.InputError) as e:
        kccd.Camera.load(str(tmp_path / "bad.yaml"))
    assert "bad.yaml" in e.value.source


def test_overlay_equals_cli(cli, arm: kccd.Model, tmp_path: pathlib.Path) -> None:
    fractions: list[float] = []
    s = kccd.synthesize_recording(str(DATA / "demo_arm.yaml"), str(tmp_path / "rec"), seconds=1.0,
                                  progress=fractions.append)
    assert s["frames"] == 25 and len(fractions) == 25 and fractions[-1] == 1.0
    assert s["collision_intervals"] and len(s["min_distance"]) == 25
    calls: list[tuple[int, int, float]] = []
    camera = kccd.Camera.load(s["camera"])
    rep = kccd.overlay_recording(arm, camera, s["video"], s["states"], output=str(tmp_path / "py.mp4"),
                                 report=str(tmp_path / "py.json"), time_offset=s["time_offset"], jobs=2,
                                 progress=lambda *a: calls.append(a))
    assert [c[0] for c in calls] == list(range(1, 26))
    assert rep["frames_total"] == 25 and rep["colliding"] > 0
    assert (tmp_path / "py.mp4").stat().st_size > 0
    subprocess.run([str(cli), "overlay", str(DATA / "demo_arm.yaml"), "--camera", s["camera"], "--video", s["video"],
                    "--states", s["states"], "--time-offset", repr(s["time_offset"]), "--report",
                    str(tmp_path / "cli.json"), "-o", str(tmp_path / "cli.mp4"), "--quiet"], check=True)
    cli_rep = json.loads((tmp_path / "cli.json").read_text())
    py_rep = json.loads((tmp_path / "py.json").read_text())
    for key in ("frames_total", "within_margin", "colliding", "no_state", "unsafe", "time_offset", "margin"):
        assert py_rep[key] == cli_rep[key] == rep[key]
    assert py_rep["frames"] == cli_rep["frames"] == rep["frames"]


def test_overlay_errors_and_progress_exceptions(arm: kccd.Model, camera: kccd.Camera, tmp_path: pathlib.Path) -> None:
    states = tmp_path / "s.csv"
    states.write_text("time,shoulder_yaw,shoulder_pitch,elbow\n0,0,0,0\n0.1,0,0,x\n")
    with pytest.raises(kccd.InputError) as e:
        kccd.overlay_recording(arm, camera, str(tmp_path / "none.mkv"), str(states))
    assert e.value.line == 3 and "s.csv" in e.value.source
    s = kccd.synthesize_recording(str(DATA / "demo_arm.yaml"), str(tmp_path / "rec"), seconds=0.2)
    rec_camera = kccd.Camera.load(s["camera"])
    # Outputs are checked before any frame is decoded, as `kccd overlay` checks them.
    kept = pathlib.Path(s["video"]).read_bytes()
    with pytest.raises(kccd.InputError, match="is an input of this run"):
        kccd.overlay_recording(arm, rec_camera, s["video"], s["states"], output=s["video"])
    assert pathlib.Path(s["video"]).read_bytes() == kept
    with pytest.raises(kccd.InputError, match=r"output .*\.mov: the output must be a \.mp4, \.mkv or \.avi file"):
        kccd.overlay_recording(arm, rec_camera, s["video"], s["states"], output=str(tmp_path / "x.mov"))
    with pytest.raises(kccd.InputError, match="does not exist"):
        kccd.overlay_recording(arm, rec_camera, s["video"], s["states"], report=str(tmp_path / "no" / "r.json"))

    def stop(*_: object) -> None:
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        kccd.overlay_recording(arm, rec_camera, s["video"], s["states"], progress=stop,
                               time_offset=s["time_offset"], report=str(tmp_path / "r.json"))
    assert not (tmp_path / "r.json").exists()


def test_contact_sheet_of_frames_of_two_sizes(tmp_path: pathlib.Path) -> None:
    wide = np.zeros((90, 160, 3), np.uint8)
    wide[..., 0] = 200  # red
    tall = np.zeros((240, 160, 3), np.uint8)
    tall[..., 2] = 200  # blue, taller than the first tile
    kccd.contact_sheet([wide, tall, wide], ["a #1", "b #2", "a #3"], str(tmp_path / "sheet.png"), tile_width=160)
    sheet = kccd.read_image(str(tmp_path / "sheet.png"))
    # Three tiles in a row, as tall as the tallest, every tile drawn whole.
    assert sheet.shape[1] == 3 * 164 + 4 and sheet.shape[0] >= 240 + 22
    assert (sheet[4:94, 4:164] == [200, 0, 0]).all()
    assert (sheet[4:244, 168:328] == [0, 0, 200]).all()
    assert (sheet[4:94, 332:492] == [200, 0, 0]).all()
    with pytest.raises(ValueError, match="captions"):
        kccd.contact_sheet([wide], [], str(tmp_path / "x.png"))
    with pytest.raises(ValueError, match=r"frames\[0\]"):
        kccd.contact_sheet([wide[..., 0]], ["x"], str(tmp_path / "x.png"))
    with pytest.raises(ValueError, match="png"):
        kccd.contact_sheet([wide], ["x"], str(tmp_path / "x.jpg"))
    assert not (tmp_path / "x.png").exists()


def test_read_frames_equal_read_frame(tmp_path: pathlib.Path) -> None:
    s = kccd.synthesize_recording(str(DATA / "demo_arm.yaml"), str(tmp_path / "rec"), seconds=0.4)
    frames = kccd.read_frames(s["video"], [7, 2, 7])
    assert len(frames) == 3 and (frames[0] == frames[2]).all()
    assert (frames[1] == kccd.read_frame(s["video"], 2)).all() and (frames[0] == kccd.read_frame(s["video"], 7)).all()
    assert kccd.read_frames(s["video"], []) == []
    with pytest.raises(ValueError, match="indices"):
        kccd.read_frames(s["video"], [-1])


def test_overlay_braking_is_checked(arm: kccd.Model, camera: kccd.Camera, tmp_path: pathlib.Path) -> None:
    states = tmp_path / "s.csv"
    states.write_text("time,shoulder_yaw,shoulder_pitch,elbow\n0,0,0,0\n0.1,0,0,0\n")
    video = str(tmp_path / "none_%04d.png")
    with pytest.raises(ValueError, match="^braking: only with swept "):
        kccd.overlay_recording(arm, camera, video, str(states), braking=kccd.BrakingParams(latency=0.01))
    for field in ("latency", "position_error", "velocity_error", "max_acceleration"):
        with pytest.raises(ValueError, match=rf"^braking\.{field}: must be in \["):
            kccd.overlay_recording(arm, camera, video, str(states), swept=True,
                                   braking=kccd.BrakingParams(**{field: -1.0}))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^braking\.deceleration: must be in \[1e-09, 1000000000\], got nan"):
        kccd.overlay_recording(arm, camera, video, str(states), swept=True,
                               braking=kccd.BrakingParams(deceleration=float("nan")))


def test_overlay_braking_is_the_commands() -> None:
    b = kccd.overlay_braking()
    assert (b.latency, b.deceleration, b.max_acceleration, b.position_error, b.velocity_error) == (0.01, 5.0, 0, 0, 0)
    b.latency = 1.0
    assert kccd.overlay_braking().latency == 0.01, "each call is a fresh copy"


# Every option of `kccd synth` has its argument in kccd.synthesize_recording, under its field's name;
# an option out of range is named in each front end's spelling.
SYNTH_OPTIONS = {"--camera": "camera", "--seconds": "seconds", "--fps": "fps", "--width": "width", "--height": "height",
                 "--seed": "seed", "--codec": "codec", "--log-rate": "log_rate", "--time-offset": "time_offset",
                 "--visible-scale": "visible_scale", "--appearance": "appearance", "--blur": "blur", "--noise": "noise",
                 "--no-collision": "collision", "--force": "replace", "--bag": "bag", "--output": "output"}


def test_every_synth_option_has_its_python_argument(cli, tmp_path: pathlib.Path) -> None:
    text = subprocess.run([str(cli), "synth", "--help"], check=True, capture_output=True, text=True).stdout
    shown = set(re.findall(r"^\s+(?:-\w,)?(--[\w-]+)", text, re.M)) - {"--help", "--quiet"}
    assert shown == set(SYNTH_OPTIONS), sorted(shown)
    signature = kccd.synthesize_recording.__doc__.splitlines()[0]
    for name in SYNTH_OPTIONS.values():
        assert re.search(rf"\b{name}:", signature), f"synthesize_recording has no {name}"
    model = str(DATA / "demo_arm.yaml")
    run = subprocess.run([str(cli), "synth", model, "-o", str(tmp_path / "a"), "--fps", "25", "--log-rate", "25"],
                         capture_output=True, text=True)
    assert run.returncode == 2 and run.stderr.startswith("kccd: --log-rate: must differ from the frame rate"), run.stderr
    with pytest.raises(kccd.InputError, match="^log_rate: must differ from the frame rate"):
        kccd.synthesize_recording(model, str(tmp_path / "b"), fps=25, log_rate=25)
    with pytest.raises(kccd.InputError, match=r"^blur: must be in \[0, 10\]"):
        kccd.synthesize_recording(model, str(tmp_path / "b"), blur=11)
    s = kccd.synthesize_recording(model, str(tmp_path / "c"), seconds=0.2, width=640, height=400, appearance="volumes",
                                  visible_scale=0.5, noise=0, bag=True)
    assert s["width"] == 640 and s["height"] == 400
    # bag=True: the state log and the frames as a bag beside it, read as the same samples; its frames on
    # the log's clock overlay as the video does at the recording's time offset.
    assert s["bag"] == str(tmp_path / "c" / "states.mcap")
    arm = kccd.Model.load(model)
    assert kccd.check_log(arm, bag=s["bag"])["samples"] == kccd.check_log(arm, s["states"])["samples"] == s["log_rows"]
    camera = kccd.Camera.load(s["camera"])
    by_bag = kccd.overlay_recording(arm, camera, bag=s["bag"])["frames"]
    by_files = kccd.overlay_recording(arm, camera, s["video"], s["states"], time_offset=s["time_offset"])["frames"]
    assert len(by_bag) == len(by_files) == s["frames"]
    assert [f["status"] for f in by_bag] == [f["status"] for f in by_files]
    assert all(f["time"] == pytest.approx(i / s["fps"] + s["time_offset"], abs=1e-9) for i, f in enumerate(by_bag))


def test_overlay_masks_equal_cli(cli, arm: kccd.Model, tmp_path: pathlib.Path) -> None:
    # kccd overlay --masks from Python: the same agreement as the command line, for mask files and
    # for masks made from the recording.
    s = kccd.synthesize_recording(str(DATA / "demo_arm.yaml"), str(tmp_path / "rec"), seconds=0.4, width=640, height=400)
    camera = kccd.Camera.load(s["camera"])
    masks = str(pathlib.Path(s["video"]).parent / "masks")
    for given in (masks, "auto"):  # the synthetic arm barely moves in 0.4 s: "auto" may know too little to say
        py = kccd.overlay_recording(arm, camera, s["video"], s["states"], time_offset=s["time_offset"], masks=given,
                                    report=str(tmp_path / "py.json"))
        subprocess.run([str(cli), "overlay", str(DATA / "demo_arm.yaml"), "--camera", s["camera"], "--video", s["video"],
                        "--states", s["states"], "--time-offset", repr(s["time_offset"]), "--masks", given, "--report",
                        str(tmp_path / "cli.json"), "-q"], check=True)
        cli_report = json.loads((tmp_path / "cli.json").read_text())
        assert py["mask_agreement"] == cli_report["mask_agreement"], given
        assert [f.get("mask_iou") for f in py["frames"]] == [f.get("mask_iou") for f in cli_report["frames"]]
        if given == masks:  # every frame has its mask file: the drawn volumes are 0.8 of the visible radius
            assert py["mask_agreement"]["frames"] == s["frames"] and py["mask_agreement"]["mean_iou"] > 0.6
    with pytest.raises(ValueError, match="mask_bodies: 'arm' is not a body"):
        kccd.overlay_recording(arm, camera, s["video"], s["states"], masks=masks, mask_bodies=["arm"], report=str(tmp_path / "x.json"))


# kccd overlay and kccd.overlay_recording are two spellings of one request (kccd/overlay/jobs/
# overlay_job.hpp): every option has its keyword with the same default, and a bad value gets the same
# message with the field spelled by each front end.
OVERLAY_CLI_ONLY = {"--help", "--json", "--quiet", "--camera"}  # printing; Python takes a loaded Camera
BRAKING_OPTIONS = {"--latency", "--deceleration", "--max-acceleration", "--position-error", "--velocity-error"}
BRAKING_SPELLED = ", ".join(sorted(BRAKING_OPTIONS, key=["--latency", "--deceleration", "--max-acceleration",
                                                          "--position-error", "--velocity-error"].index)[:-1]) + \
    " and --velocity-error"


def _overlay_keywords() -> dict[str, str]:
    signature = " ".join(kccd.overlay_recording.__doc__.split("\n\n")[0].split())
    assert signature.startswith("overlay_recording(model, camera, video='', states='', *,"), signature
    return dict(re.findall(r"(\w+)=('[^']*'|\[\]|-?[\w.]+)", signature))


def _python_default(text: str) -> object:
    return {"''": "", "[]": "", "None": None, "False": False, "True": True}.get(text, text.strip("'"))


def _field(option: str) -> str:
    return "output" if option == "-o" else option[2:].replace("-", "_")


def _as_fields(message: str) -> str:
    # The command line's spelling of fields made Python's: "--max-gap" -> "max_gap", "-o" -> "output".
    message = message.replace(BRAKING_SPELLED, "braking")
    return re.sub(r"(?<![\w-])(--[a-z][a-z-]*|-o\b)",
                  lambda m: ("braking." if m.group(1) in BRAKING_OPTIONS else "") + _field(m.group(1)), message)


def test_every_overlay_option_has_its_python_keyword(cli, tmp_path: pathlib.Path) -> None:
    text = subprocess.run([str(cli), "overlay", "--help"], check=True, capture_output=True, text=True).stdout
    options = dict(re.findall(r"^\s+(?:-\w,)?(--[\w-]+)(?: [A-Z]+(?:=(\S+))?)?", text, re.M))
    keywords = _overlay_keywords()
    fields = {_field(o) for o in set(options) - OVERLAY_CLI_ONLY - BRAKING_OPTIONS} | {"braking"}
    assert fields == set(keywords) - {"progress", "progress_every"}, sorted(fields ^ set(keywords))
    for option, default in options.items():
        if option in OVERLAY_CLI_ONLY or option in BRAKING_OPTIONS:
            continue
        py = _python_default(keywords[_field(option)])
        cli_default: object = default or ""
        if py in (False, True):  # a flag
            assert cli_default == "" and py is False, option
        elif isinstance(py, str) and py and py[0].isdigit():
            assert float(cli_default or 0) == float(py), (option, cli_default, py)
        else:
            assert cli_default == py, (option, cli_default, py)
    b = kccd.overlay_braking()
    for option in BRAKING_OPTIONS:
        assert float(options[option]) == getattr(b, _field(option)), option


def test_overlay_messages_are_the_same_from_both_front_ends(cli, arm: kccd.Model, tmp_path: pathlib.Path) -> None:
    s = kccd.synthesize_recording(str(DATA / "demo_arm.yaml"), str(tmp_path / "rec"), seconds=0.2)
    camera = kccd.Camera.load(s["camera"])
    swept = {"swept": True}
    cases: list[tuple[list[str], dict[str, object]]] = [
        (["--fps", "-1"], {"fps": -1.0}),
        (["--max-gap", "-1"], {"max_gap": -1.0}),
        (["--jobs", "300"], {"jobs": 300}),
        (["--contact-frames", "0"], {"contact_frames": 0}),
        (["--time-offset", "auto:2:1"], {"time_offset": "auto:2:1"}),
        (["--time-offset", "soon"], {"time_offset": "soon"}),
        (["--time-offset", "2e9"], {"time_offset": 2e9}),
        (["--codec", "xx"], {"codec": "xx"}),
        (["--legend", "left"], {"legend": "left"}),
        (["--plain", "--legend", "outside"], {"plain": True, "legend": "outside"}),
        (["--frames", "5:2"], {"frames": "5:2"}),
        (["--mask-bodies", "upper_arm"], {"mask_bodies": ["upper_arm"]}),
        (["--masks", "auto", "--mask-bodies", "arm"], {"masks": "auto", "mask_bodies": ["arm"]}),
        (["--latency", "0.5"], {"braking": kccd.BrakingParams(latency=0.5, deceleration=5.0)}),
        (["--swept", "--latency", "1e4"], {**swept, "braking": kccd.BrakingParams(latency=1e4, deceleration=5.0)}),
        (["--swept", "--deceleration", "0"], {**swept, "braking": kccd.BrakingParams(latency=0.01, deceleration=0.0)}),
        (["--image-topic", "/c"], {"image_topic": "/c"}),
        (["--joint-map", "m.yaml"], {"joint_map": "m.yaml"}),
        (["--time-source", "wall"], {"time_source": "wall"}),
        (["--visuals"], {"visuals": True}),
        (["-o", str(tmp_path / "x.mov")], {"output": str(tmp_path / "x.mov")}),
        (["--timeline", str(tmp_path / "no" / "t.png")], {"timeline": str(tmp_path / "no" / "t.png")}),
        (["--frame-times", str(tmp_path / "none.csv")], {"frame_times": str(tmp_path / "none.csv")}),
        (["--ignore-columns", "time"], {"ignore_columns": ["time"]}),
        (["--episode", "3"], {"episode": 3}),
        (["--frame-by", "index"], {"frame_by": "index"}),
        (["--camera-key", "observation.images.top"], {"camera_key": "observation.images.top"}),
        (["--lerobot", str(tmp_path)], {"lerobot": str(tmp_path)}),
    ]
    base = [str(cli), "overlay", str(DATA / "demo_arm.yaml"), "--camera", s["camera"], "--video", s["video"],
            "--states", s["states"], "--report", str(tmp_path / "r.json")]
    for args, kwargs in cases:
        run = subprocess.run(base + args, capture_output=True, text=True)
        assert run.returncode == 2 and run.stderr.startswith("kccd: "), (args, run.stderr)
        with pytest.raises(kccd.InputError) as e:
            kccd.overlay_recording(arm, camera, s["video"], s["states"], report=str(tmp_path / "r.json"), **kwargs)
        assert _as_fields(run.stderr.strip()[len("kccd: "):]) == str(e.value), args
        assert not (tmp_path / "r.json").exists()
    with pytest.raises(TypeError, match="unexpected keyword argument 'fsp'"):
        kccd.overlay_recording(arm, camera, s["video"], s["states"], fsp=25.0)
    with pytest.raises(TypeError, match="fps: expected"):
        kccd.overlay_recording(arm, camera, s["video"], s["states"], fps="fast")
