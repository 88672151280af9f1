"""The analyses that have no CAN frames (statics, statics_sweep, inverse_dynamics, assembly, and a
robot's dynamics given no bus) run in legsim_cli, the core on this host, through the same scene
file (`legsim_cli SCENE --format json`). The recording is the same file format with
`"runner": "legsim_cli"` and the CLI's JSON output.
"""
from __future__ import annotations

import datetime as _dt
import json
import platform
import subprocess
import time
from pathlib import Path

from ..recording import FORMAT
from ..scene import Scene, cli_path

__all__ = ["record_analysis"]


def record_analysis(scene: Scene, *, root: Path | None = None, log=None) -> dict:
    """Runs the scene in legsim_cli; the recording holds its JSON output (or the error)."""
    log = log or (lambda msg: None)
    rec: dict = {
        "format": FORMAT, "runner": "legsim_cli", "scene_name": scene.name,
        "scene_path": str(scene.path) if scene.path else None, "scene_source": scene.source,
        "scene_resolved": scene.resolved(),
        "started": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "host": platform.node(), "python": platform.python_version(), "bus": "none (legsim_cli)",
        "heartbeat": None, "samples": [], "commands": [], "loads": [], "injections": [],
        "late_faults": [], "errors": [], "complete": False, "initial_lengths": None, "cli": None,
    }
    t0 = time.monotonic()
    cli = cli_path(root)
    if scene.path is None:
        rec["errors"].append({"step": None, "error": "legsim_cli runs scene files: this scene has no path"})
    elif not cli.is_file():
        rec["errors"].append({"step": None, "error": f"legsim_cli not found at {cli}: build it (cmake "
                              "--build --preset host --target legsim_cli) or set LEGSIM_CLI"})
    else:
        rec["cli"] = str(cli)
        r = subprocess.run([str(cli), str(scene.path), "--format", "json"], capture_output=True,
                           text=True, timeout=3600)
        rec["cli_exit"] = r.returncode
        try:
            out = json.loads(r.stdout) if r.stdout.strip() else None
        except json.JSONDecodeError as e:
            out = None
            rec["errors"].append({"step": None, "error": f"legsim_cli wrote no JSON: {e}"})
        rec["cli_output"] = out
        if r.returncode != 0:
            rec["errors"].append({"step": None, "error": f"legsim_cli exit {r.returncode}: {r.stderr.strip()}"})
        if out is not None:
            # samples in the bench's shape for the summary lines (no faults: no bus)
            rec["samples"] = [dict(s, faults=[]) for s in out.get("samples", [])]
        rec["complete"] = r.returncode == 0 and out is not None and out.get("status") == "ok"
    rec["wall_time_s"] = time.monotonic() - t0
    for e in rec["errors"]:
        log(e["error"])
    return rec
