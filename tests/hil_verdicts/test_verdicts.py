"""The verdicts on the recordings tests/hil_scenes made over SocketCAN: every shipped scene and
the fixtures' scenes checked against the bench's reference model by `legsim-bench check`, here
on the host (the recordings come out of the VM through the shared tree).

tools/test.sh runs tests/hil_scenes (in the VM) first, into an emptied $LEGSIM_SCENES_OUT, then
this module with the other host tests. A recording that is missing, or older than the hil_sim
or legsim_cli it would have come from, is skipped with the command that makes it (a failure
under LEGSIM_NO_SKIP=1): a verdict never reads an earlier build's run. The check tables go
beside each recording (checks.json, checks.csv; a robot's samples.csv and reference.csv);
`legsim-bench check out/hil_scenes` adds the plots.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "hil_scenes"))
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.cli import main as bench_main  # noqa: E402
from legsim_bench.hil.runner import hil_sim_path  # noqa: E402
from legsim_bench.recording import load_recording  # noqa: E402
from legsim_bench.scene import cli_path, shipped_scenes  # noqa: E402
from test_scenes import FIXTURE_SCENES, XFAIL_VERDICT, xfail  # noqa: E402

OUT = Path(os.environ.get("LEGSIM_SCENES_OUT", ROOT / "out" / "hil_scenes"))
SCENES = [p.stem for p in shipped_scenes(ROOT)] + [Path(f).stem for f in FIXTURE_SCENES]


def _recording_path(name: str) -> Path:
    path = OUT / name / "recording.json"
    record = "tools/with-vcan env TMPDIR=/dev/shm python3 -m pytest tests/hil_scenes"
    if not path.is_file():
        pytest.skip(f"no recording {path}: record it first ({record})")
    built = [b.stat().st_mtime for b in (hil_sim_path(ROOT), cli_path(ROOT)) if b.is_file()]
    if built and path.stat().st_mtime < max(built):
        pytest.skip(f"{path} is older than the hil_sim / legsim_cli built since: record it again ({record})")
    return path


@pytest.mark.parametrize("name", xfail(SCENES, XFAIL_VERDICT))
def test_recorded_scene_passes_its_checks(name, capsys):
    rc = bench_main(["check", str(_recording_path(name)), "--no-plots"])
    assert rc == 0, capsys.readouterr().out


def _samples_q(name: str) -> np.ndarray:
    return np.array([s["q"] for s in load_recording(_recording_path(name))["samples"]])


def test_a_scene_with_its_own_model_file_differs_from_the_stock_leg():
    """heavy_shank_free_fall (hil_sim --model models/heavy_shank.toml, checked against the
    reference built from the same file, positions within 1e-5 m) and the stock leg's free_fall,
    from the same pose with the same commands, are two motions (far more than 1e-5 m apart)."""
    qh, qs = _samples_q("heavy_shank_free_fall"), _samples_q("free_fall")
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
    rec = load_recording(_recording_path("robot_box_load"))
    assert [x["name"] for x in rec["loads"] if x.get("box")] == ["box.load", "box.moment"]
    q = np.array([s["q"] for s in rec["samples"]])
    assert q[-1, 0] - q[0, 0] > 1e-4 and q[-1, 1] - q[0, 1] < -1e-5


def test_a_start_off_the_stance_reaches_hil_sim():
    """START_CMD: hil_sim's RESET starts the robot where legsim_cli does: robot_drop_1cm's stance
    lifted 1 cm with both feet free, robot_throw's moving at (1, 0.5) m/s (float32), and
    robot_slope_steep on the scene's ground (hil_sim --ground) with its feet stuck."""
    drop = load_recording(_recording_path("robot_drop_1cm"))["samples"][0]
    assert [c["state"] for c in drop["contacts"]] == ["free", "free"]
    assert drop["q"][1] == pytest.approx(1.01, abs=1e-6)
    throw = load_recording(_recording_path("robot_throw"))["samples"][0]
    qd = np.array(throw["qd"]).reshape(-1, 3)
    assert qd[:, 0] == pytest.approx(1.0, abs=1e-6) and qd[:, 1] == pytest.approx(0.5, abs=1e-6)
    slope = load_recording(_recording_path("robot_slope_steep"))["samples"][0]
    assert slope["q"][2] == pytest.approx(0.3, abs=1e-6)   # the stance parallel to the 0.3 rad line
    (xr, yr), (xl, yl) = [(c["x"], c["y"]) for c in slope["contacts"]]
    assert (yr - yl) / (xr - xl) == pytest.approx(np.tan(0.3), abs=1e-6)
    slide = load_recording(_recording_path("robot_slide_start"))["samples"]
    assert [c["state"] for c in slide[0]["contacts"]] == ["sliding", "sliding"]


def test_a_command_switches_in_the_exchange_after_its_foot_lands():
    """robot_land_switch over CAN: the bench sends the right upper's new set-point in the exchange
    right after the sample whose Ct_Events hold the right foot's touchdown, never before."""
    rec = load_recording(_recording_path("robot_land_switch"))
    td = next(s["step"] for s in rec["samples"] if "touchdown" in s["contacts"][0]["events"])
    sent = [(c["step"], c["right.upper"][1]) for c in rec["commands"] if "right.upper" in c]
    before = {v for k, v in sent if k < td}
    after = {v for k, v in sent if k >= td}
    assert td == 46 and len(before) == 1 and len(after) == 1
    assert after.pop() - before.pop() == pytest.approx(0.02, abs=1e-6)


def test_a_stroke_stop_arrives_over_can_in_the_step_that_holds_it(capsys):
    """robot_fold_stop over CAN: the left lower (robot actuator 3: leg 1's St_StrokeMask bit 1)
    reaches its stroke minimum in the step 84 .. 85 ms, where the reference puts it (84.07 ms),
    and in no other sample; the verdict's arrival check names it (test_robot_stop_arrivals: the
    check fails a missing, late, misplaced or extra arrival)."""
    path = _recording_path("robot_fold_stop")
    hits = [(s["step"], s["stroke_mask"], s["status"] & (1 << 3 | 1 << 4))
            for s in load_recording(path)["samples"] if s["stroke_mask"] or s["status"] & (1 << 3 | 1 << 4)]
    assert hits == [(85, 1 << 3, 1 << 3)]
    assert bench_main(["check", str(path), "--no-plots"]) == 0
    assert "stroke stop arrivals in the step that holds the reference's: 1 arrivals: left.lower stroke_min " \
           "at 0.084071 s" in capsys.readouterr().out
