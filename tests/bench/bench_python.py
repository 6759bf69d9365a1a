"""The Python package's costs against the C++ library, measured in one run on the same boxes.

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/bench_python.py [--boxes 10000] [--repeats 5]

- query_many over M random humanoid boxes (threads=1) against bench_query_loop, the same loop in
  C++ (both reset the table per box), and threads=2 against threads=1;
- the overhead of one Checker.query call: a Python loop of query() on one repeated box (answered
  from the carried table, so the query itself is cheap) against query_many(reuse=True) of the same
  box repeated, per call.
Best of --repeats runs each; prints a Markdown table.
"""

import argparse
import pathlib
import subprocess
import tempfile
import time

import numpy as np

import kccd

ROOT = pathlib.Path(__file__).resolve().parents[2]


def best(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--boxes", type=int, default=10000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--build", default=str(ROOT / "build"))
    a = ap.parse_args()
    model_path = ROOT / "data" / "humanoid.yaml"
    model = kccd.Model.load(str(model_path))
    rng = np.random.default_rng(1)
    centre = rng.uniform(-1.0, 1.0, (a.boxes, model.state_size))
    half = rng.uniform(0.0, 0.05, (a.boxes, model.state_size))
    lowers, uppers = centre - half, centre + half
    checker = kccd.Checker(model)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        csv = pathlib.Path(tmp) / "boxes.csv"
        np.savetxt(csv, np.hstack([lowers, uppers]), delimiter=",", fmt="%.17g")
        for qtype in ("collision", "distances"):
            cpp = float(subprocess.run([str(pathlib.Path(a.build) / "tests/bench/bench_query_loop"), str(model_path),
                                        str(csv), qtype, str(a.repeats)], check=True, capture_output=True,
                                       text=True).stdout)
            one = best(lambda: checker.query_many(lowers, uppers, type=qtype), a.repeats) / a.boxes * 1e6
            two = best(lambda: checker.query_many(lowers, uppers, type=qtype, threads=2), a.repeats) / a.boxes * 1e6
            rows.append((qtype, cpp, one, two))
    box_lo, box_hi = lowers[0], uppers[0]
    calls = 20000
    tiled_lo, tiled_hi = np.tile(box_lo, (calls, 1)), np.tile(box_hi, (calls, 1))
    checker.query(box_lo, box_hi)

    def loop() -> None:
        for _ in range(calls):
            checker.query(box_lo, box_hi)

    py_call = best(loop, a.repeats) / calls * 1e6
    cpp_call = best(lambda: checker.query_many(tiled_lo, tiled_hi, reuse=True), a.repeats) / calls * 1e6
    print(f"humanoid ({model.state_size} state values, {len(model.pairs)} pairs), {a.boxes} boxes, best of {a.repeats}\n")
    print("| query | C++ loop µs/box | query_many µs/box | / C++ | threads=2 µs/box | speed-up 2 threads |")
    print("|---|---|---|---|---|---|")
    for qtype, cpp, one, two in rows:
        print(f"| {qtype} | {cpp:.2f} | {one:.2f} | {one / cpp:.3f} | {two:.2f} | {one / two:.2f} |")
    print(f"\nOne query() call from Python: {py_call:.2f} µs against {cpp_call:.2f} µs per query in query_many "
          f"(the same carried-over box): overhead {py_call - cpp_call:.2f} µs per call.")


if __name__ == "__main__":
    main()
