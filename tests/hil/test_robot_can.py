"""The two-leg robot over SocketCAN (needs vcan0: tools/with-vcan): hil_sim --robot answers
with each leg's frames at its ids, the feet's ST_CONTACT and the box's ST_BOX; the bench
drives the Fig. 7 Scene A (design section 7) and checks box pose, contact states and ground
forces against its own RobotModel within the float32 signals' resolution; bad leg-1 frames
get a FAULT and change nothing; a one-leg hil_sim refuses leg-1 commands.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from legsim_bench import can_link as cl
from legsim_bench.robot_can import run_scene_a, scene_a_reference


@pytest.fixture(scope="module")
def scene_a():
    return scene_a_reference(0.1)   # the reference's run (~2 s), shared


def test_scene_a_over_can_matches_the_reference(start_hil, scene_a):
    hil = start_hil("--robot").link
    res = run_scene_a(hil, reference=scene_a)
    print(res.report())
    assert res.ok, res.failures
    e = res.end
    assert e.legs == 2 and e.q.shape == (39,) and e.reactions.shape == (16, 3)
    assert len(e.contacts) == 2 and e.act_seqs == (1, 1)
    # the figures of design section 7 (box +0.58 mm, +4.05 mm, +0.01634 rad; right phi3)
    moved = e.box_q - res.start.box_q
    assert abs(moved[0] - 0.58e-3) < 0.01e-3 and abs(moved[1] - 4.05e-3) < 0.01e-3
    assert abs(moved[2] - 0.01634) < 1e-5 and abs(e.q[3 * 3 + 2] - 1.07133) < 1e-5
    # the feet carry the robot: N of both feet near its weight (20 kg box + 2 x 6.2 kg legs)
    assert 300.0 < sum(c.normal for c in e.contacts) < 330.0
    # the errors are at float32 level, not at the solver's (the solver agrees far better)
    assert res.errors["box q (m, rad)"] < 1e-6 and res.errors["ground N (N)"] < 1e-4


def test_bad_leg1_frames_fault_and_change_nothing(start_hil):
    hil = start_hil("--robot").link
    hil.reset(integrator="rk4", hold_length=True, cmd_timeout_ms=0)
    before = hil.step(5)
    # NaN setpoint in ACT_CMD_L1, a classic (8-byte) ACT_CMD_L1, a leg-1 force above max_force
    nan = hil.encode("ACT_CMD_L1", {"Act_Seq": 1, "Act_Mode_upper": 1,
                                    "Act_Setpoint_upper": math.nan}, strict=False)
    hil.send_raw(nan)
    f = hil.wait_fault(code=cl.FaultCode.NOT_FINITE)
    assert f.frame_id == cl.ACT_CMD_L1 and f.signal == "Act_Setpoint_upper"
    classic = hil.encode("ACT_CMD_L1", {"Act_Seq": 2, "Act_Mode_upper": 1, "Act_Setpoint_upper": 1.0})
    classic.is_fd, classic.data = False, classic.data[:8]
    classic.dlc = 8
    hil.send_raw(classic)
    assert hil.wait_fault(code=cl.FaultCode.BAD_LENGTH).frame_id == cl.ACT_CMD_L1
    hil.command((cl.ActMode.FORCE, 2000.0), None, leg=1)
    f = hil.wait_fault(code=cl.FaultCode.OUT_OF_RANGE)
    assert f.frame_id == cl.ACT_CMD_L1 and f.signal == "Act_Setpoint_upper"
    after = hil.step(5)
    # nothing changed: a fresh run of the same 10 steps lands on the same state, bit for bit
    hil.reset(integrator="rk4", hold_length=True, cmd_timeout_ms=0)
    hil.step(5)
    clean = hil.step(5)
    assert np.array_equal(after.q, clean.q) and np.array_equal(after.qd, clean.qd)
    assert [c.normal for c in after.contacts] == [c.normal for c in clean.contacts]
    assert after.act_seqs == (0, 0) and before.step_count == 5
    assert cl.Status.FAULT in after.status


def test_one_leg_hil_sim_refuses_leg1_commands(start_hil):
    hil = start_hil().link
    s = hil.reset()
    assert s.legs == 1 and s.q.shape == (18,) and not s.contacts
    hil.command((cl.ActMode.FORCE, 10.0), None, leg=1)
    f = hil.wait_fault(code=cl.FaultCode.UNKNOWN_ID)
    assert f.frame_id == cl.ACT_CMD_L1
