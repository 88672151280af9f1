"""The bench's one reader of model files (models/*.toml), apart from the core's loader.

The references read model files themselves, not through legsim_cli: their independence from
the core is the point. The references, the verdicts' own leg equations (verdict/leg.py) and the
peers' model builders all read through here; what each takes from the file is its own.
"""
from __future__ import annotations

import os
import tomllib
from pathlib import Path

__all__ = ["ModelFileError", "read_model_file"]


class ModelFileError(ValueError):
    """A model file that cannot be read: the message names the file."""


def read_model_file(path: str | os.PathLike) -> dict:
    """The model file's tables as a dict (TOML's types: lists of tables for [[body]] etc.)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except OSError as e:
        raise ModelFileError(f"{path}: cannot read the model file: {e.strerror or e}") from None
    except tomllib.TOMLDecodeError as e:
        raise ModelFileError(f"{path}: not TOML: {e}") from None
