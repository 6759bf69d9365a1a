"""kccd.Model: loading, names, pickling, and errors that point at the file, line and field."""

import multiprocessing
import pickle

import pytest

import kccd
from conftest import DATA


def test_load_gives_names_in_state_order(arm: kccd.Model) -> None:
    assert arm.name == "demo_arm"
    assert arm.state_names == ["shoulder_yaw", "shoulder_pitch", "elbow"]
    assert arm.state_size == 3
    assert arm.joints == ["shoulder_yaw", "shoulder_pitch", "elbow"]
    assert arm.bodies[:3] == ["pedestal", "table", "post"]
    assert arm.margin == pytest.approx(0.02)
    assert len(arm.pairs) == 13 and all(a in arm.bodies and b in arm.bodies for a, b in arm.pairs)
    assert arm.source.endswith("demo_arm.yaml")
    assert "kccd: 1" in arm.yaml


def test_from_yaml_equals_load(arm: kccd.Model) -> None:
    m = kccd.Model.from_yaml(arm.yaml, "copy.yaml")
    assert (m.state_names, m.bodies, m.pairs, m.margin) == (arm.state_names, arm.bodies, arm.pairs, arm.margin)
    assert m.source == "copy.yaml"


def test_pickle_round_trip(humanoid: kccd.Model) -> None:
    m = pickle.loads(pickle.dumps(humanoid))
    assert (m.state_names, m.pairs, m.yaml, m.source) == (humanoid.state_names, humanoid.pairs, humanoid.yaml, humanoid.source)
    # The copy answers exactly as the original.
    n = m.state_size
    lo, hi = [0.0] * n, [0.05] * n
    a = kccd.Checker(humanoid).query(lo, hi, type="distances")
    b = kccd.Checker(m).query(lo, hi, type="distances")
    assert list(a.distance) == list(b.distance)


def _state_size(model: kccd.Model) -> int:
    return model.state_size


def test_pickles_into_worker_processes(arm: kccd.Model) -> None:
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        assert pool.map(_state_size, [arm, arm]) == [3, 3]


def test_bad_model_names_line_and_field() -> None:
    text = (DATA / "demo_arm.yaml").read_text().replace("radius: 0.09", "radius: -0.09", 1)
    with pytest.raises(kccd.InputError) as e:
        kccd.Model.from_yaml(text, "bad.yaml")
    assert isinstance(e.value, ValueError)
    assert e.value.source == "bad.yaml"
    line = next(i + 1 for i, l in enumerate(text.splitlines()) if "radius: -0.09" in l)
    assert e.value.line == line and e.value.column > 0
    assert "radius" in e.value.field
    assert str(e.value).startswith(f"bad.yaml:{line}:")


def test_yaml_syntax_and_missing_file() -> None:
    with pytest.raises(kccd.InputError) as e:
        kccd.Model.from_yaml("kccd: 1\nname: [\n", "broken.yaml")
    assert e.value.line >= 2
    with pytest.raises(kccd.InputError) as e:
        kccd.Model.load("/nonexistent/robot.yaml")
    assert "/nonexistent/robot.yaml" in str(e.value)


def test_wrong_argument_types() -> None:
    with pytest.raises(TypeError):
        kccd.Model.load(3)  # type: ignore[arg-type]
