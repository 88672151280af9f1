"""The hexapod's node over SocketCAN (needs vcan0: tools/with-vcan): hil_sim --hexapod driven
by the tripod walk's set-points with the statics' feed-forward (legsim.Hexapod.gait_setpoints,
as Hexapod.walk sends them), one frame per leg and a STEP 1 per step, reports the box and the
feet of the in-process legsim.HexapodSim run on the same commands bit for bit (float64 on the
bus), and the legs' lengths and forces to float32; a bad frame is refused with a FAULT naming
its signal and changes nothing; a silent leg's watchdog trips alone, its safe action (its
servos hold their set-points without feed-forward) the in-process sim's on the same step; a
walk of mixed slots (some actuators pushed by the statics' force, the others servoed) is the
in-process HexapodSim.command_each's bit for bit, each slot's mode in its leg's frame.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from legsim_bench.hil import can_link as cl
from legsim_bench.hil.hexapod_link import HEX_CMD, HexapodLink, HexMode

from conftest import ROOT

legsim = pytest.importorskip("legsim")

GAIT = dict(period_s=1.2, duty=0.6, step_length_m=0.12, step_height_m=0.05, box_height_m=1.0)  # 1.0: a float32
H = 1e-3
LEGS = 6


@pytest.fixture(scope="module")
def hexapod():
    return legsim.Hexapod.from_toml(ROOT / "models" / "hexapod.toml")


def walk_command(hexapod, t):
    """Hexapod.walk's command at t: the gait's set-points, the statics of the planned pose on
    its planned stance as feed-forward."""
    sp = hexapod.gait_setpoints(t, **GAIT)
    at = {"box_m": [0.0, 0.0, GAIT["box_height_m"]], "box_quat": [1.0, 0.0, 0.0, 0.0],
          "rowing_rad": list(sp["rowing_rad"]), "length_m": sp["length_m"].tolist()}
    stance = [k for k in range(LEGS) if sp["stance"][k]]
    s = hexapod.statics(at, stance=stance)
    return sp, at, stance, s["actuator_force_n"], s["rowing_torque_nm"]


def start(start_hil, vcan, hexapod, cmd_timeout_ms=0):
    """hil_sim --hexapod at the walk's pose at t = 0, and the in-process sim there."""
    start_hil("--hexapod")
    hx = HexapodLink(interface="socketcan", channel=vcan)
    sp, pose, stance, ff, fm = walk_command(hexapod, 0.0)
    hx.command_pose(sp["length_m"], sp["rowing_rad"], ff, fm)   # held for the RESET's pose
    s = hx.reset(box_height=GAIT["box_height_m"], stance=sum(1 << k for k in stance), servo=True,
                 use_held=True, cmd_timeout_ms=cmd_timeout_ms)
    m = hexapod.sim(pose, stuck=stance)
    m.command_pose(sp["length_m"], sp["rowing_rad"], ff, fm)
    return hx, m, s


def same(s, ref) -> bool:
    """The node's sample is the in-process state: float64 exactly, float32 to its rounding."""
    f32 = np.float32
    return (np.array_equal(s.box_m, ref["box_m"]) and np.array_equal(s.box_quat, ref["box_quat"])
            and np.array_equal(s.box_velocity_mps, ref["box_velocity_mps"])
            and np.array_equal(s.box_omega_radps, ref["box_omega_radps"])
            and np.array_equal(s.foot_m, ref["foot_m"]) and np.array_equal(s.foot_force_n, ref["foot_force_n"])
            and s.foot_state == ref["foot_state"] and s.t_s == ref["t_s"]
            and np.array_equal(s.length_m, ref["length_m"].astype(f32))
            and np.array_equal(s.actuator_force_n, ref["actuator_force_n"].astype(f32))
            and np.array_equal(s.rowing_rad, ref["rowing_rad"].astype(f32)))


