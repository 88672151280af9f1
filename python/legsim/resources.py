"""Where the shipped models, scenes and DBC are, and the scene runner (legsim_cli).

An installed wheel carries them in the package (python/pyproject.toml):
``legsim/share/legsim/{models,scenes,can}`` and ``legsim/bin/legsim_cli``. In the
repository (this package on PYTHONPATH, or ``pip install -e``) they are the
repository's own ``models/``, ``scenes/``, ``can/`` and the host build's CLI.
"""
from __future__ import annotations

import shutil
from pathlib import Path

from ._lib import PACKAGE_DIR, _repo_roots

CLI_NAME = "legsim_cli"


def data_dir() -> Path:
    """The directory holding ``models/``, ``scenes/`` and ``can/legsim.dbc``: the
    wheel's ``legsim/share/legsim``, else the repository root (``$LEGSIM_ROOT`` or
    the repository this package sits in). Raises FileNotFoundError if neither has them."""
    cands = [PACKAGE_DIR / "share" / "legsim", *_repo_roots()]
    for d in cands:
        if (d / "models" / "leg.toml").is_file():
            return d
    raise FileNotFoundError("the shipped models and scenes were not found (looked in "
                            + ", ".join(str(d) for d in cands) + ")")


def data_path(relative: str) -> Path:
    """A shipped file by its path in the repository, e.g. ``data_path("models/robot.toml")``,
    ``data_path("scenes/robot_swing.toml")``, ``data_path("can/legsim.dbc")``."""
    p = data_dir() / relative
    if not p.exists():
        raise FileNotFoundError(f"{relative}: not among the shipped files ({data_dir()})")
    return p


def cli_path() -> Path:
    """The scene runner: the wheel's ``legsim/bin/legsim_cli``, else the repository's host
    build (``build/host/firmware_core/legsim_cli``), else ``legsim_cli`` on PATH."""
    cands = [PACKAGE_DIR / "bin" / CLI_NAME]
    cands += [r / "build" / "host" / "firmware_core" / CLI_NAME for r in _repo_roots()]
    for c in cands:
        if c.is_file():
            return c
    found = shutil.which(CLI_NAME)
    if found:
        return Path(found)
    raise FileNotFoundError(f"{CLI_NAME} not found (looked at: "
                            + ", ".join(str(c) for c in cands) + ", and PATH)")
