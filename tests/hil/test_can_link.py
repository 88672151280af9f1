"""can_link and the DBC without a kernel bus: encode/decode round trips, state assembly,
fault decoding, bus configuration, and the request/answer logic against a fake hil_sim on
python-can's 'virtual' interface. Runs anywhere (no vcan)."""
from __future__ import annotations

import math
import random
import struct
import threading

import can
import cantools
import numpy as np
import pytest

from legsim_bench.hil import can_link as cl
from legsim_bench.hil import hexapod_link as hx
from legsim_bench.hil.can_link import ActMode, FaultCode, HilFault, HilLink, SimState, Status


@pytest.fixture(scope="module")
def db():
    return cantools.database.load_file(str(cl.DBC_PATH), strict=True)


def test_every_frame_is_64_byte_fd_with_an_11_bit_id(db):
    names = {m.name: m.frame_id for m in db.messages}
    leg = {"FAULT": cl.FAULT, "CONTROL": cl.CONTROL, "ACT_CMD": cl.ACT_CMD,
           "LOAD_CMD": cl.LOAD_CMD, "ST_POS": cl.ST_POS, "ST_VEL": cl.ST_VEL,
           "ST_ACT": cl.ST_ACT, "ST_REACT_A": cl.ST_REACT_A,
           "ST_REACT_B": cl.ST_REACT_B, "ST_STATUS": cl.ST_STATUS,
           "HEARTBEAT": cl.HEARTBEAT}
    # the robot: leg 1's copies of the per-leg frames at + 0x20, the feet and the box
    per_leg = ("ACT_CMD", "LOAD_CMD", "ST_POS", "ST_VEL", "ST_ACT", "ST_REACT_A", "ST_REACT_B",
               "ST_STATUS")
    robot = {f"{n}_L1": leg[n] + 0x20 for n in per_leg}
    robot.update(ST_CONTACT=cl.ST_CONTACT, ST_CONTACT_L1=cl.ST_CONTACT + 0x20, ST_BOX=cl.ST_BOX,
                  START_CMD=cl.START_CMD)
    # the hexapod (hil_sim --hexapod): per leg its command, actuators and foot; the box
    hexapod = {f"HEX_{n}_H{k}": base + k for k in range(6)
               for n, base in (("CMD", hx.HEX_CMD), ("LEG", hx.HEX_LEG), ("FOOT", hx.HEX_FOOT))}
    hexapod.update(HEX_BOX_POSE=hx.HEX_BOX_POSE, HEX_BOX_VEL=hx.HEX_BOX_VEL)
    assert names == {**leg, **robot, **hexapod}
    for n in per_leg:   # the same signals at the same places
        a, b = db.get_message_by_name(n), db.get_message_by_name(n + "_L1")
        assert [(s.name, s.start, s.length, s.is_float, s.minimum, s.maximum) for s in a.signals] == \
            [(s.name, s.start, s.length, s.is_float, s.minimum, s.maximum) for s in b.signals]
        assert b.senders == (["BENCH"] if n.endswith("_CMD") else ["HIL_L1"])
    for m in db.messages:
        assert m.is_fd and m.length == 64 and not m.is_extended_frame and m.frame_id < 0x800
        assert m.senders in (["BENCH"], ["HIL"], ["HIL_L1"])
        assert m.comment, m.name
        for s in m.signals:
            assert s.comment, f"{m.name}.{s.name} has no comment"
            assert s.scale == 1 and s.offset == 0   # floats are IEEE, integers raw
            assert s.byte_order == "little_endian"


def test_state_signals_cover_the_leg(db):
    names = {s.name for m in db.messages for s in m.signals}
    for n in cl.Q_SIGNALS + cl.QD_SIGNALS + cl.REACTION_SIGNALS:
        assert n in names
        assert db.get_message_by_name(_msg_of(db, n)).get_signal_by_name(n).is_float
    assert len(cl.Q_SIGNALS) == 18 and len(cl.QD_SIGNALS) == 18 and len(cl.REACTION_SIGNALS) == 24
    assert db.get_message_by_name("ST_STATUS").get_signal_by_name("St_Time").length == 64


def _msg_of(db, signal):
    return next(m.name for m in db.messages if any(s.name == signal for s in m.signals))


