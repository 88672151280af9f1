"""Raw CAN traces (bench/legsim_bench/hil/trace.py): a session recorded through the CAN link on
python-can's 'virtual' interface, against a peer that answers as hil_sim does (the bench's
reference model behind the DBC's frames), is logged to .log, .asc and .blf; each trace replayed
gives the same samples, faults and verdict as the live session. Bad traces give clear errors.
No SocketCAN needed (tests/hil/test_trace_vcan.py does the same against hil_sim in the VM)."""
from __future__ import annotations

import json
import math
import random
import threading
import time
from pathlib import Path

import numpy as np
import pytest

can = pytest.importorskip("can")
cantools = pytest.importorskip("cantools")

from legsim_bench import cli  # noqa: E402
from legsim_bench.hil import can_link as cl  # noqa: E402
from legsim_bench.hil.can_link import HilLink  # noqa: E402
from legsim_bench.hil.reference_link import ReferenceLink  # noqa: E402
from legsim_bench.hil.runner import record, replay_trace  # noqa: E402
from legsim_bench.hil.trace import TraceBus, TraceError, read_trace  # noqa: E402
from legsim_bench.scene import load_scene  # noqa: E402
from legsim_bench.verdict.checks import evaluate  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DBC = ROOT / "can" / "legsim.dbc"


class ReferencePeer(threading.Thread):
    """hil_sim's side of the bus played by ReferenceLink (the bench's model and hil_sim's input
    checks): decodes each frame with the DBC, answers CONTROL with the six state frames, refused
    frames with FAULT, and sends a HEARTBEAT every 100 ms."""

    def __init__(self, channel: str):
        super().__init__(daemon=True)
        self.db = cantools.database.load_file(str(DBC))
        self.bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
        self.ref = ReferenceLink(ROOT)
        self.stop_flag = threading.Event()
        self.tick = 0
        self.error: BaseException | None = None

    def send(self, name: str, values: dict) -> None:
        m = self.db.get_message_by_name(name)
        v = {s.name: 0 for s in m.signals}
        v.update(values)
        self.bus.send(can.Message(arbitration_id=m.frame_id, is_fd=True, is_extended_id=False,
                                  data=m.encode(v, strict=False)))

    def run(self):
        next_hb = time.monotonic()
        try:
            while not self.stop_flag.is_set():
                if time.monotonic() >= next_hb:
                    self.send("HEARTBEAT", {"Hb_ProtocolVersion": 1, "Hb_UptimeMs": int(time.monotonic() * 1e3) % 1000000})
                    next_hb += 0.1
                msg = self.bus.recv(0.01)
                if msg is not None:
                    self.handle(msg)
        except BaseException as e:  # noqa: BLE001 - reported by the test
            self.error = e

    def handle(self, msg):
        ref = self.ref
        fid, data = msg.arbitration_id, bytes(msg.data)
        answer = False
        if fid == cl.CONTROL and len(data) == 64:
            sig = self.db.decode_message(fid, data, decode_choices=False)
            seq = int(sig["Ctrl_Seq"])
            if int(sig["Ctrl_Command"]) == cl.Command.RESET:
                lengths = [sig[f"Ctrl_Length_{a}"] for a in cl.ACTUATORS] if sig["Ctrl_UseLengths"] else None
                timeout = int(sig["Ctrl_CmdTimeout"])
                ref.reset(cl.Variant(sig["Ctrl_Variant"]).name.lower(),
                          cl.Integrator(sig["Ctrl_Integrator"]).name.lower(),
                          sig["Ctrl_StepSize"] / 1e9, int(sig["Ctrl_Pose"]), lengths=lengths,
                          hold_length=bool(sig["Ctrl_ActInit"]), disable=int(sig["Ctrl_Disable"]),
                          cmd_timeout_ms=None if timeout in (0, cl.CMD_TIMEOUT_NONE) else timeout)
                ref._seq[cl.CONTROL] = ref._accepted[cl.CONTROL] = seq
                answer = True
            else:   # accepted (a new counter) or refused (a FAULT only)
                before = ref._accepted[cl.CONTROL]
                ref.send_raw(msg)
                answer = ref._accepted[cl.CONTROL] != before
        else:
            ref.send_raw(msg)
        for f in ref.faults():
            self.send("FAULT", {"Fault_Code": int(f.code), "Fault_FrameId": f.frame_id,
                                "Fault_FrameLen": f.frame_len, "Fault_Seq": f.seq,
                                "Fault_Detail": f.detail, "Fault_Value": f.value,
                                "Fault_StepCount": f.step_count, "Fault_Count": f.count})
        if answer:
            self.send_state(ref._state())

    def send_state(self, s):
        self.tick += 1
        sig = dict(zip(cl.Q_SIGNALS, s.q)) | dict(zip(cl.QD_SIGNALS, s.qd)) | \
            dict(zip(cl.REACTION_SIGNALS, s.reactions.reshape(-1)))
        for a, name in enumerate(cl.ACTUATORS):
            sig |= {f"Act_{name}_length": s.lengths[a], f"Act_{name}_rate": s.rates[a],
                    f"Act_{name}_force": s.forces[a]}
        sig |= {"St_Time": s.t, "St_StepCount": s.step_count, "St_Residual": s.residual,
                "St_Condition": s.condition, "St_Status": int(s.status), "St_State": int(s.state),
                "St_LastFault": int(s.last_fault), "St_Variant": int(s.variant),
                "St_Integrator": int(s.integrator), "St_ActSeq": s.act_seq, "St_CtrlSeq": s.ctrl_seq,
                "St_StepSize": s.step_ns}
        for fid, tick in cl._TICK_SIGNAL.items():
            if fid == cl.ST_CONTACT:
                continue
            m = self.db.get_message_by_frame_id(fid)
            self.send(m.name, {n.name: sig.get(n.name, 0) for n in m.signals} | {tick: self.tick})


