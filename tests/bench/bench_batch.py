"""kccd.batch against the plain command, measured in one run on the same recordings.

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/bench_batch.py [--recordings 4] [--seconds 6]

Makes --recordings synthetic recordings of the demo arm (kccd.synthesize_recording, 1280x720 at 25
fps), then runs, one after the other:
- `kccd overlay` on each recording in turn (the baseline: the command as a user runs it, all cores);
- `python3 -m kccd.batch` on a manifest of them with --workers 1 and with --workers 2 (a local
  Dask cluster; the wall time includes starting Python and the cluster).
Prints a Markdown table: wall time, frames per second, the ratio to the baseline, and the batch's
overhead per recording ((batch wall - baseline wall) / recordings).
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import kccd

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--recordings", type=int, default=4)
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--cli", default=str(pathlib.Path(kccd.__file__).resolve().parents[2] / "overlay" / "kccd"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        model = str(ROOT / "data" / "demo_arm.yaml")
        frames = 0
        lines = ["kccd_batch: 1", f"defaults: {{model: {model}, camera: r0/camera_true.yaml, time_offset: 0.137}}",
                 "recordings:"]
        for i in range(a.recordings):
            s = kccd.synthesize_recording(model, str(root / f"r{i}"), seconds=a.seconds, seed=i + 1)
            frames += s["frames"]
            lines.append(f"  - {{id: r{i}, video: r{i}/video.mkv, states: r{i}/states.csv}}")
        (root / "m.yaml").write_text("\n".join(lines) + "\n")

        t0 = time.perf_counter()
        for i in range(a.recordings):
            subprocess.run([a.cli, "overlay", model, "--camera", str(root / "r0" / "camera_true.yaml"), "--video",
                            str(root / f"r{i}" / "video.mkv"), "--states", str(root / f"r{i}" / "states.csv"),
                            "--time-offset", "0.137", "-o", str(root / f"plain{i}.mp4"), "--report",
                            str(root / f"plain{i}.json"), "--contact-sheet", str(root / f"plain{i}.png"), "--quiet"],
                           check=True)
        plain = time.perf_counter() - t0
        rows = [("`kccd overlay`, one after the other", plain, None)]
        for workers in (1, 2):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "kccd.batch", str(root / "m.yaml"), "--out", str(root / f"b{workers}"),
                            "--workers", str(workers), "--quiet"], check=True, env=os.environ, stdout=subprocess.DEVNULL)
            wall = time.perf_counter() - t0
            run = json.loads((root / f"b{workers}" / "summary.json").read_text())["run"]
            rows.append((f"`kccd.batch --workers {workers}`", wall, run["elapsed_s"]))
    print(f"{a.recordings} recordings, {frames} frames of 1280x720, {os.cpu_count()} cores\n")
    print("| run | wall s | frames/s | / plain | overhead per recording s | inside the batch s |")
    print("|---|---|---|---|---|---|")
    for name, wall, inside in rows:
        over = (wall - plain) / a.recordings
        print(f"| {name} | {wall:.2f} | {frames / wall:.1f} | {plain / wall:.2f}x | "
              f"{'' if inside is None else f'{over:+.2f}'} | {'' if inside is None else f'{inside:.2f}'} |")


if __name__ == "__main__":
    main()
