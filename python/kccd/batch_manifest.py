"""The batch manifest of :mod:`kccd.batch` (docs/formats.md section 13): read node by node, every
mistake one line ``file:line: field: problem``, every input checked before anything starts."""

from __future__ import annotations

import dataclasses
import math
import os
import re
import stat
from collections.abc import Sequence
from typing import Any

import yaml

from . import _kccd as _core

#: The largest manifest read (bytes).
MAX_MANIFEST_BYTES = 4 << 20
#: What the batch itself writes in DIR: no recording may take these names.
_RESERVED = ("summary.json", "summary.md", "colliding_frames.png")
_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,127}")
_BAG_KEYS = ("image_topic", "joint_topic", "time_source", "joint_map")
#: More of kccd.overlay_recording's keywords, under their own names (checked by kccd.check_overlay_request).
OVERLAY_KEYS = ("frame_times", "ignore_columns", "fps", "max_gap", "plain", "legend", "visuals", "masks", "mask_bodies",
                "frames", "camera_key", "state_key", "frame_by")
#: A LeRobot dataset's recording: its folder and which episodes ("all", a list, or "FIRST:END").
_LEROBOT_KEYS = ("lerobot", "episodes")
_RECORDING_KEYS = ("id", "video", "states", "bag", "model", "camera", "time_offset", "swept", "braking") + _BAG_KEYS + \
    _LEROBOT_KEYS + OVERLAY_KEYS
_DEFAULT_KEYS = ("model", "camera", "time_offset", "swept", "braking") + _BAG_KEYS + OVERLAY_KEYS
#: The braking of swept volumes unless a manifest says otherwise (kccd overlay's defaults).
DEFAULT_BRAKING = {field: float(getattr(_core.overlay_braking(), field))
                   for field in ("latency", "deceleration", "max_acceleration", "position_error", "velocity_error")}


class ManifestError(ValueError):
    """A manifest that cannot be run: str() is one line 'file:line: field: problem'."""


@dataclasses.dataclass(frozen=True)
class Recording:
    """One recording of a manifest, its paths made absolute."""

    id: str
    video: str  #: "" for a robot log
    states: str  #: "" for a robot log
    model: str
    camera: str
    time_offset: float | str  #: seconds, or "auto:A:B"
    swept: bool
    line: int  #: where the manifest lists it (1-based)
    braking: tuple[tuple[str, float], ...] = tuple(DEFAULT_BRAKING.items())  #: with swept, every joint
    bag: str = ""  #: a robot log instead of video and states
    image_topic: str = ""
    joint_topic: str = ""
    time_source: str = "header"
    joint_map: str = ""
    frame_times: str = ""  #: with a video: each frame's time
    lerobot: str = ""  #: a LeRobot dataset's folder instead (one episode of it)
    episode: int = -1  #: with lerobot: its episode_index
    #: With lerobot: the files the episode is read from (meta/info.json, its table, its camera's video).
    lerobot_info: str = ""
    lerobot_data: str = ""
    lerobot_video: str = ""
    #: The other keywords of kccd.overlay_recording given (OVERLAY_KEYS but frame_times), lists as tuples.
    options: tuple[tuple[str, Any], ...] = ()

    def input_keys(self) -> tuple[str, ...]:
        """The fields naming this recording's input files."""
        if self.lerobot:
            recording: tuple[str, ...] = ("lerobot_info", "lerobot_data") + (("lerobot_video",) if self.lerobot_video else ())
        else:
            recording = ("bag",) if self.bag else ("video", "states") + (("frame_times",) if self.frame_times else ())
        return recording + ("model", "camera") + (("joint_map",) if self.joint_map else ())

    def keywords(self) -> dict[str, Any]:
        """kccd.overlay_recording's keywords for this recording (but its outputs, jobs and progress)."""
        kw: dict[str, Any] = {"time_offset": self.time_offset, "swept": self.swept}
        if self.swept:
            kw["braking"] = _core.BrakingParams(**dict(self.braking))
        if self.bag:
            kw.update(bag=self.bag, image_topic=self.image_topic, joint_topic=self.joint_topic,
                      time_source=self.time_source, joint_map=self.joint_map)
        elif self.lerobot:
            kw.update(lerobot=self.lerobot, episode=self.episode, joint_map=self.joint_map)
        elif self.frame_times:
            kw["frame_times"] = self.frame_times
        kw.update({k: list(v) if isinstance(v, tuple) else v for k, v in self.options})
        return kw


