"""Conservativeness from Python with an oracle of its own (no library code): the demo arm's forward
kinematics from the YAML file, sphere swept convex hull distances by Frank-Wolfe on the Minkowski
difference (every iterate is a point of it, so the oracle is never below the true distance), at
the corners and at random configurations of random boxes. Every bound must lie at or below it."""

import numpy as np
import yaml

import kccd
from conftest import DATA


def rot(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices (S, 3, 3) about a unit axis by angles (S,) (Rodrigues)."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def rpy(r: float, p: float, y: float) -> np.ndarray:
    one = np.array([1.0])
    return (rot(np.array([0, 0, 1.0]), y * one) @ rot(np.array([0, 1.0, 0]), p * one) @ rot(np.array([1.0, 0, 0]), r * one))[0]


def frames(doc: dict, q: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """World pose (R (S,3,3), t (S,3)) of every joint frame for configurations q (S, n)."""
    s = q.shape[0]
    out = {"world": (np.broadcast_to(np.eye(3), (s, 3, 3)), np.zeros((s, 3)))}
    for i, j in enumerate(doc["joints"]):
        o = j.get("origin", {})
        ro, to = rpy(*o.get("rpy", [0, 0, 0])), np.array(o.get("xyz", [0, 0, 0]), float)
        pr, pt = out[j["parent"]]
        r0, t0 = pr @ ro, pt + np.einsum("sij,j->si", pr, to)
        axis = np.array(j.get("axis", [0, 0, 1]), float)
        assert j["type"] == "revolute"
        out[j["name"]] = (r0 @ rot(axis / np.linalg.norm(axis), q[:, i]), t0)
    return out


def hull_distance(a: np.ndarray, b: np.ndarray, iters: int = 400) -> np.ndarray:
    """Distance between the hulls of point sets a (S, na, 3) and b (S, nb, 3): Frank-Wolfe with
    exact line search on the Minkowski difference, from its best vertex; >= the true distance. A
    sample stops once its duality gap x.(x - v) is at most 5e-19: |x|^2 - d^2 <= 2 gap, so |x| is
    then within 1e-9 of the distance d (the others go on, up to `iters` steps)."""
    d = (a[:, :, None, :] - b[:, None, :, :]).reshape(a.shape[0], -1, 3)
    x = d[np.arange(d.shape[0]), np.argmin((d * d).sum(-1), axis=1)]
    live = np.arange(d.shape[0])
    for _ in range(iters):
        dl, xl = d[live], x[live]
        v = dl[np.arange(len(live)), np.argmin(np.einsum("skj,sj->sk", dl, xl), axis=1)]
        step = xl - v
        gap = (xl * step).sum(-1)
        den = (step * step).sum(-1)
        t = np.clip(np.where(den > 0, gap / np.maximum(den, 1e-300), 0.0), 0.0, 1.0)
        x[live] = xl - t[:, None] * step
        live = live[gap > 5e-19]
        if len(live) == 0:
            break
    return np.linalg.norm(x, axis=1)


def test_bounds_below_an_independent_oracle(arm: kccd.Model) -> None:
    doc = yaml.safe_load((DATA / "demo_arm.yaml").read_text())
    bodies = {b["name"]: b for b in doc["bodies"]}
    rng = np.random.default_rng(2026)
    checker = kccd.Checker(arm)
    limits = np.array([j["limits"] for j in doc["joints"]], float)
    checked = 0
    for box in range(40):
        centre = rng.uniform(limits[:, 0], limits[:, 1])
        half = rng.uniform(0.0, [0.2, 0.2, 0.2] if box % 2 else [0.02, 0.02, 0.02])
        lower, upper = centre - half, centre + half
        r = checker.query(lower, upper, type="distances", exact="all" if box % 3 == 0 else None)
        assert r.status == kccd.Status.OK
        corners = np.array([[(lower, upper)[(c >> k) & 1][k] for k in range(3)] for c in range(8)])
        q = np.vstack([corners, rng.uniform(lower, upper, (400, 3))])
        f = frames(doc, q)
        for k in range(len(r)):
            ba, bb = bodies[arm.bodies[r.body_a[k]]], bodies[arm.bodies[r.body_b[k]]]
            pts = []
            for b in (ba, bb):
                rm, t = f[b["frame"]]
                pts.append(np.einsum("sij,pj->spi", rm, np.array(b["points"], float)) + t[:, None, :])
            true = np.maximum(hull_distance(pts[0], pts[1]) - ba["radius"] - bb["radius"], 0.0)
            assert r.distance[k] <= true.min() + 1e-9, (box, arm.bodies[r.body_a[k]], arm.bodies[r.body_b[k]])
            checked += 1
    assert checked == 40 * len(arm.pairs)
