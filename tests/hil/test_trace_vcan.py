"""A raw CAN trace of a session with hil_sim over SocketCAN (needs vcan0: tools/with-vcan):
`legsim-bench record --log trace.blf` against a started hil_sim, then the trace replayed
(legsim_bench.hil.runner.replay_trace, the link's own decoding) gives the same recording and
the same verdict. Short (free_fall, 30 samples): the VM is slow."""
from __future__ import annotations

import json

from legsim_bench import cli
from legsim_bench.hil import can_link as cl
from legsim_bench.hil.runner import replay_trace
from legsim_bench.hil.trace import read_trace
from legsim_bench.recording import load_recording, scene_of
from legsim_bench.verdict.checks import evaluate

from conftest import ROOT


def _rows(ev):
    return json.dumps([(r.name, r.passed, r.error, r.where, r.got) for r in ev.results])


def test_a_session_on_vcan_replays_from_its_blf_trace_to_the_same_verdict(vcan, hil_binary, tmp_path):
    trace = tmp_path / "free_fall.blf"
    rc = cli.main(["record", "free_fall", "--start-hil", "--hil-sim", str(hil_binary),
                   "--interface", "socketcan", "--channel", vcan, "--no-progress",
                   "--out", str(tmp_path), "--log", str(trace)])
    assert rc == 0, (tmp_path / "hil_sim.log").read_text(errors="replace")
    live = load_recording(tmp_path / "free_fall" / "recording.json")
    assert live["complete"] and live["trace"] == str(trace)

    frames = read_trace(trace)
    rx = [m for m in frames if m.is_rx]
    assert all(m.is_fd and len(m.data) == 64 for m in frames)
    assert sum(m.arbitration_id == cl.ST_STATUS for m in rx) == len(live["samples"])
    assert any(m.arbitration_id == cl.HEARTBEAT for m in rx)
    assert sum(m.arbitration_id == cl.CONTROL for m in frames if not m.is_rx) == len(live["samples"])

    replayed = replay_trace(trace, scene_of(live, ROOT), dbc=ROOT / "can" / "legsim.dbc")
    for key in ("samples", "commands", "loads", "injections", "errors", "complete", "late_faults",
                "heartbeat"):
        if key == "samples":
            strip = lambda ss: [{k: v for k, v in s.items() if k != "wall"} for s in ss]  # noqa: E731
            assert json.dumps(strip(live[key])) == json.dumps(strip(replayed[key]))
        else:
            assert json.dumps(live[key]) == json.dumps(replayed[key]), key
    ev_live, ev_replay = evaluate(live, ROOT), evaluate(replayed, ROOT)
    assert ev_live.passed and ev_replay.passed and _rows(ev_live) == _rows(ev_replay)
