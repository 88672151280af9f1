"""Every scene of scenes/*.toml (and the fixtures' scenes: the heavy-shank leg, which names its
own model file, and the robot pushed by a box load), recorded end to end through the bench:
dynamics against hil_sim over SocketCAN (the leg's, and the two-leg robot's on
hil_sim --model ROBOT.toml as two CAN nodes), the other analyses in legsim_cli (no CAN frames).

Needs vcan0 (CAN FD) and a built hil_sim, so it runs inside tools/with-vcan (tools/test.sh):

    tools/with-vcan env TMPDIR=/dev/shm python3 -m pytest -q tests/hil_scenes

One hil_sim per model (from $LEGSIM_HIL_SIM, else build/host/hil_sim/hil_sim; with
--model FILE for a scene's own model) and one CAN link for the module; each scene RESETs its
own session and is recorded to $LEGSIM_SCENES_OUT/NAME/recording.json (default out/hil_scenes/
in the repository). Here each run must complete; the verdicts against the reference model are
tests/hil_verdicts/, on the host, where the robot's reference simulations run at native speed
(the VM emulates its CPU).

Without vcan0 or without the binary every test is skipped with the reason (so the module
can be collected anywhere), unless LEGSIM_HIL_REQUIRE=1 turns the skips into failures.
"""
from __future__ import annotations

import os
import socket
import sys
import time
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
# heavy_shank_free_fall names models/heavy_shank.toml (shank + 2 kg); robot_box_load pushes the box;
# robot_slide_start starts both feet sliding (START_CMD's Start_SlidingContacts).
FIXTURE_SCENES = ["heavy_shank_free_fall.toml", "robot_box_load.toml", "robot_slide_start.toml"]

# Scenes that show a bug of the core another branch fixes (issue 22): each is shipped with the
# checks it should meet and marked xfail (strict: it turns green, and must be unmarked, when the
# fix merges). XFAIL_RUN: the run itself fails (hil_sim HALTED); XFAIL_VERDICT: its verdict
# (tests/hil_verdicts) fails.
XFAIL_RUN: dict[str, str] = {}
XFAIL_VERDICT = {
    **XFAIL_RUN,
}


def xfail(names, reasons):
    return [pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=reasons[n])) if n in reasons else n
            for n in names]


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
            # the old process's last frames, still in the link's socket, are not the new one's:
            # a stale HEARTBEAT taken for it sent the first RESET before the new one listened
            if self.link is not None:
                self.link.drain()
            started = time.monotonic()
            self.proc = HilProcess.for_scene(sc, CHANNEL, binary, self.out_dir / "hil_sim.log").__enter__()
            self.args = sc.hil_args()
            if self.link is None:
                self.link = HilLink(interface="socketcan", channel=CHANNEL, dbc=ROOT / "can" / "legsim.dbc",
                                    timeout=10.0).__enter__()
            try:
                while True:  # a HEARTBEAT of this process: its uptime within its age
                    hb = self.link.heartbeat(timeout=10.0)
                    if hb.uptime_ms <= (time.monotonic() - started) * 1e3 + 100:
                        break
                    if time.monotonic() - started > 10.0:
                        raise RuntimeError(f"only HEARTBEATs of an older hil_sim (uptime {hb.uptime_ms} ms)")
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


def _record(spec, hil, out_dir):
    from legsim_bench.hil.runner import record
    from legsim_bench.recording import save_recording

    sc = load_scene(spec, ROOT)
    rec = record(sc, hil.for_scene(sc), progress=False)
    save_recording(rec, out_dir / sc.name / "recording.json")
    assert rec["complete"], f"{sc.name}: run did not complete: {rec['errors']}"


@pytest.mark.parametrize("name", xfail(SCENES, XFAIL_RUN))
def test_scene(name, hil, out_dir):
    _record(name, hil, out_dir)


@pytest.mark.parametrize("fixture", FIXTURE_SCENES)
def test_fixture_scene(fixture, hil, out_dir):
    _record(FIXTURES / fixture, hil, out_dir)