@pytest.fixture
def session(tmp_path):
    """The bad_input scene (commands, loads, every kind of refused frame, a silence and the
    command timeout) recorded live through HilLink on a virtual bus, logged in three formats at
    once... one writer per session: so three sessions, one per format."""
    scene = load_scene("bad_input", ROOT)

    def run(trace: Path):
        channel = f"legsim-trace-{random.random()}"
        peer = ReferencePeer(channel)
        peer.start()
        try:
            with HilLink(bus=can.Bus(interface="virtual", channel=channel, receive_own_messages=False),
                         dbc=DBC, timeout=5.0) as link:
                # HEARTBEATs queued before the session: the one recorded is the next (live and replayed)
                time.sleep(0.25)
                with link.trace(trace) as writer:
                    rec = record(scene, link, progress=False)
                link.bus.shutdown()
        finally:
            peer.stop_flag.set()
            peer.join()
            peer.bus.shutdown()
        assert peer.error is None, peer.error
        assert writer.frames > 0
        return rec
    return scene, run


def _same_samples(a: dict, b: dict):
    assert len(a["samples"]) == len(b["samples"]) > 10
    for sa, sb in zip(a["samples"], b["samples"]):
        for key in ("t", "step", "q", "qd", "lengths", "rates", "forces", "reactions", "status",
                    "ctrl_seq", "act_seq", "faults", "state", "last_fault"):
            assert json.dumps(sa[key]) == json.dumps(sb[key]), (key, sa["step"])   # NaN == NaN
    for key in ("commands", "loads", "injections", "errors", "complete", "late_faults",
                "initial_lengths", "heartbeat"):
        assert json.dumps(a[key]) == json.dumps(b[key]), key


@pytest.mark.parametrize("suffix", [".log", ".asc", ".blf"])
def test_a_session_replays_from_its_trace_to_the_same_samples_and_verdict(session, tmp_path, suffix):
    scene, run = session
    trace = tmp_path / f"session{suffix}"
    live = run(trace)
    assert live["complete"], live["errors"]
    # every kind of refusal came over the bus and is in the trace
    codes = {f["code"] for s in live["samples"] for f in s["faults"]}
    assert {"NOT_FINITE", "OUT_OF_RANGE", "STALE_SEQ", "UNKNOWN_ID", "BAD_LENGTH", "CMD_TIMEOUT"} <= codes

    frames = read_trace(trace)
    sent = [m for m in frames if not m.is_rx]
    got = [m for m in frames if m.is_rx]
    # the bench's frames: one RESET and one STEP per boundary, the commands, loads, injections
    assert sum(m.arbitration_id == cl.CONTROL for m in sent) == len(live["samples"]) + 1  # + the stale STEP
    assert any(m.arbitration_id == 0x123 for m in sent) and any(len(m.data) == 32 for m in sent)
    assert all(m.is_fd for m in frames)
    assert sum(m.arbitration_id == cl.ST_STATUS for m in got) == len(live["samples"])
    ts = [m.timestamp for m in frames]
    assert all(b >= a for a, b in zip(ts, ts[1:]))

    replayed = replay_trace(trace, scene, dbc=DBC)
    _same_samples(live, replayed)
    assert live["heartbeat"] is not None
    assert replayed["trace"] == str(trace)
    ev_live, ev_replay = evaluate(live, ROOT), evaluate(replayed, ROOT)
    assert ev_live.passed and ev_replay.passed
    assert len(ev_live.results) > 10
    assert json.dumps([(r.name, r.passed, r.error, r.where, r.got) for r in ev_live.results]) == \
        json.dumps([(r.name, r.passed, r.error, r.where, r.got) for r in ev_replay.results])
    # the replay's clock is the trace's: the session's length, not the replay's
    assert replayed["wall_time_s"] == pytest.approx(ts[-1] - ts[0], abs=0.2)


