"""The two-leg robot over SocketCAN (needs vcan0: tools/with-vcan): what the robot's scenes
(tests/hil_scenes, every scenes/robot_*.toml dynamics scene over CAN) do not cover: bad frames
to either leg's node get a FAULT, change nothing and the heartbeat goes on; the feet's events
(Ct_Events) arrive decoded, each on its own foot, none lost between samples; the RESET's feet
options (Ctrl_FreeContacts); a one-leg hil_sim refuses leg-1 commands; each leg node has its
own command watchdog (a silent leg trips alone, in lockstep and in real time).
"""
from __future__ import annotations

import math
import time

import numpy as np
import pytest

from legsim_bench.hil import can_link as cl

CE = cl.ContactEvent


def test_bad_frames_to_either_leg_fault_change_nothing_and_the_heartbeat_goes_on(start_hil):
    hil = start_hil("--robot").link
    hil.reset(integrator="rk4", hold_length=True, cmd_timeout_ms=0)
    before = hil.step(5)
    hb0 = hil.heartbeat()
    bad = [  # (frame, what it must raise, its frame id, the signal named)
        (hil.encode("ACT_CMD", {"Act_Seq": 1, "Act_Mode_lower": 1, "Act_Setpoint_lower": math.inf}, strict=False),
         cl.FaultCode.NOT_FINITE, cl.ACT_CMD, "Act_Setpoint_lower"),
        (hil.encode("ACT_CMD_L1", {"Act_Seq": 1, "Act_Mode_upper": 1, "Act_Setpoint_upper": math.nan},
                    strict=False), cl.FaultCode.NOT_FINITE, cl.ACT_CMD_L1, "Act_Setpoint_upper"),
        (hil.encode("LOAD_CMD", {"Load_Seq": 1, "Load_Index": 1, "Load_Value1": 1.0}),
         cl.FaultCode.OUT_OF_RANGE, cl.LOAD_CMD, "Load_Index"),     # leg 0 has one force element
        (hil.encode("LOAD_CMD_L1", {"Load_Seq": 1, "Load_Index": 0, "Load_Value2": math.nan}, strict=False),
         cl.FaultCode.NOT_FINITE, cl.LOAD_CMD_L1, "Load_Value2"),
        (hil.encode("ACT_CMD", {"Act_Seq": 2, "Act_Mode_upper": 2, "Act_Setpoint_upper": 0.95}),
         cl.FaultCode.OUT_OF_RANGE, cl.ACT_CMD, "Act_Setpoint_upper"),  # out of the stroke
    ]
    classic = hil.encode("ACT_CMD_L1", {"Act_Seq": 2, "Act_Mode_upper": 1, "Act_Setpoint_upper": 1.0})
    classic.is_fd, classic.data, classic.dlc = False, classic.data[:8], 8
    for msg, code, fid, signal in bad:
        hil.send_raw(msg)
        f = hil.wait_fault(code=code)
        assert (f.frame_id, f.signal) == (fid, signal), str(f)
    hil.send_raw(classic)
    assert hil.wait_fault(code=cl.FaultCode.BAD_LENGTH).frame_id == cl.ACT_CMD_L1
    hil.command((cl.ActMode.FORCE, 2000.0), None, leg=1)       # above max_force
    f = hil.wait_fault(code=cl.FaultCode.OUT_OF_RANGE)
    assert f.frame_id == cl.ACT_CMD_L1 and f.signal == "Act_Setpoint_upper"
    # the heartbeat goes on, counting them, in lockstep
    hb = hil.heartbeat()
    assert hb.counter > hb0.counter and hb.state == cl.SimState.LOCKSTEP
    assert hb.fault_count - hb0.fault_count == len(bad) + 2 and hb.rx_rejected >= len(bad) + 2
    after = hil.step(5)
    # nothing changed: a fresh run of the same 10 steps lands on the same state, bit for bit
    hil.reset(integrator="rk4", hold_length=True, cmd_timeout_ms=0)
    hil.step(5)
    clean = hil.step(5)
    assert np.array_equal(after.q, clean.q) and np.array_equal(after.qd, clean.qd)
    assert [c.normal for c in after.contacts] == [c.normal for c in clean.contacts]
    assert after.act_seqs == (0, 0) and before.step_count == 5
    assert cl.Status.FAULT in after.status and cl.Status.FAULT not in clean.status


def test_each_foot_has_its_own_events_and_none_is_lost_between_samples(start_hil):
    """The left foot free at t = 0 (Ctrl_FreeContacts): the robot leans onto it and it touches
    down. Sampled every step or once over the same 60 steps, the left foot's Ct_Events hold
    TOUCHDOWN (the union of the per-step events: none lost), the right foot's none."""
    hil = start_hil("--robot").link
    s0 = hil.reset(integrator="rk4", hold_length=True, cmd_timeout_ms=0, free_contacts=0b10)
    assert [c.state for c in s0.contacts] == [cl.ContactState.STUCK, cl.ContactState.FREE]
    assert [c.events for c in s0.contacts] == [CE(0), CE(0)]
    per_step = [CE(0), CE(0)]
    states = []
    for _ in range(60):
        s = hil.step(1)
        states.append(s.contacts[1].state)
        for k in range(2):
            per_step[k] |= s.contacts[k].events
    hil.reset(integrator="rk4", hold_length=True, cmd_timeout_ms=0, free_contacts=0b10)
    once = hil.step(60)
    assert [c.events for c in once.contacts] == per_step
    assert CE.TOUCHDOWN in once.contacts[1].events and once.contacts[0].events == CE(0)
    assert states[-1] == cl.ContactState.STUCK   # it landed (at the first step) and stays


