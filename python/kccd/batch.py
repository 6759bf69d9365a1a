"""Batch overlay of many recordings on a Dask cluster: ``python3 -m kccd.batch MANIFEST.yaml --out DIR``.

One task per recording runs :func:`kccd.overlay_recording` in a Dask worker process. Inputs are read
from paths every worker sees (shared storage); each recording's outputs are written into a hidden
staging folder under DIR and renamed to ``DIR/<id>/`` only when all of them are complete, so a
killed worker never leaves a folder that looks complete. A failed task is retried once, then
reported with its one-line reason while the others finish. ``DIR/summary.json`` and
``DIR/summary.md`` sum the fleet up.

The manifest (paths relative to it)::

    kccd_batch: 1
    defaults: {model: robot.yaml, camera: cam.yaml, time_offset: 0.137, swept: false}
    recordings:
      - {id: cell3-2026-11-20-a, video: rec/a.mkv, states: rec/a.csv}
      - {id: cell3-2026-11-20-b, video: rec/b.mkv, states: rec/b.csv, swept: true}
      - {id: cell3-2026-11-21, bag: rec/2026-11-21.mcap}

A recording is a video with its state log, or a robot log (``bag``: MCAP, rosbag2 .db3 or folder,
ROS 1 .bag) read as ``kccd overlay --bag`` reads it (``image_topic``, ``joint_topic``,
``time_source`` and ``joint_map`` here or in defaults). The overlay's other options are keys too,
under :func:`kccd.overlay_recording`'s names (``frame_times``, ``ignore_columns``, ``fps``,
``max_gap``, ``plain``, ``legend``, ``visuals``, ``masks``, ``mask_bodies``, ``frames``; ``time_offset`` may be
``auto:A:B``), each checked by the overlay's own checks (:func:`kccd.check_overlay_request`) before
anything starts.
"""

from __future__ import annotations

import argparse
import dataclasses
import fcntl
import fnmatch
import hashlib
import json
import logging
import os
import re
import shutil
import sys
import tempfile
import time
import uuid
from collections.abc import Callable, Sequence
from typing import Any


from . import _kccd as _core
from .batch_manifest import _ID, DEFAULT_BRAKING, MAX_MANIFEST_BYTES, ManifestError, Recording, _is_sequence, _one_line, \
    _sequence_files, read_manifest

__all__ = ["BatchError", "BatchProgress", "BatchResult", "DEFAULT_BRAKING", "MAX_MANIFEST_BYTES", "ManifestError", "OUTPUT_FILES",
           "Recording", "RecordingFailed", "colliding_intervals", "colliding_sheet", "complete_summary", "main", "provenance",
           "read_manifest", "recording_summary", "run_batch", "run_recording", "summarize", "summary_markdown"]

#: What each recording's folder holds when it is complete.
OUTPUT_FILES = ("overlay.mp4", "report.json", "contact_sheet.png", "timeline.png", "inputs.json")
_TOPIC = "kccd-batch"
#: Held (flock) while a batch writes in DIR: one run per output folder.
_LOCK = ".kccd-batch.lock"
#: The environment of local worker processes (Dask's default, less MALLOC_TRIM_THRESHOLD_).
_WORKER_ENVIRON = {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1}


class BatchError(RuntimeError):
    """A batch that cannot start (its output folder is in use, the scheduler cannot be reached):
    str() is one line."""


class RecordingFailed(RuntimeError):
    """A recording's task failed; str() is its one-line reason."""


# --------------------------------------------------------------------------------------------
# Provenance: what made a recording's outputs


def _input_files(path: str) -> list[str]:
    if os.path.isdir(path):  # a rosbag2 folder: its files
        return sorted(os.path.join(path, f) for f in os.listdir(path) if os.path.isfile(os.path.join(path, f)))
    return _sequence_files(path) if _is_sequence(path) else [path]


