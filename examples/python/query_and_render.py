"""KCCD from Python: load a model, query a braking box, render the swept volumes and plot them.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/query_and_render.py [OUT.png]
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import kccd  # noqa: E402

DATA = pathlib.Path(__file__).resolve().parents[2] / "data"


def main(out: str) -> None:
    model = kccd.Model.load(str(DATA / "demo_arm.yaml"))
    camera = kccd.Camera.load(str(DATA / "demo_camera.yaml"))
    # Where the arm can stop if it brakes now (positions rad, velocities rad/s, state order).
    q = np.array([0.3, -0.5, 0.9])
    v = np.array([0.8, -0.4, 1.2])
    lower, upper = kccd.braking_intervals(model, q, v, kccd.BrakingParams(latency=0.01, deceleration=5.0))
    checker = kccd.Checker(model)
    r = checker.query(lower, upper, type="distances")
    if r.status != kccd.Status.OK:
        raise SystemExit(f"unsafe query status {r.status.name}: stop")
    print(f"{'collision' if r.collision else 'clear'}: min distance {r.min_distance:.4f} m (margin {r.margin} m)")
    for k in np.argsort(r.distance)[:3]:
        print(f"  {model.bodies[r.body_a[k]]:>10} - {model.bodies[r.body_b[k]]:<10} {r.distance[k]:.4f} m")
    image = kccd.render(model, camera, lower=lower, upper=upper)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.imshow(image["rgba"])
    ax.set_title(f"demo arm swept over its braking box: min distance {r.min_distance * 1000:.1f} mm")
    ax.axis("off")
    fig.savefig(out, dpi=100, bbox_inches="tight")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "kccd_example.png")
