"""A recording: plain JSON (`legsim-bench-recording/1`) of one run of a scene, whoever ran it
(hil_sim over CAN, legsim_cli, the reference model playing hil_sim); it carries the scene it
was made from, so that the verdicts need nothing else.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from .scene import Scene, parse_scene

FORMAT = "legsim-bench-recording/1"

__all__ = ["FORMAT", "RecordingError", "save_recording", "load_recording", "scene_of"]


class RecordingError(RuntimeError):
    pass


def save_recording(rec: dict, path: str | os.PathLike) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(rec, indent=1, allow_nan=True))
    tmp.replace(path)
    return path


def load_recording(path: str | os.PathLike) -> dict:
    path = Path(path)
    try:
        rec = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise RecordingError(f"{path}: cannot read the recording: {e}") from None
    if not isinstance(rec, dict) or rec.get("format") != FORMAT:
        raise RecordingError(f"{path}: not a legsim-bench recording ({FORMAT})")
    return rec


def scene_of(rec: dict, root: Path | None = None) -> Scene:
    """The Scene a recording was made from (parsed from the TOML text it carries)."""
    p = rec.get("scene_path")
    return parse_scene(rec["scene_source"], p, root=root, name=rec.get("scene_name"))
