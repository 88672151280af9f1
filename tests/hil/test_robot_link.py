"""The bench's decoding of the robot's frames (can_link), against frames encoded from the
DBC and sent on python-can's 'virtual' interface. Runs anywhere (no vcan)."""
from __future__ import annotations

import random

import can
import numpy as np
import pytest

from legsim_bench.hil import can_link as cl
from legsim_bench.hil.can_link import HilLink


@pytest.fixture
def pair():
    channel = f"robot-{random.random()}"
    link = HilLink(bus=can.Bus(interface="virtual", channel=channel, receive_own_messages=False),
                   timeout=2.0)
    sim = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
    yield link, sim
    link.close()
    sim.shutdown()


# leg 0's watchdog armed, leg 1's tripped (each leg node's own St_Status)
LEG_STATUS = (cl.Status.ASSEMBLED | cl.Status.CMD_WATCHDOG, cl.Status.ASSEMBLED | cl.Status.SAFE_STATE)


def _send(link, sim, name, values):
    sim.send(link.encode(name, values))


def _robot_sample(link, sim, tick, rng, order=None):
    """One robot sample with random float32 values; returns what was sent (q, qd, ...)."""
    f32 = lambda a: a.astype(np.float32).astype(float)
    q, qd = f32(rng.uniform(-1, 1, 39)), f32(rng.uniform(-1, 1, 39))
    lengths, forces = f32(rng.uniform(0.4, 0.7, 4)), f32(rng.uniform(-100, 100, 4))
    reactions = f32(rng.uniform(-500, 500, (16, 3)))
    frames = [("ST_BOX", {"Box_Tick": tick, **dict(zip(["Box_x", "Box_y", "Box_phi"], q[:3])),
                          **dict(zip(["Box_vx", "Box_vy", "Box_omega"], qd[:3]))})]
    statuses = []
    for k, sfx in enumerate(("", "_L1")):
        o = 3 + 18 * k
        pos = {"Pos_Tick": tick, **{n: q[o + i] for i, n in enumerate(cl.Q_SIGNALS[:15])}}
        vel = {"Vel_Tick": tick, **{n: qd[o + i] for i, n in enumerate(cl.QD_SIGNALS[:15])}}
        act = {"Act_Tick": tick, **{n: q[o + 15 + i] for i, n in enumerate(cl.Q_SIGNALS[15:])},
               **{n: qd[o + 15 + i] for i, n in enumerate(cl.QD_SIGNALS[15:])}}
        for a, name in enumerate(cl.ACTUATORS):
            act[f"Act_{name}_length"] = lengths[2 * k + a]
            act[f"Act_{name}_force"] = forces[2 * k + a]
        r = reactions[8 * k:8 * k + 8].reshape(-1)
        ra = {"RA_Tick": tick, **{n: r[i] for i, n in enumerate(cl.REACTION_SIGNALS[:15])}}
        rb = {"RB_Tick": tick, **{n: r[15 + i] for i, n in enumerate(cl.REACTION_SIGNALS[15:])}}
        ct = {"Ct_Tick": tick, "Ct_State": 1, "Ct_Normal": 150.0 + k, "Ct_Tangential": -20.0 + k,
              "Ct_X": 0.633 * (1 - 2 * k), "Ct_Events": 0b100010 * k}   # leg 1: TOUCHDOWN, AMBIGUOUS
        frames += [(f"ST_POS{sfx}", pos), (f"ST_VEL{sfx}", vel), (f"ST_ACT{sfx}", act),
                   (f"ST_REACT_A{sfx}", ra), (f"ST_REACT_B{sfx}", rb), (f"ST_CONTACT{sfx}", ct)]
        statuses.append((f"ST_STATUS{sfx}", {"St_Tick": tick, "St_StepCount": tick, "St_Time": tick * 1e-3,
                                             "St_State": 1, "St_ActSeq": 3 + k, "St_CtrlSeq": 7,
                                             "St_StrokeMask": k + 1,
                                             "St_Status": int(LEG_STATUS[k])}))
    for name, values in frames + statuses:
        _send(link, sim, name, values)
    return q, qd, lengths, forces, reactions


def test_a_robot_sample_in_the_cores_order(pair):
    link, sim = pair
    rng = np.random.default_rng(9)
    q, qd, lengths, forces, reactions = _robot_sample(link, sim, 42, rng)
    s = link.read_state()
    assert s.legs == 2 and s.step_count == 42 and s.ctrl_seq == 7
    assert np.array_equal(s.q, q) and np.array_equal(s.qd, qd)        # box, leg 0, leg 1
    assert np.array_equal(s.box_q, q[:3]) and s.body_q.shape == (13, 3)
    assert np.array_equal(s.lengths, lengths) and np.array_equal(s.forces, forces)
    assert np.array_equal(s.reactions, reactions)
    assert s.act_seqs == (3, 4) and s.stroke_mask == 1 | (2 << 2)
    # each leg node's own status bits (leg 1's watchdog tripped, leg 0's not)
    assert s.statuses == LEG_STATUS and s.status == LEG_STATUS[0]
    assert [c.state for c in s.contacts] == [cl.ContactState.STUCK] * 2
    assert [c.normal for c in s.contacts] == [150.0, 151.0]
    assert [c.tangential for c in s.contacts] == [-20.0, -19.0]
    assert [c.events for c in s.contacts] == [cl.ContactEvent(0),
                                               cl.ContactEvent.TOUCHDOWN | cl.ContactEvent.CONTACT_AMBIGUOUS]


def test_a_robot_sample_waits_for_every_legs_status(pair):
    link, sim = pair
    rng = np.random.default_rng(1)
    _robot_sample(link, sim, 5, rng)
    link.read_state()
    # a sample whose leg-1 status never comes is never complete
    _send(link, sim, "ST_BOX", {"Box_Tick": 6})
    for name in ("ST_POS", "ST_VEL", "ST_ACT", "ST_REACT_A", "ST_REACT_B", "ST_CONTACT"):
        _send(link, sim, name, {})
    _send(link, sim, "ST_STATUS", {"St_Tick": 6, "St_State": 1})
    link.poll(0.2)
    assert not link._states
    # the next whole sample completes (the broken one is dropped)
    _robot_sample(link, sim, 7, rng)
    assert link.read_state().step_count == 7 and not link._states


def test_robot_commands_go_to_each_legs_frame(pair):
    link, sim = pair
    link.command_force(2, 12.5)        # actuator 2 = leg 1's upper
    link.command_length(1, 0.55)       # leg 0's lower
    link.set_load(0, 1.0, -2.0, leg=1)
    got = [sim.recv(1.0) for _ in range(3)]
    assert [m.arbitration_id for m in got] == [cl.ACT_CMD_L1, cl.ACT_CMD, cl.LOAD_CMD_L1]
    a = link.db.decode_message(cl.ACT_CMD_L1, got[0].data, decode_choices=False)
    assert a["Act_Mode_upper"] == cl.ActMode.FORCE and a["Act_Setpoint_upper"] == 12.5
    assert a["Act_Mode_lower"] == cl.ActMode.KEEP and a["Act_Seq"] == 1
    b = link.db.decode_message(cl.ACT_CMD, got[1].data, decode_choices=False)
    assert b["Act_Mode_lower"] == cl.ActMode.LENGTH and b["Act_Seq"] == 1   # its own count