def _file_record(path: str, digest: str | None = None) -> dict[str, Any]:
    files = _input_files(path)
    stats = [os.stat(f) for f in files]
    if digest is None:
        h = hashlib.sha256()
        for f in files:
            with open(f, "rb") as fh:
                for block in iter(lambda: fh.read(1 << 20), b""):
                    h.update(block)
        digest = h.hexdigest()
    return {"path": path, "sha256": digest, "bytes": sum(s.st_size for s in stats),
            "mtime_ns": max((s.st_mtime_ns for s in stats), default=0), "files": len(files)}


def provenance(rec: Recording, contact_frames: int = 12) -> dict[str, Any]:
    """The inputs' hashes, the options and the kccd version a recording's outputs are made from."""
    return {
        "id": rec.id,
        "kccd_version": _core.__version__,
        "time_offset": rec.time_offset,
        "swept": rec.swept,
        "braking": dict(rec.braking),
        "contact_frames": contact_frames,
        "bag": provenance_bag(rec),
        "options": provenance_options(rec),
        "inputs": {key: _file_record(getattr(rec, key)) for key in rec.input_keys()},
    }


def provenance_bag(rec: Recording) -> dict[str, str] | None:
    """How a robot log is read (None for a video with its state log)."""
    return {"image_topic": rec.image_topic, "joint_topic": rec.joint_topic, "time_source": rec.time_source} if rec.bag else None


def provenance_options(rec: Recording) -> dict[str, Any]:
    """The other overlay keywords the manifest gives (fps, masks, ...), as JSON keeps them."""
    return {key: list(value) if isinstance(value, tuple) else value for key, value in rec.options}


def complete_summary(rec: Recording, out_dir: str, contact_frames: int = 12) -> dict[str, Any] | None:
    """The summary line of ``out_dir/<id>/`` when it holds every output, made by this kccd version
    with these options from these inputs; else None. An input with the recorded size and
    modification time counts as unchanged; one whose size or time differ is hashed again (a
    touched file with the same content still counts as unchanged)."""
    folder = os.path.join(out_dir, rec.id)
    if not all(os.path.isfile(os.path.join(folder, f)) for f in OUTPUT_FILES):
        return None
    try:
        with open(os.path.join(folder, "inputs.json"), encoding="utf-8") as f:
            made = json.load(f)
        if made.get("kccd_version") != _core.__version__ or made.get("time_offset") != rec.time_offset \
                or made.get("swept") != rec.swept or made.get("braking") != dict(rec.braking) \
                or made.get("contact_frames") != contact_frames or made.get("bag") != provenance_bag(rec) \
                or made.get("options", {}) != provenance_options(rec) \
                or sorted(made["inputs"]) != sorted(rec.input_keys()):
            return None
        for key in rec.input_keys():
            old = made["inputs"][key]
            path = getattr(rec, key)
            if old.get("path") != path:
                return None
            now = _file_record(path, digest=old["sha256"])
            if now["bytes"] == old["bytes"] and now["mtime_ns"] == old["mtime_ns"] and now["files"] == old["files"]:
                continue
            if _file_record(path)["sha256"] != old["sha256"]:
                return None
        with open(os.path.join(folder, "report.json"), encoding="utf-8") as f:
            return {**recording_summary(rec.id, json.load(f)), "skipped": True}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


# --------------------------------------------------------------------------------------------
# The task: one recording on one worker


def _write_text(path: str, text: str) -> None:
    """Writes `text` under a temporary name beside `path`, then renames it: never a partial file."""
    tmp = f"{path}.tmp-{uuid.uuid4().hex}"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def _write_json(path: str, value: Any) -> None:
    _write_text(path, json.dumps(value, indent=2, sort_keys=True) + "\n")


def _publish(message: dict[str, Any]) -> None:
    try:
        from distributed import get_worker

        get_worker().log_event(_TOPIC, message)
    except (ImportError, ValueError):
        pass  # not on a Dask worker (run_recording called directly)