# --------------------------------------------------------------------------------------------
# The manifest


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def read_manifest(path: str, check_inputs: bool = True) -> list[Recording]:
    """The recordings of the manifest at `path`, in its order. Checks its structure (one YAML
    document, known keys, ``kccd_batch: 1``, ids explicit, unique and fit for a folder name) and,
    with `check_inputs`, that every input exists and every model and camera loads. Raises
    ManifestError naming the file, line and field."""
    try:
        st = os.stat(path)
        if not stat.S_ISREG(st.st_mode):
            raise ManifestError(f"{path}: manifest: not a regular file")
        if st.st_size > MAX_MANIFEST_BYTES:
            raise ManifestError(f"{path}: manifest: {st.st_size} bytes, more than {MAX_MANIFEST_BYTES}")
        with open(path, "rb") as f:
            raw = f.read(MAX_MANIFEST_BYTES + 1)
    except OSError as e:
        raise ManifestError(f"{path}: manifest: cannot read ({e.strerror})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ManifestError(f"{path}: not UTF-8 text (byte {e.start})") from None

    def fail(node: yaml.Node | None, field: str, problem: str) -> ManifestError:
        where = f"{path}:{node.start_mark.line + 1}" if node is not None else path
        return ManifestError(f"{where}: {field}: {problem}")

    loader: Any = None
    try:
        loader = yaml.SafeLoader(text)  # partly untyped in its stubs
        root = loader.get_single_node()
    except yaml.MarkedYAMLError as e:
        line = e.problem_mark.line + 1 if e.problem_mark else 0
        raise ManifestError(f"{path}:{line}: yaml: {_one_line(str(e.problem or e.context))}") from None
    except yaml.reader.ReaderError as e:
        line = text[: max(0, e.position)].count("\n") + 1
        raise ManifestError(f"{path}:{line}: yaml: character #x{e.character:04x} is not allowed") from None
    except yaml.YAMLError as e:
        raise ManifestError(f"{path}: yaml: {_one_line(str(e))}") from None
    finally:
        if loader is not None:
            loader.dispose()
    if not isinstance(root, yaml.MappingNode):
        raise fail(root, "manifest", "expected a mapping with kccd_batch, defaults and recordings")

    def mapping(node: yaml.Node, field: str, allowed: Sequence[str]) -> dict[str, yaml.Node]:
        if not isinstance(node, yaml.MappingNode):
            raise fail(node, field, "expected a mapping")
        out: dict[str, yaml.Node] = {}
        for k, v in node.value:
            if not isinstance(k, yaml.ScalarNode):
                raise fail(k, field, "keys must be plain words")
            if k.value in out:
                raise fail(k, f"{field}.{k.value}", "given twice")
            if k.value not in allowed:
                raise fail(k, f"{field}.{k.value}", "unknown field (known: " + ", ".join(allowed) + ")")
            out[k.value] = v
        return out

    def scalar(node: yaml.Node, field: str) -> Any:
        if not isinstance(node, yaml.ScalarNode):
            raise fail(node, field, "expected a single value")
        c: Any = yaml.SafeLoader("")
        try:
            return c.construct_object(node)
        except Exception as e:  # noqa: BLE001 - PyYAML's constructors raise more than YAMLError for bad tags
            raise fail(node, field, _one_line(str(e)) or f"cannot read this {node.tag} value") from None
        finally:
            c.dispose()

    def finite(v: Any) -> float | None:
        """v as a finite float, or None (bools, text, huge ints and non-finite values)."""
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            return None
        try:
            x = float(v)
        except OverflowError:
            return None
        return x if math.isfinite(x) else None

    def text_field(node: yaml.Node, field: str) -> str:
        v = scalar(node, field)
        if not isinstance(v, str) or not v:
            raise fail(node, field, "expected a non-empty text")
        return v

    def number_field(node: yaml.Node, field: str) -> float:
        x = finite(scalar(node, field))
        if x is None:
            raise fail(node, field, "expected a finite number")
        return x

    def time_offset_field(node: yaml.Node, field: str) -> float | str:
        v = scalar(node, field)
        if isinstance(v, str) and v.startswith("auto:"):
            return v
        x = finite(v)
        if x is None:
            raise fail(node, field, "expected a finite number of seconds, or auto:A:B")
        return x

    def texts_field(node: yaml.Node, field: str) -> tuple[str, ...]:
        if not isinstance(node, yaml.SequenceNode) or not node.value:
            raise fail(node, field, "expected a non-empty list of names")
        return tuple(text_field(v, f"{field}[{k}]") for k, v in enumerate(node.value))

    def overlay_options(merged: dict[str, yaml.Node], where: Any) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key in OVERLAY_KEYS:
            if key not in merged or key == "frame_times":
                continue
            node = merged[key]
            if key in ("fps", "max_gap"):
                out[key] = number_field(node, where(key))
            elif key in ("plain", "visuals"):
                out[key] = bool_field(node, where(key))
            elif key in ("ignore_columns", "mask_bodies"):
                out[key] = texts_field(node, where(key))
            elif key == "masks":
                masks = text_field(node, where(key))
                out[key] = masks if masks == "auto" else resolve(node, where(key))
            else:
                out[key] = text_field(node, where(key))
        return out

    def bool_field(node: yaml.Node, field: str) -> bool:
        v = scalar(node, field)
        if not isinstance(v, bool):
            raise fail(node, field, "expected true or false")
        return v

    def braking_field(node: yaml.Node, field: str) -> tuple[tuple[str, float], ...]:
        given = mapping(node, field, tuple(DEFAULT_BRAKING))
        out = dict(DEFAULT_BRAKING)
        for key, v in given.items():
            x = finite(scalar(v, f"{field}.{key}"))
            if x is None:
                raise fail(v, f"{field}.{key}", "expected a finite number (SI units: s, rad or m, per s, per s^2)")
            out[key] = x
        return tuple(out.items())

    top = mapping(root, "manifest", ("kccd_batch", "defaults", "recordings"))
    if "kccd_batch" not in top:
        raise fail(root, "kccd_batch", "missing (the first line of a batch manifest is kccd_batch: 1)")
    version = scalar(top["kccd_batch"], "kccd_batch")
    if version != 1 or isinstance(version, bool):
        raise fail(top["kccd_batch"], "kccd_batch", f"unsupported version {version!r} (this kccd reads 1)")
    defaults = mapping(top["defaults"], "defaults", _DEFAULT_KEYS) if "defaults" in top else {}
    if "recordings" not in top:
        raise fail(root, "recordings", "missing")
    seq = top["recordings"]
    if not isinstance(seq, yaml.SequenceNode) or not seq.value:
        raise fail(seq, "recordings", "expected a non-empty list")

    base = os.path.dirname(os.path.abspath(path))

    def resolve(node: yaml.Node, field: str) -> str:
        return os.path.normpath(os.path.join(base, text_field(node, field)))

    out: list[Recording] = []
    inputs: list[tuple[str, str, yaml.Node, str]] = []  # kind, path, its node, its field: checked below
    nodes: list[Any] = []  # each recording's field -> (its node, its field as the manifest names it)
    first_line: dict[str, int] = {}
    for i, item in enumerate(seq.value):
        name = f"recordings[{i}]"
        rec = mapping(item, name, _RECORDING_KEYS)
        if "id" not in rec:
            raise fail(item, f"{name}.id", "missing")
        if "bag" in rec and "lerobot" in rec:
            raise fail(rec["lerobot"], f"{name}.lerobot", "not with bag (one recording)")
        if "bag" in rec or "lerobot" in rec:
            what = "bag" if "bag" in rec else "lerobot"
            for key in ("video", "states"):
                if key in rec:
                    raise fail(rec[key], f"{name}.{key}", f"not with {what} (the {'robot log' if what == 'bag' else 'dataset'} "
                               "gives the frames and the states)")
        else:
            for key in ("video", "states"):
                if key not in rec:
                    raise fail(item, f"{name}.{key}", "missing (give video and states, bag, or lerobot)")
        if "episodes" in rec and "lerobot" not in rec:
            raise fail(rec["episodes"], f"{name}.episodes", "goes with lerobot")
        rid = text_field(rec["id"], f"{name}.id")
        if not _ID.fullmatch(rid):
            raise fail(rec["id"], f"{name}.id", f"'{rid}' is not a folder name (letters, digits, '.', '_', '-'; "
                       "at most 128; not starting with '.', '_' or '-')")
        if rid.lower() in _RESERVED:
            raise fail(rec["id"], f"{name}.id", f"'{rid}' is the name of a file the batch writes in DIR")
        if rid in first_line:
            raise fail(rec["id"], f"{name}.id", f"'{rid}' is also the id on line {first_line[rid]}")
        first_line[rid] = rec["id"].start_mark.line + 1
        merged = {**defaults, **rec}

        def where(key: str, rec: dict[str, yaml.Node] = rec, name: str = name) -> str:
            return f"{name}.{key}" if key in rec else f"defaults.{key}"

        for key in ("model", "camera"):
            if key not in merged:
                raise fail(item, f"{name}.{key}", "missing (give it here or in defaults)")
        keys = ("bag", "joint_map", "model", "camera") if "bag" in rec else \
            ("lerobot", "joint_map", "model", "camera") if "lerobot" in rec else ("video", "states", "frame_times", "model", "camera")
        paths = {key: resolve(merged[key], where(key)) for key in keys if key in merged}
        inputs += [(key, paths[key], merged[key], where(key)) for key in paths]
        if "bag" not in rec:
            for key in _BAG_KEYS:
                if key in rec and not (key == "joint_map" and "lerobot" in rec):
                    raise fail(rec[key], f"{name}.{key}", "goes with bag" + (" or lerobot" if key == "joint_map" else ""))
        elif "frame_times" in rec:
            raise fail(rec["frame_times"], f"{name}.frame_times", "not with bag (each frame has its own time)")
        topics = {key: text_field(merged[key], where(key)) for key in ("image_topic", "joint_topic") if key in merged and "bag" in rec}
        time_source = text_field(merged["time_source"], where("time_source")) if "time_source" in merged else "header"
        if time_source not in ("header", "log"):
            raise fail(merged["time_source"], where("time_source"), "expected header or log")

        def node_of(field: str, merged: dict[str, yaml.Node] = merged, item: yaml.Node = item, name: str = name,
                    where: Any = where) -> tuple[yaml.Node, str]:
            key, dot, rest = field.partition(".")  # "braking.latency": the braking node
            if key in merged:
                return merged[key], where(key) + dot + rest
            return item, f"{name}.{field}" if field else name

        episodes: list[tuple[str, int, dict[str, str]]] = [(rid, -1, {})]
        if "lerobot" in rec:
            episodes = _episodes(paths["lerobot"], rec, merged, name, rid, fail, scalar, where, first_line)
        for eid, episode, files in episodes:
            nodes.append(node_of)
            out.append(Recording(
                id=eid,
                lerobot=paths.get("lerobot", ""),
                episode=episode,
                lerobot_info=files.get("info", ""),
                lerobot_data=files.get("data", ""),
                lerobot_video=files.get("video", ""),
                video=paths.get("video", ""),
                states=paths.get("states", ""),
                model=paths["model"],
                camera=paths["camera"],
                bag=paths.get("bag", ""),
                joint_map=paths.get("joint_map", ""),
                time_source=time_source,
                **topics,
                time_offset=time_offset_field(merged["time_offset"], where("time_offset")) if "time_offset" in merged else 0.0,
                frame_times=paths.get("frame_times", ""),
                options=tuple(overlay_options(merged, where).items()),
                swept=bool_field(merged["swept"], where("swept")) if "swept" in merged else False,
                line=item.start_mark.line + 1,
                braking=braking_field(merged["braking"], where("braking"))
                if "braking" in merged else tuple(DEFAULT_BRAKING.items()),
            ))

    def check_options(models: dict[str, Any]) -> None:
        # The overlay's own checks of every option (kccd.check_overlay_request), each named by its node.
        for recording, node_of in zip(out, nodes):
            try:
                # braking is checked whether or not this recording sweeps (a manifest's value is never ignored)
                keywords: dict[str, Any] = {**recording.keywords(), "swept": True,
                                            "braking": _core.BrakingParams(**dict(recording.braking))}
                _core.check_overlay_request(models.get(recording.model), recording.video, recording.states, **keywords)
            except _core.InputError as e:
                node, field = node_of(e.field)
                raise fail(node, field, e.problem) from None

    check_options({})
    if check_inputs:
        checked: set[tuple[str, str]] = set()
        models: dict[str, Any] = {}
        for key, p, node, field in inputs:
            if key == "video" and _is_sequence(p):
                try:
                    frames = _sequence_files(p)
                except (TypeError, ValueError) as e:
                    raise fail(node, field, f"{p}: not an image-sequence pattern ({_one_line(str(e))})") from None
                if not frames:
                    raise fail(node, field, f"{p}: no image of the sequence (numbered from 0 or 1) exists")
            elif key == "lerobot":
                pass  # read when its episodes were listed
            elif key == "bag" and os.path.isdir(p):
                if not os.path.isfile(os.path.join(p, "metadata.yaml")) and not any(f.endswith(".mcap") for f in os.listdir(p)):
                    raise fail(node, field, f"{p}: a folder without metadata.yaml (not a rosbag2 bag)")
            elif not os.path.isfile(p):
                raise fail(node, field, f"{p}: no such file")
            if key in ("model", "camera") and (key, p) not in checked:
                checked.add((key, p))
                try:
                    if key == "model":
                        models[p] = _core.Model.load(p)
                    else:
                        _core.Camera.load(p)
                except _core.InputError as e:
                    raise fail(node, field, _one_line(str(e))) from None
        check_options(models)
    return out


def _episodes(path: str, rec: dict[str, yaml.Node], merged: dict[str, yaml.Node], name: str, rid: str, fail: Any,
              scalar: Any, where: Any, first_line: dict[str, int]) -> list[tuple[str, int, dict[str, str]]]:
    """A lerobot recording's episodes, each as (id, episode_index, its files): every episode of the
    dataset, or those `episodes` lists ([0, 3, 7] or "FIRST:END"); ids ``<id>-<episode, 6 digits>``."""
    try:
        info = _core.read_lerobot(path)["info"]
    except _core.InputError as err:
        raise fail(rec["lerobot"], f"{name}.lerobot", _one_line(str(err))) from None
    listed = {int(entry["episode"]): entry for entry in info["episode_list"]}
    span = f"{min(listed)} ... {max(listed)}" if listed else "none"
    chosen: list[int] = sorted(listed)
    if "episodes" in rec:
        node = rec["episodes"]
        if isinstance(node, yaml.SequenceNode) and node.value:
            chosen = []
            for k, v in enumerate(node.value):
                index = scalar(v, f"{name}.episodes[{k}]")
                if isinstance(index, bool) or not isinstance(index, int) or index not in listed:
                    raise fail(v, f"{name}.episodes[{k}]", f"{index!r} is not an episode of {path} (its episodes: {span})")
                chosen.append(index)
        else:
            text = scalar(node, f"{name}.episodes")
            m = re.fullmatch(r"(\d*):(\d*)", text) if isinstance(text, str) else None
            if text == "all":
                pass
            elif m:
                lo, hi = int(m.group(1) or 0), int(m.group(2)) if m.group(2) else max(listed, default=0) + 1
                chosen = [index for index in sorted(listed) if lo <= index < hi]
            else:
                raise fail(node, f"{name}.episodes", "expected all, a list of episode indices, or FIRST:END")
        if not chosen:
            raise fail(node, f"{name}.episodes", f"no episode of {path} chosen (its episodes: {span})")
    key = str(scalar(merged["camera_key"], where("camera_key"))) if "camera_key" in merged else ""
    cameras = [c["key"] for c in info["cameras"]]
    if key and key not in cameras:
        raise fail(merged["camera_key"], where("camera_key"),
                   f"'{key}' is not a camera of {path} (its cameras: {', '.join(cameras) or 'none'})")
    if not key and len(cameras) == 1:
        key = cameras[0]
    out: list[tuple[str, int, dict[str, str]]] = []
    for index in chosen:
        eid = f"{rid}-{index:06d}"
        if eid in first_line:
            raise fail(rec["id"], f"{name}.id", f"'{eid}' (episode {index}) is also the id on line {first_line[eid]}")
        first_line[eid] = rec["id"].start_mark.line + 1
        files = listed[index]["files"]
        video = files["videos"].get(key, "") if key else ""
        if video and not os.path.isfile(video):
            raise fail(rec.get("episodes", rec["lerobot"]), f"{name}.episodes",
                       f"episode {index}'s video {video} is not on disk (list the episodes to overlay)")
        out.append((eid, index, {"info": os.path.join(path, "meta", "info.json"), "data": files["data"] or "",
                                 "video": video}))
    return out


def _sequence_files(pattern: str) -> list[str]:
    """The files of an image-sequence pattern, numbered from 0 or 1 as the video reader does."""
    files: list[str] = []
    for start in (0, 1):
        k = start
        while os.path.isfile(pattern % k):
            files.append(pattern % k)
            k += 1
        if files:
            break
    return files


def _is_sequence(path: str) -> bool:
    """A path with a '%' is an image-sequence pattern (the rule of kccd's video reader)."""
    return "%" in path
