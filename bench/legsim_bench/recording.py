"""A recording: plain JSON (`legsim-bench-recording/1`) of one run of a scene, whoever ran it
(hil_sim over CAN, legsim_cli, the reference model playing hil_sim); it carries the scene it
was made from, so that the verdicts need nothing else: the TOML text as written
("scene_source") and the scene as legsim_cli resolved it ("scene_resolved", its --check JSON),
from which the verdicts rebuild the Scene without reading the TOML again. A recording without
"scene_resolved" (made before recordings carried it) has its TOML text read by legsim_cli.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from .scene import Scene, SceneError, parse_scene, scene_from_resolved

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
    """The Scene a recording was made from: its resolved scene, else its TOML text read by
    legsim_cli (SceneError if the bench cannot run it)."""
    p = rec.get("scene_path")
    if rec.get("scene_resolved") is not None:
        try:
            return scene_from_resolved(rec["scene_resolved"], p, rec.get("scene_source", ""), root=root)
        except (KeyError, TypeError, ValueError, IndexError) as e:
            if isinstance(e, SceneError):
                raise
            raise RecordingError(f"its resolved scene (scene_resolved) is not legsim_cli --check's: {e!r}") from None
    if "scene_source" not in rec:
        raise RecordingError("the recording carries no scene (neither scene_resolved nor scene_source)")
    return parse_scene(rec["scene_source"], p, root=root, name=rec.get("scene_name"))