def colliding_intervals(report: dict[str, Any], status: str = "colliding") -> list[dict[str, Any]]:
    """Runs of consecutive frames of an overlay report with `status` (colliding, or within_margin):
    first and last frame index and their video times (seconds)."""
    out: list[dict[str, Any]] = []
    for fr in report.get("frames", []):
        if fr.get("status") != status:
            continue
        if out and out[-1]["last_frame"] == fr["index"] - 1:
            out[-1]["last_frame"] = fr["index"]
            out[-1]["end_s"] = fr["time"]
        else:
            out.append({"first_frame": fr["index"], "last_frame": fr["index"], "start_s": fr["time"],
                        "end_s": fr["time"]})
    return out


def recording_summary(rec_id: str, report: dict[str, Any]) -> dict[str, Any]:
    """A done recording's line of summary.json, from its report."""
    frames = report.get("frames", [])
    return {
        "id": rec_id,
        "status": "done",
        "reason": "",
        "frames_total": report["frames_total"],
        "clear": sum(1 for f in frames if f.get("status") == "clear"),
        "within_margin": report["within_margin"],
        "colliding": report["colliding"],
        "no_state": report["no_state"],
        "unsafe": report.get("unsafe", 0),
        "colliding_intervals": colliding_intervals(report),
        "margin_intervals": colliding_intervals(report, "within_margin"),
    }


def run_recording(rec: Recording, out_dir: str, jobs: int = 0, contact_frames: int = 12,
                  run: str = "") -> dict[str, Any]:
    """Runs the overlay of one recording into ``out_dir/<id>/`` (staged: written into a hidden
    folder, renamed when every output is complete) and returns its summary line. `run` tags its
    progress events. Any failure is raised as RecordingFailed with a one-line reason, and nothing
    is left behind."""
    stage = ""
    final = os.path.join(out_dir, rec.id)
    try:
        os.makedirs(out_dir, exist_ok=True)
        stage = tempfile.mkdtemp(prefix=f".{rec.id}.partial-", dir=out_dir)
        os.chmod(stage, 0o755)  # mkdtemp's 0700 would hide the outputs from the others sharing the storage
        made = provenance(rec, contact_frames)
        model = _core.Model.load(rec.model)
        camera = _core.Camera.load(rec.camera)

        def progress(done: int, expected: int, fps: float) -> None:
            _publish({"run": run, "id": rec.id, "frames_done": done, "frames_expected": expected, "fps": fps})

        report = _core.overlay_recording(
            model, camera, rec.video, rec.states,
            output=os.path.join(stage, "overlay.mp4"), report=os.path.join(stage, "report.json"),
            contact_sheet=os.path.join(stage, "contact_sheet.png"), timeline=os.path.join(stage, "timeline.png"),
            jobs=jobs, contact_frames=contact_frames, progress=progress, progress_every=1.0, **rec.keywords())
        # The report names its outputs as they are once committed: beside it.
        report["video"] = "overlay.mp4"
        report["contact_sheet"] = "contact_sheet.png"
        report["timeline"] = "timeline.png"
        _write_json(os.path.join(stage, "report.json"), report)
        _write_json(os.path.join(stage, "inputs.json"), made)
        old = ""
        if os.path.lexists(final):
            old = os.path.join(out_dir, f".{rec.id}.old-{uuid.uuid4().hex}")
            os.rename(final, old)
        os.rename(stage, final)
        stage = ""
        if old:
            shutil.rmtree(old, ignore_errors=True)
        _publish({"run": run, "id": rec.id, "frames_done": report["frames_total"],
                  "frames_expected": report["frames_total"], "done": True})
        return recording_summary(rec.id, report)
    except Exception as e:  # noqa: BLE001 - every failure becomes the recording's one-line reason
        # The staging folder's random name would make the reason differ from run to run.
        reason = _one_line(str(e).replace(stage, final) if stage else str(e)) or type(e).__name__
        raise RecordingFailed(reason) from None
    finally:
        if stage:
            shutil.rmtree(stage, ignore_errors=True)