def test_the_walk_over_the_bus_is_the_in_process_walk(start_hil, vcan, hexapod):
    hx, m, s = start(start_hil, vcan, hexapod)
    try:
        assert same(s, m.state()) and s.step_count == 0 and s.modes == [(HexMode.SERVO,) * 3] * LEGS
        n = 200
        samples = [s]
        for i in range(n):
            sp, _, _, ff, fm = walk_command(hexapod, (i + 1) * H)
            hx.command_pose(sp["length_m"], sp["rowing_rad"], ff, fm)
            s = hx.step(1)
            m.command_pose(sp["length_m"], sp["rowing_rad"], ff, fm)
            m.step(1, h_s=H)
            assert same(s, m.state()), f"step {i + 1}"
            samples.append(s)
        assert not s.faults and s.step_count == n and all(k == n + 1 for k in s.leg_seq)
        # and Hexapod.walk itself, sampled every step, lands on the same numbers
        w = hexapod.walk(**GAIT, t_end_s=n * H, h_s=H, every=1)
        assert np.array_equal(np.array([x.box_m for x in samples]), w["box_m"])
        assert np.array_equal(np.array([x.foot_m for x in samples]), w["foot_m"])
        # the start's forces are those of the commands in force then: on the bus the RESET's held
        # (t = 0) set-points, in walk the first step's (as legsim_cli); after it, the same steps
        assert np.array_equal(np.array([x.foot_force_n for x in samples[1:]]), w["foot_force_n"][1:])
        # the swing tripod's feet left the ground on the way
        assert any(x.foot_state.count("free") >= 3 for x in samples)
        print(f"hexapod walk over vcan0: {n} steps, box x {s.box_m[0]:.6f} m, "
              f"{sum(x.foot_state.count('free') for x in samples)} free-foot samples, all equal")
    finally:
        hx.close()


def test_a_bad_frame_is_refused_and_a_silent_leg_trips_alone(start_hil, vcan, hexapod):
    hx, m, _ = start(start_hil, vcan, hexapod, cmd_timeout_ms=20)
    try:
        sp, _, _, ff, fm = walk_command(hexapod, 0.0)
        hb0 = hx.heartbeat()
        # bad frames: one FAULT each, naming the signal; nothing applied
        lengths = sp["length_m"][3]
        bad = [
            (hx.encode("HEX_CMD_H3", {"Hc_Seq": 100, "Hc_Mode_upper": 2, "Hc_Mode_lower": 2, "Hc_Mode_rowing": 2,
                                      "Hc_Setpoint_upper": lengths[0], "Hc_Setpoint_lower": math.nan},
                       strict=False), cl.FaultCode.NOT_FINITE, "Hc_Setpoint_lower"),
            (hx.encode("HEX_CMD_H3", {"Hc_Seq": 101, "Hc_Mode_upper": 2, "Hc_Setpoint_upper": 5.0}),
             cl.FaultCode.OUT_OF_RANGE, "Hc_Setpoint_upper"),            # past the stroke
            (hx.encode("HEX_CMD_H3", {"Hc_Seq": 102, "Hc_Mode_upper": 1, "Hc_Setpoint_upper": 10.0,
                                      "Hc_Mode_rowing": 3}, strict=False),
             cl.FaultCode.OUT_OF_RANGE, "Hc_Mode_rowing"),               # a mode past SERVO
        ]
        for msg, code, signal in bad:
            hx.send_raw(msg)
            f = hx.wait_fault(code=code)
            assert (f.frame_id, f.signal) == (HEX_CMD + 3, signal), str(f)
        classic = hx.encode("HEX_CMD_H3", {"Hc_Seq": 103})
        classic.is_fd, classic.data, classic.dlc = False, classic.data[:8], 8
        hx.send_raw(classic)
        assert hx.wait_fault(code=cl.FaultCode.BAD_LENGTH).frame_id == HEX_CMD + 3
        # leg 4 falls silent after the first step's command: 20 steps later it trips, alone
        trips = []
        for i in range(30):
            for k in range(LEGS):
                if k != 4 or i == 0:
                    hx.command_servo(k, sp["length_m"][k], sp["rowing_rad"][k], ff[k], fm[k])
            s = hx.step(1)
            given_ff, given_fm = ff.copy(), fm.copy()
            if i >= 20:
                given_ff[4], given_fm[4] = 0.0, 0.0
            m.command_pose(sp["length_m"], sp["rowing_rad"], given_ff, given_fm)
            m.step(1, h_s=H)
            assert same(s, m.state()), f"step {i + 1}"
            trips += [(i, f) for f in s.faults if f.code == cl.FaultCode.CMD_TIMEOUT]
            assert (cl.Status.SAFE_STATE in s.leg_status[4]) == (i >= 20)
            assert all(cl.Status.SAFE_STATE not in s.leg_status[k] for k in range(LEGS) if k != 4)
        assert len(trips) == 1 and trips[0][0] == 20
        f = trips[0][1]
        assert (f.frame_id, f.detail, f.value) == (HEX_CMD + 4, 20, 20.0)
        # the heartbeat went on, counting the refusals
        hb = hx.heartbeat()
        assert hb.counter > hb0.counter and hb.state == cl.SimState.LOCKSTEP
        assert hb.rx_rejected >= len(bad) + 1 and hb.fault_count >= len(bad) + 2
    finally:
        hx.close()


