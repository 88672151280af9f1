"""Shared fixtures of the Python API tests (tests/python).

They need the host build's shared libraries (liblegsim.so, liblegsim_f32.so: the
targets legsim and legsim_f32), found as the package finds them ($LEGSIM_LIB_DIR,
else build/host/firmware_core/). Without them the tests are skipped with that
reason (a failure under LEGSIM_NO_SKIP=1, see tests/conftest.py).
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
if importlib.util.find_spec("legsim") is None:  # not installed: the package of this tree
    sys.path.insert(0, str(ROOT / "python"))

import legsim  # noqa: E402


ROBOT = ROOT / "models" / "robot.toml"


def robot_sim(**kw) -> legsim.Sim:
    """The two-leg robot of models/robot.toml (skipped where the library has no room for it)."""
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip(f"{lib.path} is built without room for the robot")
    return legsim.Sim(str(ROBOT), **kw)


def _need(precision: str) -> None:
    if not legsim.library_available(precision):
        pytest.skip(f"{legsim.LIB_NAMES[precision]} is not built (cmake --build build/host, "
                    "or set LEGSIM_LIB_DIR)")


@pytest.fixture(autouse=True)
def _double_library():
    _need("double")


@pytest.fixture(params=["double", "float"])
def precision(request) -> str:
    """Each precision whose library is built."""
    _need(request.param)
    return request.param


@pytest.fixture
def root() -> Path:
    return ROOT


@pytest.fixture
def model_toml() -> Path:
    return ROOT / "models" / "leg.toml"


@pytest.fixture
def stand():
    """make(model=None, **Sim keywords): a sim assembled in the stand pose."""
    def make(model=None, **kw) -> legsim.Sim:
        s = legsim.Sim(model, **kw)
        s.assemble_pose("stand")
        return s
    return make