# --------------------------------------------------------------------------------------------
# The batch


@dataclasses.dataclass
class BatchResult:
    """What a batch did: the summary written to summary.json, and where."""

    summary: dict[str, Any]
    summary_json: str
    summary_md: str

    @property
    def failed(self) -> list[str]:
        return [r["id"] for r in self.summary["recordings"] if r["status"] == "failed"]


@dataclasses.dataclass
class BatchProgress:
    """The state of a batch, as the progress callback sees it."""

    total: int
    done: int = 0
    running: int = 0
    failed: int = 0
    skipped: int = 0
    frames_done: int = 0
    frames_per_second: float = 0.0
    eta_s: float | None = None
    dashboard: str = ""


def _dashboard(client: Any) -> str:
    try:
        return str(client.dashboard_link or "")
    except Exception:  # noqa: BLE001 - no dashboard (bokeh missing, or a remote scheduler without one)
        return ""


def _reason(future: Any) -> str:
    try:
        e = future.exception()
    except Exception as ex:  # noqa: BLE001
        e = ex
    if isinstance(e, RecordingFailed):
        return str(e)
    name = type(e).__name__
    if name == "KilledWorker":
        return ("the worker running it was lost (killed, out of memory, or its machine went away) as often as the "
                "scheduler allows (allowed-failures)")
    return _one_line(f"{name}: {e}") if str(e) else name


def summarize(records: list[dict[str, Any]], elapsed_s: float, workers: int) -> dict[str, Any]:
    """summary.json's content from the recordings' lines."""
    done = [r for r in records if r["status"] == "done"]
    totals = {k: sum(r.get(k, 0) for r in done) for k in ("frames_total", "clear", "within_margin", "colliding",
                                                          "no_state", "unsafe")}
    look = [r["id"] for r in records if r["status"] == "failed" or r.get("colliding", 0) or r.get("unsafe", 0)]
    ran = sum(r.get("frames_total", 0) for r in done if not r.get("skipped"))
    return {
        "kccd_batch": 1,
        "kccd_version": _core.__version__,
        "recordings": records,
        "totals": {"recordings": len(records), "done": len(done), "failed": len(records) - len(done), **totals},
        "needs_look": look,
        "run": {"workers": workers, "elapsed_s": round(elapsed_s, 3),
                "frames_per_second": round(ran / elapsed_s, 2) if elapsed_s > 0 else 0.0},
    }


def _clock(t: float) -> str:
    m, s = divmod(max(t, 0.0), 60.0)
    return f"{int(m)}:{s:06.3f}"


