"""The bench's one reader of model files (models/*.toml), apart from the core's loader.

The references read model files themselves, not through legsim_cli: their independence from
the core is the point. The references, the verdicts' own leg equations (verdict/leg.py) and the
peers' model builders all read through here; what each takes from the file is its own.
"""
from __future__ import annotations

import os
import stat
import tomllib
from pathlib import Path

__all__ = ["ModelFileError", "read_model_file"]


class ModelFileError(ValueError):
    """A model file that cannot be read: the message names the file."""


# as the core's reader (firmware_core/host/toml_limits.hpp: kTomlMaxBytes)
MAX_BYTES = 1024 * 1024


def read_model_file(path: str | os.PathLike) -> dict:
    """The model file's tables as a dict (TOML's types: lists of tables for [[body]] etc.).
    As the core's reader: a regular file of at most 1 MiB; anything else (a FIFO, a device,
    a folder) is refused without blocking: opened non-blocking and checked before reading."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise ModelFileError(f"{path}: cannot read the model file: not a regular file")
        with os.fdopen(fd, "rb") as fh:
            data = fh.read(MAX_BYTES + 1)
        if len(data) > MAX_BYTES:
            raise ModelFileError(f"{path}: cannot read the model file: larger than {MAX_BYTES} bytes")
        return tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError as e:
        raise ModelFileError(f"{path}: not UTF-8 text: {e}") from None
    except OSError as e:
        raise ModelFileError(f"{path}: cannot read the model file: {e.strerror or e}") from None
    except tomllib.TOMLDecodeError as e:
        raise ModelFileError(f"{path}: not TOML: {e}") from None
