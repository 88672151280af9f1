"""The built programs the bench tests run: each one's path, or the test skipped with how to build it."""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def legsim_cli() -> Path:
    """build/host's legsim_cli (or $LEGSIM_CLI); skips the calling test when it is not built."""
    from legsim_bench.scene import cli_path
    p = cli_path(ROOT)
    if not p.is_file():
        pytest.skip(f"{p} not built (cmake --build --preset host --target legsim_cli, or LEGSIM_CLI)")
    return p