def _random_values(msg, rng):
    out = {}
    for s in msg.signals:
        if s.is_float:
            lo, hi = max(s.minimum, -1e6), min(s.maximum, 1e6)
            out[s.name] = rng.uniform(lo, hi)
        else:
            out[s.name] = rng.randint(int(s.minimum), int(s.maximum))
    return out


@pytest.mark.parametrize("seed", range(20))
def test_round_trip_every_frame(db, seed):
    rng = random.Random(seed)
    for msg in db.messages:
        values = _random_values(msg, rng)
        data = msg.encode(values, strict=True)
        assert len(data) == 64
        back = msg.decode(data, decode_choices=False)
        for s in msg.signals:
            v = values[s.name]
            if s.is_float and s.length == 32:
                assert back[s.name] == struct.unpack("<f", struct.pack("<f", v))[0]
                assert abs(back[s.name] - v) <= 6e-8 * abs(v)  # the documented resolution
            else:
                assert back[s.name] == v, (msg.name, s.name)


def _sample_frames(db, state: dict, tick: int) -> list[can.Message]:
    """The six frames hil_sim sends for one sample, encoded with cantools."""
    sig = {}
    for i, n in enumerate(cl.Q_SIGNALS):
        sig[n] = state["q"][i]
    for i, n in enumerate(cl.QD_SIGNALS):
        sig[n] = state["qd"][i]
    for i, n in enumerate(cl.REACTION_SIGNALS):
        sig[n] = state["reactions"].flat[i]
    for a, name in enumerate(cl.ACTUATORS):
        sig[f"Act_{name}_length"] = state["lengths"][a]
        sig[f"Act_{name}_rate"] = state["rates"][a]
        sig[f"Act_{name}_force"] = state["forces"][a]
    sig.update(state.get("status_signals", {}))
    frames = []
    for fid, tick_name in ((cl.ST_POS, "Pos_Tick"), (cl.ST_VEL, "Vel_Tick"), (cl.ST_ACT, "Act_Tick"),
                           (cl.ST_REACT_A, "RA_Tick"), (cl.ST_REACT_B, "RB_Tick"),
                           (cl.ST_STATUS, "St_Tick")):
        msg = db.get_message_by_frame_id(fid)
        values = {s.name: sig.get(s.name, 0) for s in msg.signals}
        values[tick_name] = tick
        frames.append(can.Message(arbitration_id=fid, data=msg.encode(values), is_fd=True,
                                  is_extended_id=False))
    return frames


def _random_state(rng):
    return {"q": rng.uniform(-1, 1, 18), "qd": rng.uniform(-5, 5, 18),
            "lengths": rng.uniform(0.4, 0.7, 2), "rates": rng.uniform(-1, 1, 2),
            "forces": rng.uniform(-1500, 1500, 2), "reactions": rng.uniform(-2000, 2000, (8, 3))}


@pytest.fixture
def null_link():
    """A HilLink on a bus that drops what is sent to it and never receives."""
    bus = _NullBus()
    yield HilLink(bus=bus)
    bus.shutdown()


class _NullBus(can.BusABC):
    def __init__(self):
        super().__init__(channel="null")
        self.sent = []

    def send(self, msg, timeout=None):
        self.sent.append(msg)

    def _recv_internal(self, timeout):
        return None, False


def test_state_assembled_from_frames_as_float32(db, null_link):
    rng = np.random.default_rng(1)
    st = _random_state(rng)
    st["status_signals"] = {"St_Time": 0.123456789012345, "St_StepCount": 2**40 + 5,
                            "St_Status": int(Status.ASSEMBLED | Status.SAFE_STATE),
                            "St_State": 1, "St_ActSeq": 7, "St_CtrlSeq": 9,
                            "St_StepSize": 1000000, "St_Residual": 1e-11}
    link = null_link
    frames = _sample_frames(db, st, tick=(2**40 + 5) & 0xFFFFFFFF)
    # a heartbeat and a stray incomplete sample interleaved must not disturb it
    link._handle(_sample_frames(db, st, tick=3)[0])
    for f in frames[:3]:
        link._handle(f)
    link._handle(link.encode("HEARTBEAT", {"Hb_Counter": 4, "Hb_JitterP99": 12.0}))
    for f in frames[3:]:
        link._handle(f)
    s = link.read_state(timeout=0)
    f32 = lambda a: np.asarray(a, dtype=np.float32).astype(np.float64)  # noqa: E731
    assert np.array_equal(s.q, f32(st["q"])) and s.q.shape == (18,)
    assert np.array_equal(s.qd, f32(st["qd"]))
    assert np.array_equal(s.reactions, f32(st["reactions"])) and s.reactions.shape == (8, 3)
    assert np.array_equal(s.lengths, f32(st["lengths"]))
    assert np.array_equal(s.forces, f32(st["forces"]))
    assert s.t == 0.123456789012345 and s.step_count == 2**40 + 5   # exact
    assert s.status == Status.ASSEMBLED | Status.SAFE_STATE
    assert s.status_names == ["ASSEMBLED", "SAFE_STATE"]
    assert s.state == SimState.LOCKSTEP and s.act_seq == 7 and s.ctrl_seq == 9
    assert np.max(np.abs(s.q - st["q"])) <= 6e-8 * np.max(np.abs(st["q"]))
    assert link.last_heartbeat.counter == 4 and link.last_heartbeat.jitter_p99_us == 12.0
    assert not link._partial  # the stray sample was dropped