def summary_markdown(summary: dict[str, Any]) -> str:
    """summary.md: the fleet's totals, what needs a person's look (with each one's contact sheet),
    per recording its frame counts and colliding intervals, and the failures."""
    t = summary["totals"]
    lines = ["# KCCD batch overlay", "",
             f"{t['recordings']} recordings: {t['done']} done, {t['failed']} failed. Frames: {t['frames_total']} "
             f"({t['clear']} clear, {t['within_margin']} within the margin, {t['colliding']} colliding, "
             f"{t['no_state']} without a state, {t['unsafe']} unsafe).", ""]
    by_id = {r["id"]: r for r in summary["recordings"]}
    if summary["needs_look"]:
        lines += ["## Needs a person's look", ""]
        sheet = summary.get("colliding_frames", {})
        if sheet.get("file"):
            lines += [f"The middle frame of each colliding interval ({len(sheet['frames'])} frames):", "",
                      f"![colliding frames]({sheet['file']})", ""]
        elif sheet.get("problem"):
            lines += [f"(No sheet of colliding frames: {sheet['problem']})", ""]
        for rid in summary["needs_look"]:
            r = by_id[rid]
            if r["status"] == "failed":
                lines += [f"- **{rid}**: failed: {r['reason']}"]
                continue
            spans = ", ".join(f"{_clock(c['start_s'])}–{_clock(c['end_s'])} (frames {c['first_frame']}–"
                              f"{c['last_frame']})" for c in r["colliding_intervals"]) or "none"
            lines += [f"- **{rid}**: {r['colliding']} colliding frames, {r['unsafe']} unsafe; colliding: {spans}",
                      "", f"  ![{rid}]({rid}/contact_sheet.png)", ""]
        lines += [""]
    else:
        lines += ["Nothing needs a look: no recording failed and no frame collides.", ""]
    lines += ["## Recordings", "",
              "| id | status | frames | clear | within margin | colliding | no state | colliding intervals (video time) "
              "| within-margin intervals |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in summary["recordings"]:
        if r["status"] == "failed":
            lines += [f"| {r['id']} | failed | | | | | | {r['reason'].replace('|', '/')} | |"]
            continue
        spans, margin = ("; ".join(f"{_clock(c['start_s'])}–{_clock(c['end_s'])}" for c in r.get(key, []))
                         for key in ("colliding_intervals", "margin_intervals"))
        lines += [f"| [{r['id']}]({r['id']}/report.json) | done{' (kept)' if r.get('skipped') else ''} | "
                  f"{r['frames_total']} | {r['clear']} | {r['within_margin']} | {r['colliding']} | {r['no_state']} | "
                  f"{spans or '–'} | {margin or '–'} |"]
    run = summary["run"]
    lines += ["", f"Run: {run['workers']} workers, {run['elapsed_s']:.1f} s, {run['frames_per_second']:.1f} frames/s "
              f"over the cluster; kccd {summary['kccd_version']}.", ""]
    return "\n".join(lines)


_LEFTOVER = re.compile(rf"\.({_ID.pattern})\.(partial-[A-Za-z0-9_]{{8}}|old-[0-9a-f]{{32}})")


def _stale(out_dir: str) -> None:
    """Removes the staging folders a killed run left (.<id>.partial-XXXXXXXX, .<id>.old-<hex>; the
    caller holds the folder's lock, so no other run is writing them)."""
    try:
        names = os.listdir(out_dir)
    except OSError:
        return
    for n in names:
        if _LEFTOVER.fullmatch(n):
            shutil.rmtree(os.path.join(out_dir, n), ignore_errors=True)


def run_batch(
    manifest: str,
    out_dir: str,
    *,
    client: Any = None,
    scheduler: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    only: str | None = None,
    jobs: int = 0,
    contact_frames: int = 12,
    progress: Callable[[BatchProgress], None] | None = None,
) -> BatchResult:
    """Runs the overlay of every recording of `manifest` (those whose id matches the glob `only`)
    into `out_dir`: on `client` when given, else on the scheduler at `scheduler`
    (tcp://HOST:PORT), else on a local cluster of `workers` processes (None: one per core, at most
    one per recording to run). `jobs`: drawing threads per
    recording (0: the worker machine's cores divided among its workers). `resume`: recordings whose
    outputs are complete (is_complete) are kept, not run again. Raises ManifestError before
    anything starts; a failing recording is retried once, then reported in the summary."""
    recordings = read_manifest(manifest)
    if only is not None:
        recordings = [r for r in recordings if fnmatch.fnmatchcase(r.id, only)]
        if not recordings:
            raise ManifestError(f"{manifest}: --only {only}: no recording id matches")
    if workers is not None and workers < 1:
        raise ValueError("workers: must be >= 1")
    if not 1 <= contact_frames <= 64:
        raise ValueError("contact_frames: must be 1 ... 64")
    try:
        os.makedirs(out_dir, exist_ok=True)
        lock = open(os.path.join(out_dir, _LOCK), "a")  # noqa: SIM115 - held until the end of the run
    except OSError as e:
        raise BatchError(f"{out_dir}: cannot write there ({e.strerror or e})") from None
    try:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise BatchError(f"{out_dir}: another kccd.batch run is writing there (it holds {_LOCK})") from None
        return _locked_batch(recordings, os.path.abspath(out_dir), client, scheduler, workers, resume, jobs,
                             contact_frames, progress)
    finally:
        lock.close()


def _locked_batch(recordings: list[Recording], out_dir: str, client: Any, scheduler: str | None, workers: int | None,
                  resume: bool, jobs: int, contact_frames: int,
                  progress: Callable[[BatchProgress], None] | None) -> BatchResult:
    _stale(out_dir)
    t0 = time.monotonic()
    records: dict[str, dict[str, Any]] = {}
    for r in recordings:
        line = complete_summary(r, out_dir, contact_frames) if resume else None
        if line is not None:
            records[r.id] = line
    todo = [r for r in recordings if r.id not in records]

    state = BatchProgress(total=len(recordings), done=len(records), skipped=len(records))
    own_cluster = None
    own_client = False
    if workers is None:
        workers = max(1, min(os.cpu_count() or 1, len(todo)))
    n_workers = workers
    if todo:
        import dask
        import distributed

        dist: Any = distributed  # untyped: its calls are not checked
        if client is None:
            own_client = True
            if scheduler:
                try:
                    client = dist.Client(scheduler, timeout=30)
                except Exception as e:  # noqa: BLE001 - a bad address, a refused or timed-out connection
                    raise BatchError(f"--scheduler {scheduler}: cannot connect ({_one_line(str(e)) or type(e).__name__})") \
                        from None
            else:
                # A worker lost while running a task: its task runs once more, then fails. Workers
                # without Dask's MALLOC_TRIM_THRESHOLD_: trimming the heap after every frame's
                # buffers costs 10 % of the overlay's time (measured: 4.92 against 4.45 s).
                with dask.config.set({"distributed.scheduler.allowed-failures": 1,
                                      "distributed.nanny.pre-spawn-environ": _WORKER_ENVIRON}):
                    own_cluster = dist.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                    dashboard_address=":0", silence_logs=logging.ERROR)
                client = dist.Client(own_cluster)
        pending: set[Any] = set()
        try:
            info = client.scheduler_info().get("workers", {})
            n_workers = max(1, len(info))
            slots = sum(int(w.get("nthreads", 1)) for w in info.values()) or n_workers
            state.dashboard = _dashboard(client)
            per_job = jobs
            if per_job <= 0:
                per_job = max(1, (os.cpu_count() or 1) // max(1, n_workers)) if own_cluster is not None else 0
            run = uuid.uuid4().hex
            futures = {client.submit(run_recording, r, out_dir, per_job, contact_frames, run, pure=False, retries=1,
                                     key=f"kccd-overlay-{r.id}-{run[:8]}"): r for r in todo}
            frames: dict[str, tuple[int, int]] = {}  # per recording running or done: frames done, expected
            failed: set[str] = set()
            seen_until = 0.0
            pending = set(futures)
            last_report = 0.0
            while pending:
                time.sleep(0.25)
                for fut in [x for x in pending if x.done()]:
                    pending.discard(fut)
                    r = futures[fut]
                    if fut.status == "finished":
                        records[r.id] = fut.result()
                        state.done += 1
                        frames[r.id] = (records[r.id]["frames_total"], records[r.id]["frames_total"])
                    else:
                        records[r.id] = {"id": r.id, "status": "failed", "reason": _reason(fut), "frames_total": 0,
                                         "clear": 0, "within_margin": 0, "colliding": 0, "no_state": 0,
                                         "unsafe": 0, "colliding_intervals": [], "margin_intervals": []}
                        state.failed += 1
                        failed.add(r.id)
                        frames.pop(r.id, None)
                try:
                    events = client.get_events(_TOPIC)
                except Exception:  # noqa: BLE001 - progress is best effort
                    events = ()
                for stamp, msg in events:
                    if stamp <= seen_until or not isinstance(msg, dict) or msg.get("run") != run:
                        continue
                    seen_until = max(seen_until, stamp)
                    if msg.get("id") not in records:
                        frames[msg["id"]] = (int(msg["frames_done"]), int(msg["frames_expected"]))
                now = time.monotonic()
                if progress is not None and (now - last_report >= 1.0 or not pending):
                    last_report = now
                    processing = client.processing()
                    assigned = sum(1 for keys in processing.values() for k in keys if str(k).startswith("kccd-overlay-"))
                    state.running = min(assigned, slots)
                    state.frames_done = sum(d for d, _ in frames.values())
                    elapsed = now - t0
                    state.frames_per_second = state.frames_done / elapsed if elapsed > 0 else 0.0
                    known = [e for _, e in frames.values() if e > 0]
                    mean = sum(known) / len(known) if known else 0.0
                    not_started = len(todo) - len(set(frames) | failed)
                    remaining = sum(max(e - d, 0) for d, e in frames.values()) + mean * max(0, not_started)
                    state.eta_s = remaining / state.frames_per_second if state.frames_per_second > 0 and known else None
                    progress(dataclasses.replace(state))
        finally:
            if pending:  # interrupted: nothing of this run keeps running on the cluster
                try:
                    client.cancel(list(pending))
                except Exception:  # noqa: BLE001
                    pass
            if own_client:
                client.close()
            if own_cluster is not None:
                own_cluster.close()
    _stale(out_dir)
    ordered = [records[r.id] for r in recordings]
    summary = summarize(ordered, time.monotonic() - t0, n_workers)
    summary["colliding_frames"] = colliding_sheet(summary, out_dir)
    js = os.path.join(out_dir, "summary.json")
    md = os.path.join(out_dir, "summary.md")
    _write_json(js, summary)
    _write_text(md, summary_markdown(summary))
    return BatchResult(summary, js, md)


def colliding_sheet(summary: dict[str, Any], out_dir: str, per_recording: int = 4, most: int = 24) -> dict[str, Any]:
    """DIR/colliding_frames.png: the middle frame of each colliding interval (at most `per_recording`
    per recording, `most` in all) of the recordings that collide, from their overlay videos, each
    captioned with its recording, frame and time. Returns what summary.json says of it."""
    picks: list[tuple[str, int, float]] = []
    for r in summary["recordings"]:
        if r["status"] != "done":
            continue
        for c in r["colliding_intervals"][:per_recording]:
            mid = (c["first_frame"] + c["last_frame"]) // 2
            t = c["start_s"] + (c["end_s"] - c["start_s"]) * (mid - c["first_frame"]) / max(1, c["last_frame"] - c["first_frame"])
            picks.append((r["id"], mid, t))
    picks = picks[:most]
    path = os.path.join(out_dir, "colliding_frames.png")
    if not picks:
        if os.path.exists(path):
            os.remove(path)
        return {"file": None, "frames": []}
    images, captions = [], []
    try:
        by_id: dict[str, list[tuple[int, float]]] = {}
        for rid, idx, t in picks:
            by_id.setdefault(rid, []).append((idx, t))
        for rid, frames in by_id.items():
            got = _core.read_frames(os.path.join(out_dir, rid, "overlay.mp4"), [i for i, _ in frames])
            images += got
            captions += [f"{rid} #{i} {t:.2f} s" for i, t in frames]
        _core.contact_sheet(images, captions, path)
    except (_core.InputError, OSError) as e:
        return {"file": None, "frames": [], "problem": _one_line(str(e))}
    return {"file": "colliding_frames.png", "frames": [{"id": rid, "frame": i} for rid, i, _ in picks]}


# --------------------------------------------------------------------------------------------
# The command


def _terminal(stream: Any) -> Callable[[BatchProgress], None]:
    tty = stream.isatty()
    printed = [0.0]

    def show(p: BatchProgress) -> None:
        eta = f", ETA {p.eta_s / 60:.1f} min" if p.eta_s is not None else ""
        line = (f"recordings {p.done}/{p.total} done, {p.running} running, {p.failed} failed"
                f"{f' ({p.skipped} kept)' if p.skipped else ''}; {p.frames_done} frames, "
                f"{p.frames_per_second:.1f} frames/s over the cluster{eta}")
        if tty:
            stream.write("\r" + line.ljust(110))
            stream.flush()
        elif time.monotonic() - printed[0] >= 10.0:
            printed[0] = time.monotonic()
            stream.write(line + "\n")
            stream.flush()

    return show


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python3 -m kccd.batch",
        description="Overlay many recordings (kccd overlay on each) on a Dask cluster and sum them up. Each "
                    "recording's outputs go to DIR/<id>/ (overlay.mp4, report.json as kccd overlay --report, "
                    "contact_sheet.png, inputs.json), renamed into place only when complete; DIR/summary.json and "
                    "DIR/summary.md sum the fleet up. Inputs are read from paths every worker sees.",
        epilog="Exit status: 0 every recording done, 1 some failed (retried once; see summary.md), 2 bad manifest "
               "or options (nothing started).")
    parser.add_argument("manifest", help="batch manifest (YAML, kccd_batch: 1; paths relative to it)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                       help="a running Dask scheduler (dask-scheduler; workers started with dask-worker)")
    where.add_argument("--workers", type=int, default=None, metavar="N",
                       help="local cluster of N worker processes (default: one per core, at most one per "
                            "recording; each draws with --jobs threads, one GL context each)")
    parser.add_argument("--resume", action="store_true",
                        help="keep recordings whose outputs are complete (same inputs, options and kccd version)")
    parser.add_argument("--only", metavar="GLOB", help="only the recordings whose id matches (fnmatch: cell3-*)")
    parser.add_argument("--jobs", type=int, default=0, metavar="N",
                        help="drawing threads per recording (default: the local cores divided among the workers; "
                             "on a remote scheduler each worker's cores)")
    parser.add_argument("--contact-frames", type=int, default=12, metavar="N",
                        help="frames per recording's contact sheet (1 ... 64, default 12)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress, only the last line and errors")
    args = parser.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        parser.error("--workers: must be >= 1")
    if args.jobs < 0:
        parser.error("--jobs: must be >= 0")
    if not 1 <= args.contact_frames <= 64:
        parser.error("--contact-frames: must be 1 ... 64")
    show = None if args.quiet else _terminal(sys.stderr)
    announced = [False]

    def relay(p: BatchProgress) -> None:
        if not announced[0] and not args.quiet:
            announced[0] = True
            if p.dashboard:
                sys.stderr.write(f"Dask dashboard: {p.dashboard}\n")
        if show is not None:
            show(p)

    try:
        result = run_batch(args.manifest, args.out, scheduler=args.scheduler, workers=args.workers,
                           resume=args.resume, only=args.only, jobs=args.jobs, contact_frames=args.contact_frames,
                           progress=relay)
    except (ManifestError, BatchError) as e:
        sys.stderr.write(f"kccd.batch: {e}\n")
        return 2
    except OSError as e:  # the output folder (writing the summary), or the cluster's own files
        place = f"{e.filename}: " if e.filename else ""
        sys.stderr.write(f"kccd.batch: {place}{e.strerror or _one_line(str(e))}\n")
        return 2
    if show is not None and sys.stderr.isatty():
        sys.stderr.write("\n")
    t = result.summary["totals"]
    for r in result.summary["recordings"]:
        if r["status"] == "failed":
            sys.stderr.write(f"kccd.batch: {r['id']}: failed: {r['reason']}\n")
    print(f"{t['done']} of {t['recordings']} recordings done, {t['failed']} failed; {t['colliding']} colliding frames; "
          f"{len(result.summary['needs_look'])} recordings need a look: {result.summary_md}")
    return 1 if t["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
