"""Shared set-up of the bench tests (tests/bench).

pytest imports this before the test modules of this folder, so the bench package
is importable in all of them: the installed one, else this tree's bench/.
Fixtures: the two-leg robot reference built from models/robot.toml.
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
if importlib.util.find_spec("legsim_bench") is None:  # not installed: the source tree
    sys.path.insert(0, str(ROOT / "bench"))


@pytest.fixture(scope="module")
def robot():
    """The robot reference (RobotModel) of models/robot.toml, built once per module."""
    from legsim_bench.reference.robot import RobotModel
    from model_files import ROBOT
    return RobotModel.from_toml(ROBOT)
