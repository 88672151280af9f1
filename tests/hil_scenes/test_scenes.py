"""Every shipped bench scene (bench/scenes/*.toml), end to end against hil_sim over SocketCAN.

Needs vcan0 (CAN FD) and a built hil_sim, so it runs inside tools/with-vcan (tools/test.sh):

    tools/with-vcan env TMPDIR=/dev/shm python3 -m pytest -q tests/hil_scenes

One hil_sim (from $LEGSIM_HIL_SIM, else build/host/hil_sim/hil_sim) and one CAN link for
the module; each scene RESETs its own session, is recorded, then checked against the
bench's reference model exactly as `legsim-bench run` does (no plots: matplotlib stays out
of the VM). Recordings and the check tables go to $LEGSIM_SCENES_OUT (default
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

from legsim_bench.vcan import vcan_problem as _vcan_problem  # noqa: E402
from legsim_bench.scene import load_scene, shipped_scenes  # noqa: E402

CHANNEL = os.environ.get("LEGSIM_HIL_CHANNEL", "vcan0")
REQUIRE = os.environ.get("LEGSIM_HIL_REQUIRE") == "1"
SCENES = [p.stem for p in shipped_scenes(ROOT)]


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


@pytest.fixture(scope="module")
def link(out_dir):
    problem = vcan_problem()
    if problem:
        _skip_or_fail(problem)
    from legsim_bench.runner import HilProcess, hil_sim_path

    binary = hil_sim_path(ROOT)
    if not binary.is_file():
        _skip_or_fail(f"{binary} not built (cmake --preset host && cmake --build --preset host)")
    with HilProcess(CHANNEL, binary, log_path=out_dir / "hil_sim.log") as hil:
        from legsim_bench.can_link import HilLink

        with HilLink(interface="socketcan", channel=CHANNEL, dbc=ROOT / "can" / "legsim.dbc",
                     timeout=10.0) as lk:
            try:
                lk.heartbeat(timeout=10.0)
            except Exception as e:  # noqa: BLE001
                pytest.fail(f"hil_sim did not come up on {CHANNEL}: {e}\n{hil.log()}")
            yield lk
        assert hil.proc.poll() is None, f"hil_sim died: {hil.log()}"


def test_shipped_scenes_exist():
    assert len(SCENES) >= 7, SCENES


@pytest.mark.parametrize("name", SCENES)
def test_scene(name, link, out_dir):
    from legsim_bench.checks import evaluate
    from legsim_bench.report import format_table, write_outputs
    from legsim_bench.runner import record, save_recording

    sc = load_scene(name, ROOT)
    rec = record(sc, link, progress=False)
    d = out_dir / sc.name
    save_recording(rec, d / "recording.json")
    assert rec["complete"], f"{name}: run did not complete: {rec['errors']}"
    ev = evaluate(rec, ROOT)
    write_outputs(ev, d)
    table = format_table(ev)
    (d / "table.txt").write_text(table + "\n")
    print(table)
    assert ev.passed, "\n" + table