def test_mixed_slots_over_the_bus_are_the_in_process_command_each(start_hil, vcan, hexapod):
    """A leg controller's mix: the stance legs' lower actuators and leg 1's rowing motor pushed by
    the statics' force and torque, leg 4's upper actuator switched from servo to force after 20
    steps, the other slots servoed, leg 5's rowing KEEP after the first step."""
    hx, m, _ = start(start_hil, vcan, hexapod)
    try:
        n = 60
        for i in range(n):
            sp, _, stance, ff, fm = walk_command(hexapod, (i + 1) * H)
            mode = [["servo"] * 3 for _ in range(LEGS)]
            for k in stance:
                mode[k][1] = "force"
            mode[1][2] = "force"
            if i >= 20:
                mode[4][0] = "force"
            if i > 0:
                mode[5][2] = "keep"
            load = np.column_stack([ff, fm])
            setpoint = np.column_stack([sp["length_m"], sp["rowing_rad"]])
            forced = np.array([[x == "force" for x in row] for row in mode])
            value = np.where(forced, load, setpoint)
            feedforward = np.where(forced, 0.0, load)
            hx.command_each(mode, value, feedforward)
            s = hx.step(1)
            m.command_each(mode, value, feedforward)
            m.step(1, h_s=H)
            assert same(s, m.state()), f"step {i + 1}"
            want = [tuple(HexMode.SERVO if x == "keep" else HexMode[x.upper()] for x in row) for row in mode]
            assert s.modes == want, f"step {i + 1}"
            assert np.array_equal(s.actuator_force_n[forced[:, :2]], load[:, :2][forced[:, :2]].astype(np.float32))
        assert not s.faults and s.step_count == n
        print(f"hexapod mixed slots over vcan0: {n} steps equal to HexapodSim.command_each's")
    finally:
        hx.close()


def test_the_link_assembles_a_sample_from_its_15_frames():
    """No bus needed: a sample's frames (python-can's virtual interface) decoded into a HexState."""
    import can

    bus = can.Bus(interface="virtual", channel="hexapod_link_test", receive_own_messages=False)
    theirs = can.Bus(interface="virtual", channel="hexapod_link_test")
    hx = HexapodLink(bus=theirs)
    try:
        tick = 7
        frames = [("HEX_BOX_POSE", {"Hb_Tick": tick, "Hb_X": 0.1, "Hb_Y": -0.2, "Hb_Z": 1.0 + 2 ** -40,
                                    "Hb_Qw": 1.0}),
                  ("HEX_BOX_VEL", {"Hv_Tick": tick, "Hv_Vx": 1e-9, "Hv_Impacts": 3, "Hv_Energy": 2.5})]
        for k in range(LEGS):
            frames.append((f"HEX_LEG_H{k}", {"Hl_Tick": tick, "Hl_FootState": k % 3, "Hl_Mode_upper": 2,
                                             "Hl_Mode_lower": 1 + (k == 2), "Hl_Mode_rowing": 2, "Hl_Seq": k,
                                             "Hl_Length_upper": 0.7, "Hl_Status": int(cl.Status.SAFE_STATE) * (k == 4)}))
            frames.append((f"HEX_FOOT_H{k}", {"Hf_Tick": tick, "Hf_X": k + 0.1, "Hf_Fz": 100.0 + k}))
        frames.append(("ST_STATUS", {"St_Tick": tick, "St_Time": 0.007, "St_StepCount": tick, "St_State": 1,
                                     "St_CtrlSeq": 9}))
        for name, sig in frames:
            bus.send(hx.encode(name, sig))
        s = hx.read_state(timeout=2.0)
        assert (s.tick, s.t_s, s.step_count, s.ctrl_seq, s.impacts) == (7, 0.007, 7, 9, 3)
        assert s.box_m[2] == 1.0 + 2 ** -40 and s.box_velocity_mps[0] == 1e-9   # float64 end to end
        assert s.foot_state == ["free", "stuck", "sliding"] * 2
        assert s.modes == [(HexMode.SERVO, HexMode.SERVO if k == 2 else HexMode.FORCE, HexMode.SERVO)
                           for k in range(LEGS)]
        assert list(s.foot_m[:, 0]) == [k + 0.1 for k in range(LEGS)] and s.foot_force_n[5, 2] == 105.0
        assert s.length_m[0, 0] == np.float32(0.7) and s.leg_seq == list(range(LEGS))
        assert cl.Status.SAFE_STATE in s.leg_status[4] and cl.Status.SAFE_STATE not in s.leg_status[3]
    finally:
        theirs.shutdown()
        bus.shutdown()
