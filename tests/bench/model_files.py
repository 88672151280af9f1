"""The model files the bench tests read, as paths and as parsed TOML (dicts).

Read-only for the tests: copy (copy.deepcopy) before changing one.
"""
from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ROBOT = ROOT / "models" / "robot.toml"
LEG_TOML = ROOT / "models" / "leg.toml"
DATA = tomllib.loads(ROBOT.read_text())
LEG = tomllib.loads(LEG_TOML.read_text())