def test_one_leg_hil_sim_refuses_leg1_commands_and_the_feet_options(start_hil):
    hil = start_hil().link
    s = hil.reset()
    assert s.legs == 1 and s.q.shape == (18,) and not s.contacts
    hil.command((cl.ActMode.FORCE, 10.0), None, leg=1)
    f = hil.wait_fault(code=cl.FaultCode.UNKNOWN_ID)
    assert f.frame_id == cl.ACT_CMD_L1
    with pytest.raises(cl.HilFault) as e:
        hil.reset(contact_law="paper")
    assert e.value.fault.code == cl.FaultCode.OUT_OF_RANGE and e.value.fault.signal == "Ctrl_ContactLaw"


def _hold_command(hil, s, leg):
    """Leg's two servos hold the lengths of sample s; returns the ACT_CMD's counter."""
    return hil.command((cl.ActMode.LENGTH, float(s.lengths[2 * leg])),
                       (cl.ActMode.LENGTH, float(s.lengths[2 * leg + 1])), leg=leg)


def test_each_leg_node_has_its_own_command_watchdog_in_lockstep(start_hil):
    """hil_sim's default timeout (100 ms = 100 steps of 1 ms), zero force. Leg 0 is commanded
    every 50 steps, leg 1 once at step 0: leg 1 trips alone at step 100 (FAULT CMD_TIMEOUT
    naming ACT_CMD_L1 and its counter, SAFE_STATE in its own ST_STATUS, its actuators at zero
    force) while leg 0 keeps its servo command and its armed watchdog; the heartbeat goes on
    (its bits: any leg's). Leg 0, silent in turn, trips at its own time; leg 1's next command
    leaves its safe state."""
    S = cl.Status
    hil = start_hil("--robot").link
    s0 = hil.reset(integrator="rk4", hold_length=True)
    _hold_command(hil, s0, 0)
    seq1 = _hold_command(hil, s0, 1)
    s = hil.step(50)
    assert not s.faults and all(S.CMD_WATCHDOG in st for st in s.statuses)
    _hold_command(hil, s0, 0)
    s = hil.step(50)                         # step 100: exactly leg 1's timeout, still fine
    assert not s.faults and not any(S.SAFE_STATE in st for st in s.statuses)
    seq0 = _hold_command(hil, s0, 0)
    hb0 = hil.heartbeat()
    s = hil.step(50)                         # step 150
    assert [(f.code, f.frame_id, f.seq, f.step_count, f.detail) for f in s.faults] == \
        [(cl.FaultCode.CMD_TIMEOUT, cl.ACT_CMD_L1, seq1, 100, 100)]
    assert S.SAFE_STATE in s.statuses[1] and S.CMD_WATCHDOG not in s.statuses[1]
    assert S.SAFE_STATE not in s.statuses[0] and S.CMD_WATCHDOG in s.statuses[0]
    assert np.all(s.forces[2:] == 0.0)        # leg 1 at zero force
    assert np.all(np.abs(s.forces[:2]) > 1.0)  # leg 0's servos still hold (the robot's weight)
    hb = hil.heartbeat()
    assert hb.counter > hb0.counter and hb.state == cl.SimState.LOCKSTEP
    assert S.SAFE_STATE in hb.status and S.CMD_WATCHDOG in hb.status
    s = hil.step(100)                         # leg 0 silent since step 100: trips at 200
    assert [(f.code, f.frame_id, f.seq, f.step_count) for f in s.faults] == \
        [(cl.FaultCode.CMD_TIMEOUT, cl.ACT_CMD, seq0, 200)]
    assert all(S.SAFE_STATE in st for st in s.statuses)
    _hold_command(hil, s0, 1)                 # leg 1 commanded again: out of its safe state
    s = hil.step(1)
    assert not s.faults
    assert S.SAFE_STATE not in s.statuses[1] and S.CMD_WATCHDOG in s.statuses[1]
    assert S.SAFE_STATE in s.statuses[0]


def test_each_leg_node_has_its_own_command_watchdog_in_real_time(start_hil):
    """Real time at 1 kHz, timeout 100 ms: the bench keeps leg 0 alive (an ACT_CMD every
    10 ms) while leg 1, commanded once, stays silent: leg 1's watchdog trips, on hil_sim's own
    clock past its 100 ms (and within half a second: an emulated VM stalls); the heartbeat
    goes on with SAFE_STATE set. The bench's clock only paces the keep-alives."""
    S = cl.Status
    hil = start_hil("--robot").link
    s0 = hil.reset(integrator="rk4", hold_length=True, cmd_timeout_ms=100)
    hil.start_realtime(decimation=20)
    _hold_command(hil, s0, 0)
    seq1 = _hold_command(hil, s0, 1)
    tripped, end = [], time.monotonic() + 20.0
    leg1 = None
    while leg1 is None and time.monotonic() < end:
        hil.keepalive()                        # leg 0's ACT_CMD (modes KEEP)
        hil.poll(0.01)
        tripped += [f for f in hil.faults() if f.code == cl.FaultCode.CMD_TIMEOUT]
        leg1 = next((f for f in tripped if f.frame_id == cl.ACT_CMD_L1), None)
    hb = hil.heartbeat(timeout=5)
    hil.stop_realtime()
    assert leg1 is not None, f"leg 1's watchdog never tripped (timeouts seen: {tripped})"
    assert leg1.seq == seq1 and leg1.detail == 100 and 100.0 <= leg1.value < 600.0, str(leg1)
    assert hb.state == cl.SimState.REALTIME and S.SAFE_STATE in hb.status