def test_check_log_replays_a_trace_beside_its_recording(session, tmp_path, capsys):
    scene, run = session
    out = tmp_path / "bad_input"
    live = run(out / "trace.blf")
    (out / "recording.json").write_text(json.dumps(live))
    rc = cli.main(["check", "--no-plots", "--log", str(out / "trace.blf")])
    text = capsys.readouterr().out
    assert rc == 0, text
    assert "replayed" in text and "ALL PASS" in text
    rec = json.loads((out / "replay" / "recording.json").read_text())
    _same_samples(live, rec)
    # a scene given explicitly, outputs elsewhere
    rc = cli.main(["check", "--no-plots", "--log", str(out / "trace.blf"), "--scene", "bad_input",
                   "--out", str(tmp_path / "elsewhere")])
    assert rc == 0 and (tmp_path / "elsewhere" / "bad_input" / "samples.csv").is_file()


def test_a_trace_of_another_scene_is_refused(session, tmp_path):
    scene, run = session
    trace = tmp_path / "t.log"
    run(trace)
    with pytest.raises(TraceError, match="another scene"):
        replay_trace(trace, load_scene("free_fall", ROOT), dbc=DBC)


@pytest.fixture
def candump(session, tmp_path):
    scene, run = session
    trace = tmp_path / "t.log"
    run(trace)
    return scene, trace