def test_fault_decoding_names_the_signal(db, null_link):
    link = null_link
    start = db.get_message_by_name("ACT_CMD").get_signal_by_name("Act_Setpoint_upper").start
    link._handle(link.encode("FAULT", {"Fault_Code": 4, "Fault_FrameId": cl.ACT_CMD,
                                       "Fault_FrameLen": 64, "Fault_Seq": 3,
                                       "Fault_Detail": start, "Fault_Value": 0.95}))
    f = link.wait_fault(timeout=0)
    assert f.code == FaultCode.OUT_OF_RANGE and f.signal == "Act_Setpoint_upper"
    assert f.seq == 3 and abs(f.value - 0.95) < 1e-7
    assert "OUT_OF_RANGE" in str(f) and "Act_Setpoint_upper" in str(f)


def test_encode_refuses_out_of_range_unless_raw(null_link):
    link = null_link
    with pytest.raises(Exception):
        link.encode("ACT_CMD", {"Act_Mode_upper": 7})
    msg = link.encode("ACT_CMD", {"Act_Mode_upper": 1, "Act_Setpoint_upper": math.nan}, strict=False)
    assert msg.is_fd and len(msg.data) == 64 and math.isnan(struct.unpack_from("<f", msg.data, 8)[0])


def test_commands_encode_modes_and_counters(db, null_link):
    link, bus = null_link, null_link.bus
    s1 = link.command_force("upper", 100.0)
    s2 = link.command_length(1, 0.5)
    link.keepalive()
    decoded = [db.decode_message(m.arbitration_id, m.data, decode_choices=False) for m in bus.sent]
    assert [d["Act_Seq"] for d in decoded] == [s1, s2, s2 + 1] == [1, 2, 3]
    assert decoded[0]["Act_Mode_upper"] == ActMode.FORCE and decoded[0]["Act_Mode_lower"] == ActMode.KEEP
    assert decoded[0]["Act_Setpoint_upper"] == 100.0
    assert decoded[1]["Act_Mode_lower"] == ActMode.LENGTH and decoded[1]["Act_Setpoint_lower"] == 0.5
    assert decoded[2]["Act_Mode_upper"] == decoded[2]["Act_Mode_lower"] == ActMode.KEEP


def test_bus_config_precedence(monkeypatch, tmp_path):
    monkeypatch.setenv("HOME", str(tmp_path))      # no ~/.canrc
    for k in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(k, raising=False)
    monkeypatch.setattr(can, "rc", {})
    cfg = cl.bus_config()
    assert cfg["interface"] == "socketcan" and cfg["channel"] == "vcan0" and cfg["fd"] is True
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", "bench")
    cfg = cl.bus_config()
    assert (cfg["interface"], cfg["channel"]) == ("virtual", "bench")
    cfg = cl.bus_config("socketcan", "vcan7")
    assert (cfg["interface"], cfg["channel"]) == ("socketcan", "vcan7")


# ---- request/answer against a fake hil_sim on the 'virtual' interface -------------------

