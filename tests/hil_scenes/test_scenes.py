"""Every scene of scenes/*.toml (and the heavy-shank scene of fixtures/, which names its own
model file), end to end through the bench: dynamics against hil_sim over SocketCAN (the leg's,
and the two-leg robot's on hil_sim --model ROBOT.toml as two CAN nodes, against RobotModel),
the other analyses in legsim_cli (no CAN frames for them), all checked against the reference
model.

Needs vcan0 (CAN FD) and a built hil_sim, so it runs inside tools/with-vcan (tools/test.sh):

    tools/with-vcan env TMPDIR=/dev/shm python3 -m pytest -q tests/hil_scenes

One hil_sim per model (from $LEGSIM_HIL_SIM, else build/host/hil_sim/hil_sim; with
--model FILE for a scene's own model) and one CAN link for the module; each scene RESETs its
own session, is recorded, then checked against the bench's reference model exactly as
`legsim-bench run` does (no plots: matplotlib stays out of the VM). Recordings and the check tables go to $LEGSIM_SCENES_OUT (default
out/hil_scenes/ in the repository) for `legsim-bench check` on the host, where the plots
are cheap.

Without vcan0 or without the binary every test is skipped with the reason (so the module
can be collected anywhere), unless LEGSIM_HIL_REQUIRE=1 turns the skips into failures.
"""
from __future__ import annotations

import os
import socket
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.scene  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.hil.vcan import vcan_problem as _vcan_problem  # noqa: E402
from legsim_bench.scene import load_scene, shipped_scenes  # noqa: E402

CHANNEL = os.environ.get("LEGSIM_HIL_CHANNEL", "vcan0")
REQUIRE = os.environ.get("LEGSIM_HIL_REQUIRE") == "1"
FIXTURES = Path(__file__).resolve().parent / "fixtures"
SCENES = [p.stem for p in shipped_scenes(ROOT)]
OWN_MODEL = FIXTURES / "heavy_shank_free_fall.toml"   # models/heavy_shank.toml: shank + 2 kg


def _skip_or_fail(reason: str):
    if REQUIRE:
        pytest.fail(reason + " (LEGSIM_HIL_REQUIRE=1)")
    pytest.skip(reason)


def vcan_problem(channel: str = CHANNEL) -> str | None:
    return _vcan_problem(channel)


@pytest.fixture(scope="module")
def out_dir() -> Path:
    d = Path(os.environ.get("LEGSIM_SCENES_OUT", ROOT / "out" / "hil_scenes"))
    d.mkdir(parents=True, exist_ok=True)
    return d


class Hil:
    """hil_sim for the scene's model (restarted with --model FILE when it changes) and one link."""

    def __init__(self, out_dir: Path):
        self.out_dir, self.proc, self.link, self.args = out_dir, None, None, None

    def for_scene(self, sc):
        from legsim_bench.hil.can_link import HilLink
        from legsim_bench.hil.runner import HilProcess, hil_sim_path

        if not sc.over_can:
            return None                      # legsim_cli: no bus
        if self.proc is None or self.args != sc.hil_args():
            problem = vcan_problem()
            if problem:
                _skip_or_fail(problem)
            binary = hil_sim_path(ROOT)
            if not binary.is_file():
                _skip_or_fail(f"{binary} not built (cmake --preset host && cmake --build --preset host)")
            self.close_proc()
            self.proc = HilProcess.for_scene(sc, CHANNEL, binary, self.out_dir / "hil_sim.log").__enter__()
            self.args = sc.hil_args()
            if self.link is None:
                self.link = HilLink(interface="socketcan", channel=CHANNEL, dbc=ROOT / "can" / "legsim.dbc",
                                    timeout=10.0).__enter__()
            try:
                self.link.heartbeat(timeout=10.0)
            except Exception as e:  # noqa: BLE001
                pytest.fail(f"hil_sim {' '.join(self.args)} did not come up on {CHANNEL}: {e}\n{self.proc.log()}")
        return self.link

    def close_proc(self):
        if self.proc is not None:
            alive = self.proc.proc.poll() is None
            log = self.proc.log()
            self.proc.stop()
            self.proc = None
            assert alive, f"hil_sim died: {log}"


@pytest.fixture(scope="module")
def hil(out_dir):
    h = Hil(out_dir)
    yield h
    h.close_proc()
    if h.link is not None:
        h.link.__exit__(None, None, None)


def test_shipped_scenes_exist():
    assert len(SCENES) >= 12, SCENES


def _run(spec, hil, out_dir):
    from legsim_bench.verdict.checks import evaluate
    from legsim_bench.report.tables import format_table, write_outputs
    from legsim_bench.hil.runner import record
    from legsim_bench.recording import save_recording

    sc = load_scene(spec, ROOT)
    rec = record(sc, hil.for_scene(sc), progress=False)
    d = out_dir / sc.name
    save_recording(rec, d / "recording.json")
    assert rec["complete"], f"{sc.name}: run did not complete: {rec['errors']}"
    ev = evaluate(rec, ROOT)
    write_outputs(ev, d)
    table = format_table(ev)
    (d / "table.txt").write_text(table + "\n")
    print(table)
    assert ev.passed, "\n" + table
    return rec


@pytest.mark.parametrize("name", SCENES)
def test_scene(name, hil, out_dir):
    _run(name, hil, out_dir)


def test_a_scene_with_its_own_model_file_runs_on_hil_sim_and_differs_from_the_stock_leg(hil, out_dir):
    """heavy_shank_free_fall: hil_sim --model models/heavy_shank.toml, checked against the
    reference built from the same file (positions within 1e-5 m); the stock leg's free fall,
    from the same pose with the same commands, is another motion (far more than 1e-5 m)."""
    import numpy as np

    heavy = _run(OWN_MODEL, hil, out_dir)
    stock = _run("free_fall", hil, out_dir)
    qh = np.array([s["q"] for s in heavy["samples"]])
    qs = np.array([s["q"] for s in stock["samples"]])
    assert qh.shape == qs.shape
    assert np.max(np.abs(qh[0] - qs[0])) < 1e-6          # the same stand pose to start
    xy = np.delete(np.arange(18), np.s_[2::3])
    # then another motion: at the end 100x the position tolerance apart (legsim_cli: 2.0 mm in x)
    assert np.max(np.abs(qh[-1, xy] - qs[-1, xy])) > 100 * 1e-5


def test_a_robot_scene_with_a_box_load_runs_over_can_against_robot_model(hil, out_dir):
    """fixtures/robot_box_load.toml: box_load goes to hil_sim in leg 0's LOAD_CMD (index 2
    box.load, 3 box.moment) and RobotModel replays the float32 load: the run passes its checks
    (1e-9 m + float32) and the box moves as pushed (forward and down, far beyond them)."""
    import numpy as np

    rec = _run(FIXTURES / "robot_box_load.toml", hil, out_dir)
    assert [x["name"] for x in rec["loads"] if x.get("box")] == ["box.load", "box.moment"]
    q = np.array([s["q"] for s in rec["samples"]])
    assert q[-1, 0] - q[0, 0] > 1e-4 and q[-1, 1] - q[0, 1] < -1e-5