def test_a_trace_cut_short_fails_with_the_reason(candump, tmp_path):
    scene, trace = candump
    lines = trace.read_text().splitlines(keepends=True)
    steps = [i for i, line in enumerate(lines) if " 080##" in line and line.endswith(" T\n")]
    cut = tmp_path / "cut.log"
    # right after a STEP: the bench waits for an answer the trace does not have
    cut.write_text("".join(lines[: steps[len(steps) // 2] + 1]))
    rec = replay_trace(cut, scene, dbc=DBC)
    assert not rec["complete"]
    assert any("ends while the bench waits" in e["error"] for e in rec["errors"])
    assert not evaluate(rec, ROOT).passed
    # after the answer: the bench goes on sending what the trace has not
    cut.write_text("".join(lines[: steps[len(steps) // 2] + 7]))
    with pytest.raises(TraceError, match="after the trace's last sent frame .* cut short"):
        replay_trace(cut, scene, dbc=DBC)
    # cut inside a line: python-can cannot parse it
    bad = tmp_path / "bad.log"
    bad.write_text("".join(lines[:20]) + lines[20][:25] + "\n")
    with pytest.raises(TraceError, match="not a readable candump log trace"):
        replay_trace(bad, scene, dbc=DBC)


def test_corrupt_traces_give_clear_errors(candump, tmp_path, capsys):
    scene, trace = candump
    blf = tmp_path / "t.blf"
    with can.Logger(str(blf)) as w:
        for m in read_trace(trace):
            w(m)
    data = blf.read_bytes()
    (tmp_path / "trunc.blf").write_bytes(data[: len(data) // 2])
    (tmp_path / "junk.blf").write_bytes(bytes(range(256)) * 4)
    (tmp_path / "empty.asc").write_text("")
    for name, match in (("trunc.blf", "cut short"),
                        ("junk.blf", "not a readable Vector BLF trace"),
                        ("empty.asc", "none sent by the bench"),
                        ("missing.log", "no such trace")):
        with pytest.raises(TraceError, match=match):
            TraceBus(tmp_path / name)
    with pytest.raises(TraceError, match="named by its format"):
        read_trace(tmp_path / "t.txt")
    # the command line: exit 2 with the message
    rc = cli.main(["check", "--no-plots", "--log", str(tmp_path / "junk.blf"), "--scene", "bad_input"])
    assert rc == 2 and "not a readable Vector BLF trace" in capsys.readouterr().err


def test_record_writes_a_trace_beside_each_recording_by_default(tmp_path, capsys):
    """`record` on a bus nobody answers still logs what it sent (the RESET), beside recording.json;
    --log with several scenes needs {scene}; an unknown suffix is refused before the bus opens."""
    ch = f"nobody-{random.random()}"
    rc = cli.main(["record", "--interface", "virtual", "--channel", ch, "--timeout", "0.2",
                   "--no-progress", "--out", str(tmp_path), "free_fall"])
    assert rc == 1
    frames = read_trace(tmp_path / "free_fall" / "trace.log")
    assert [m.arbitration_id for m in frames if not m.is_rx] == [cl.CONTROL]
    assert "trace: 1 frames" in capsys.readouterr().out
    assert json.loads((tmp_path / "free_fall" / "recording.json").read_text())["trace"] == \
        str(tmp_path / "free_fall" / "trace.log")
    rc = cli.main(["record", "--interface", "virtual", "--channel", ch, "--log", str(tmp_path / "x.blf"),
                   "free_fall", "upper_step_50N"])
    assert rc == 2 and "{scene}" in capsys.readouterr().err
    rc = cli.main(["record", "--interface", "virtual", "--channel", ch, "--log", str(tmp_path / "x.txt"),
                   "free_fall"])
    assert rc == 2 and "named by its format" in capsys.readouterr().err


def test_sniff_logs_the_bus_beside_the_bench(tmp_path, capsys):
    """--sniff: a second listener on the bus logs every frame (here the bench's RESET and a
    stranger's frame the bench's own trace filters out), as candump would."""
    ch = f"sniffed-{random.random()}"
    stranger = can.Bus(interface="virtual", channel=ch)
    done = threading.Event()

    def chatter():   # another node's frame every 50 ms while the bench runs
        while not done.wait(0.05):
            stranger.send(can.Message(arbitration_id=0x7AB, data=b"\x01\x02", is_extended_id=False))
    later = threading.Thread(target=chatter)
    later.start()
    rc = cli.main(["record", "--interface", "virtual", "--channel", ch, "--timeout", "0.3",
                   "--no-progress", "--out", str(tmp_path), "--sniff", str(tmp_path / "bus.asc"),
                   "free_fall"])
    done.set()
    later.join()
    stranger.shutdown()
    assert rc == 1 and "sniffer: every frame on the bus" in capsys.readouterr().out
    with can.LogReader(str(tmp_path / "bus.asc")) as r:
        ids = [m.arbitration_id for m in r]
    assert cl.CONTROL in ids and 0x7AB in ids
    assert 0x7AB not in [m.arbitration_id for m in read_trace(tmp_path / "free_fall" / "trace.log")]


def test_check_log_waits_as_long_as_the_live_session(tmp_path, capsys):
    """The live link's answer timeout is in the recording; `check --log` replays with it (no
    --timeout given): the RESET nobody answered times out after the live 0.3 s, not 5 s."""
    ch = f"nobody-{random.random()}"
    rc = cli.main(["record", "--interface", "virtual", "--channel", ch, "--timeout", "0.3",
                   "--no-progress", "--out", str(tmp_path), "free_fall"])
    assert rc == 1
    live = json.loads((tmp_path / "free_fall" / "recording.json").read_text())
    assert live["timeout_s"] == 0.3
    assert any("within 0.3 s" in e["error"] for e in live["errors"])
    capsys.readouterr()
    rc = cli.main(["check", "--no-plots", "--log", str(tmp_path / "free_fall" / "trace.log")])
    assert rc == 1 and "replayed" in capsys.readouterr().out
    replayed = json.loads((tmp_path / "free_fall" / "replay" / "recording.json").read_text())
    assert replayed["timeout_s"] == 0.3
    assert replayed["errors"][0] == live["errors"][0]
    assert replayed["wall_time_s"] == pytest.approx(live["wall_time_s"], abs=0.1)
    # --timeout still overrides it
    rc = cli.main(["check", "--no-plots", "--log", str(tmp_path / "free_fall" / "trace.log"),
                   "--timeout", "0.7", "--out", str(tmp_path / "longer")])
    longer = json.loads((tmp_path / "longer" / "free_fall" / "recording.json").read_text())
    assert longer["timeout_s"] == 0.7 and any("within 0.7 s" in e["error"] for e in longer["errors"])