class FakeHil(threading.Thread):
    """Answers CONTROL like hil_sim (a sample per accepted frame, FAULT STALE_SEQ on an old
    counter, FAULT NOT_FINITE on a NaN setpoint), with a heartbeat inside every sample."""

    def __init__(self, channel):
        super().__init__(daemon=True)
        self.db = cantools.database.load_file(str(cl.DBC_PATH))
        self.bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
        self.stop_flag = threading.Event()
        self.steps = 0
        self.last_ctrl = None
        self.act_seq = 0

    def sample(self, ctrl_seq):
        rng = np.random.default_rng(self.steps)
        st = _random_state(rng)
        st["status_signals"] = {"St_StepCount": self.steps, "St_Time": self.steps * 1e-3,
                                "St_CtrlSeq": ctrl_seq, "St_ActSeq": self.act_seq, "St_State": 1,
                                "St_StepSize": 1000000}
        frames = _sample_frames(self.db, st, self.steps)
        hb = self.db.get_message_by_name("HEARTBEAT")
        frames.insert(2, can.Message(arbitration_id=cl.HEARTBEAT, is_fd=True, is_extended_id=False,
                                     data=hb.encode({s.name: 0 for s in hb.signals})))
        for f in frames:
            self.bus.send(f)

    def fault(self, code, frame_id, seq, detail=0):
        m = self.db.get_message_by_name("FAULT")
        v = {s.name: 0 for s in m.signals}
        v.update(Fault_Code=code, Fault_FrameId=frame_id, Fault_Seq=seq, Fault_Detail=detail,
                 Fault_FrameLen=64)
        self.bus.send(can.Message(arbitration_id=cl.FAULT, is_fd=True, is_extended_id=False,
                                   data=m.encode(v)))

    def run(self):
        while not self.stop_flag.is_set():
            msg = self.bus.recv(0.05)
            if msg is None:
                continue
            sig = self.db.decode_message(msg.arbitration_id, msg.data, decode_choices=False)
            if msg.arbitration_id == cl.CONTROL:
                seq, cmd = sig["Ctrl_Seq"], sig["Ctrl_Command"]
                if cmd != 1 and self.last_ctrl is not None and seq <= self.last_ctrl:
                    self.fault(5, cl.CONTROL, seq, self.last_ctrl)
                    continue
                self.last_ctrl = seq
                if cmd == 1:
                    self.steps = 0
                elif cmd == 2:
                    self.steps += sig["Ctrl_NSteps"]
                self.sample(seq)
            elif msg.arbitration_id == cl.ACT_CMD:
                if math.isnan(sig["Act_Setpoint_upper"]):
                    self.fault(3, cl.ACT_CMD, sig["Act_Seq"], 64)
                else:
                    self.act_seq = sig["Act_Seq"]


@pytest.fixture
def fake():
    channel = f"legsim-test-{random.random()}"
    f = FakeHil(channel)
    f.start()
    link = HilLink(bus=can.Bus(interface="virtual", channel=channel, receive_own_messages=False),
                   timeout=2.0)
    yield f, link
    f.stop_flag.set()
    f.join()
    link.bus.shutdown()
    f.bus.shutdown()


def test_requests_get_their_answers(fake):
    sim, link = fake
    s0 = link.reset()
    assert s0.step_count == 0 and s0.ctrl_seq == 1
    link.command_length("upper", 0.6)
    s = link.step(25)
    assert s.step_count == 25 and s.t == pytest.approx(0.025) and s.act_seq == 1
    assert link.step(5).step_count == 30
    assert link.last_heartbeat is not None


def test_a_refused_request_raises_its_fault(fake):
    sim, link = fake
    link.reset()
    link._seq[cl.CONTROL] = 0   # the link forgets its counter: the next STEP is stale
    with pytest.raises(HilFault) as e:
        link.step(1)
    assert e.value.fault.code == FaultCode.STALE_SEQ and e.value.fault.frame_id == cl.CONTROL


def test_unanswered_faults_reach_the_next_state(fake):
    sim, link = fake
    link.reset()
    link.send_raw(link.encode("ACT_CMD", {"Act_Seq": 99, "Act_Mode_upper": 1,
                                          "Act_Setpoint_upper": math.nan}, strict=False))
    s = link.step(1)
    assert [f.code for f in s.faults] == [FaultCode.NOT_FINITE]
    assert s.faults[0].signal == "Act_Setpoint_upper"
    assert link.wait_fault(timeout=0).code == FaultCode.NOT_FINITE


def test_no_answer_is_an_error_not_a_hang():
    link = HilLink(bus=can.Bus(interface="virtual", channel=f"nobody-{random.random()}"),
                   timeout=0.2)
    with pytest.raises(cl.HilError, match="no answer to RESET"):
        link.reset()
    link.bus.shutdown()
