"""kccd.Checker: answers equal to `kccd query --json`, fresh arrays, argument checks naming the
argument, query_many against a loop of queries, threads, and misuse from two threads."""

import json
import subprocess
import threading
import time

import numpy as np
import pytest

import kccd
from conftest import DATA


def random_boxes(model: kccd.Model, count: int, seed: int, width: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-1.5, 1.5, (count, model.state_size))
    half = rng.uniform(0.0, width, (count, model.state_size))
    return centre - half, centre + half


@pytest.mark.parametrize("qtype", ["collision", "closest", "nclosest", "distances"])
def test_equals_cli_json(cli, arm: kccd.Model, qtype: str) -> None:
    lower, upper = [0.1, -0.4, 0.6], [0.3, -0.2, 0.9]
    args = [str(cli), "query", str(DATA / "demo_arm.yaml"), "--json", "--type", qtype, "--n", "3",
            "--lower", ",".join(map(repr, lower)), "--upper", ",".join(map(repr, upper))]
    j = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    r = kccd.Checker(arm).query(lower, upper, type=qtype, n=3)
    assert r.status == kccd.Status.OK and j["status"] == "ok"
    assert r.collision == j["collision"] and r.margin == j["margin"]
    assert r.min_distance == j["min_distance"]
    assert len(r) == len(j["pairs"])
    for k, p in enumerate(j["pairs"]):
        assert (arm.bodies[r.body_a[k]], arm.bodies[r.body_b[k]]) == (p["a"], p["b"])
        assert r.distance[k] == p["distance"]
        if "witness_a" in p:
            assert list(r.witness_a[k]) == p["witness_a"] and list(r.witness_b[k]) == p["witness_b"]
        else:
            assert not r.has_witness[k] and np.isnan(r.witness_a[k]).all()


def test_result_arrays_are_fresh_and_typed(humanoid: kccd.Model) -> None:
    c = kccd.Checker(humanoid)
    lo, hi = random_boxes(humanoid, 2, 1)
    a = c.query(lo[0], hi[0], type="distances")
    kept = a.distance.copy()
    c.query(lo[1], hi[1], type="distances")
    assert np.array_equal(a.distance, kept)  # not a view of the checker's buffers
    assert a.body_a.dtype == np.int32 and a.distance.dtype == np.float64
    assert a.witness_a.shape == (len(a), 3) and a.witness_a.flags["C_CONTIGUOUS"]
    assert len(a) == len(humanoid.pairs)
    assert set(a.stats) >= {"time_us", "pairs_checked", "gjk_calls", "budget_exhausted"}


def test_bad_arguments_name_the_argument(arm: kccd.Model) -> None:
    c = kccd.Checker(arm)
    with pytest.raises(ValueError, match=r"lower: expected shape \(3,\)"):
        c.query([0.0, 0.0])
    with pytest.raises(ValueError, match="upper"):
        c.query([0.0] * 3, np.zeros((3, 1)))
    with pytest.raises(TypeError, match="lower"):
        c.query(["a", "b", "c"])
    with pytest.raises(TypeError, match="lower"):
        c.query(np.zeros(3, dtype=complex))
    with pytest.raises(ValueError, match="type"):
        c.query([0.0] * 3, type="nearest")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="exact"):
        c.query([0.0] * 3, exact="some")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="margin"):
        c.query([0.0] * 3, margin=-1.0)
    with pytest.raises(ValueError, match="lowers"):
        c.query_many(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="uppers"):
        c.query_many(np.zeros((4, 3)), np.zeros((5, 3)))


def test_unsafe_input_is_a_status_not_an_exception(arm: kccd.Model) -> None:
    c = kccd.Checker(arm)
    r = c.query([0.0, float("nan"), 0.0])
    assert r.status == kccd.Status.NON_FINITE_STATE and r.collision
    r = c.query([0.5, 0.0, 0.0], [0.4, 0.0, 0.0])
    assert r.status == kccd.Status.LOWER_ABOVE_UPPER and r.collision
    m = c.query_many(np.array([[0.0, np.inf, 0.0], [0.1, 0.2, 0.3]]))
    assert list(m["status"]) == [kccd.Status.NON_FINITE_STATE, kccd.Status.OK]
    assert m["collision"][0]


@pytest.mark.parametrize("qtype", ["collision", "distances"])
def test_query_many_equals_a_loop_and_threads_agree(humanoid: kccd.Model, qtype: str) -> None:
    lo, hi = random_boxes(humanoid, 60, 7)
    c = kccd.Checker(humanoid)
    many = c.query_many(lo, hi, type=qtype)
    two = c.query_many(lo, hi, type=qtype, threads=2)
    for i in range(len(lo)):
        c.reset()
        r = c.query(lo[i], hi[i], type=qtype)
        assert many["status"][i] == r.status and many["collision"][i] == r.collision
        assert many["min_distance"][i] == r.min_distance
    for key in ("status", "collision", "min_distance"):
        assert np.array_equal(many[key], two[key])


def test_two_threads_on_one_checker_raise(humanoid: kccd.Model) -> None:
    c = kccd.Checker(humanoid)
    lo, hi = random_boxes(humanoid, 4000, 3)
    errors: list[BaseException] = []

    def long_run() -> None:
        try:
            c.query_many(lo, hi, type="distances")
        except BaseException as e:  # noqa: BLE001 - recorded for the assertion
            errors.append(e)

    t = threading.Thread(target=long_run)
    t.start()
    time.sleep(0.05)
    with pytest.raises(RuntimeError, match="two threads"):
        for _ in range(200):  # until the other thread's call is seen running
            c.query(lo[0], hi[0])
            time.sleep(0.001)
    t.join()
    assert not errors
    # Afterwards the checker works again.
    assert c.query(lo[0], hi[0]).status == kccd.Status.OK


def test_budget_and_braking(arm: kccd.Model) -> None:
    c = kccd.Checker(arm, budget_us=1e6)
    assert c.budget_us == 1e6 and c.model is not None
    with pytest.raises(ValueError, match="budget_us"):
        kccd.Checker(arm, budget_us=-1.0)
    p = kccd.BrakingParams(latency=0.01, deceleration=5.0)
    lower, upper = kccd.braking_intervals(arm, [0.0, 0.5, 2.4], [1.0, -1.0, 2.0], p)
    # Moving up at 1 rad/s: S = 0.01 + 1 / 10 ahead; moving down: the same behind; clamped to the limit.
    assert lower[0] == pytest.approx(0.0) and upper[0] == pytest.approx(0.11)
    assert lower[1] == pytest.approx(0.39) and upper[1] == pytest.approx(0.5)
    assert upper[2] == pytest.approx(2.5)
    with pytest.raises(ValueError, match="params"):
        kccd.braking_intervals(arm, [0.0] * 3, [0.0] * 3, [p, p])
