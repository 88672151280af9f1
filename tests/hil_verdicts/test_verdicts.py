"""The verdicts on the recordings tests/hil_scenes made over SocketCAN: every shipped scene and
the fixtures' scenes checked against the bench's reference model, exactly as `legsim-bench run`
does, here on the host (the recordings come out of the VM through the shared tree).

tools/test.sh runs tests/hil_scenes (in the VM) first, from an empty $LEGSIM_SCENES_OUT, then
this module with the other host tests. Run alone, a scene whose recording is missing is skipped
with the command that makes it (a failure under LEGSIM_NO_SKIP=1). The check tables are written
beside each recording (checks.json, checks.csv, table.txt); `legsim-bench check out/hil_scenes`
adds the plots.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.recording import load_recording  # noqa: E402
from legsim_bench.report.tables import format_table, write_outputs  # noqa: E402
from legsim_bench.scene import shipped_scenes  # noqa: E402
from legsim_bench.verdict.checks import evaluate  # noqa: E402

OUT = Path(os.environ.get("LEGSIM_SCENES_OUT", ROOT / "out" / "hil_scenes"))
SCENES = [p.stem for p in shipped_scenes(ROOT)] + ["heavy_shank_free_fall", "robot_box_load"]


def _recording(name: str) -> dict:
    path = OUT / name / "recording.json"
    if not path.is_file():
        pytest.skip(f"no recording {path}: record it first "
                    f"(tools/with-vcan env TMPDIR=/dev/shm python3 -m pytest tests/hil_scenes)")
    return load_recording(path)


def _check(name: str) -> dict:
    rec = _recording(name)
    assert rec["complete"], f"{name}: the run did not complete: {rec['errors']}"
    ev = evaluate(rec, ROOT)
    d = OUT / name
    write_outputs(ev, d)
    table = format_table(ev)
    (d / "table.txt").write_text(table + "\n")
    print(table)
    assert ev.passed, "\n" + table
    return rec


@pytest.mark.parametrize("name", SCENES)
def test_recorded_scene_passes_its_checks(name):
    _check(name)


def test_a_scene_with_its_own_model_file_differs_from_the_stock_leg():
    """heavy_shank_free_fall (hil_sim --model models/heavy_shank.toml, checked against the
    reference built from the same file, positions within 1e-5 m) and the stock leg's free_fall,
    from the same pose with the same commands, are two motions (far more than 1e-5 m apart)."""
    qh = np.array([s["q"] for s in _recording("heavy_shank_free_fall")["samples"]])
    qs = np.array([s["q"] for s in _recording("free_fall")["samples"]])
    assert qh.shape == qs.shape
    assert np.max(np.abs(qh[0] - qs[0])) < 1e-6          # the same stand pose to start
    xy = np.delete(np.arange(18), np.s_[2::3])
    # then another motion: at the end 100x the position tolerance apart (legsim_cli: 2.0 mm in x)
    assert np.max(np.abs(qh[-1, xy] - qs[-1, xy])) > 100 * 1e-5


def test_a_robot_scene_with_a_box_load_moves_the_box_as_pushed():
    """fixtures/robot_box_load.toml: box_load goes to hil_sim in leg 0's LOAD_CMD (index 2
    box.load, 3 box.moment) and RobotModel replays the float32 load: the run passes its checks
    (test_recorded_scene_passes_its_checks) and the box moves as pushed (forward and down, far
    beyond them)."""
    rec = _recording("robot_box_load")
    assert [x["name"] for x in rec["loads"] if x.get("box")] == ["box.load", "box.moment"]
    q = np.array([s["q"] for s in rec["samples"]])
    assert q[-1, 0] - q[0, 0] > 1e-4 and q[-1, 1] - q[0, 1] < -1e-5
