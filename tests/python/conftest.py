"""Shared fixtures of the Python package's tests (run by ctest as `python`, or by hand:
PYTHONPATH=build/python /usr/bin/python3 -m pytest tests/python)."""

import os
import pathlib

import pytest

import kccd

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = ROOT / "data"


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The `kccd` command built beside the package (KCCD_CLI overrides)."""
    path = pathlib.Path(os.environ.get("KCCD_CLI", pathlib.Path(kccd.__file__).resolve().parents[2] / "overlay" / "kccd"))
    assert path.is_file(), f"kccd command not found at {path} (set KCCD_CLI)"
    return path


@pytest.fixture(scope="session")
def arm() -> kccd.Model:
    return kccd.Model.load(str(DATA / "demo_arm.yaml"))


@pytest.fixture(scope="session")
def humanoid() -> kccd.Model:
    return kccd.Model.load(str(DATA / "humanoid.yaml"))


@pytest.fixture(scope="session")
def camera() -> kccd.Camera:
    return kccd.Camera.load(str(DATA / "demo_camera.yaml"))
