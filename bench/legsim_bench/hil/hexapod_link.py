"""The bench's CAN link to the hexapod's node (``hil_sim --hexapod``): python-can for the bus,
cantools with can/legsim.dbc for the frames, as :class:`~legsim_bench.hil.can_link.HilLink`
(whose bus configuration, waiting, faults and heartbeats it shares). Layout and rules:
can/README.md, "The hexapod".

    from legsim_bench.hil.hexapod_link import HexapodLink, HexMode

    with HexapodLink() as hx:
        for leg in range(6):                         # the servos' set-points, held for the RESET
            hx.command_servo(leg, lengths[leg], rowing[leg], ff[leg], ff_rowing[leg])
        s = hx.reset(box_height=1.0, stance=0b010101, servo=True, use_held=True)
        s = hx.step(1)
        print(s.t, s.box_m, s.foot_m[0], s.foot_state)

Each leg is its own node: HEX_CMD_Hj carries its three slots (upper, lower, rowing: KEEP /
FORCE / SERVO, set-point and feed-forward, float64), each slot in its own mode whatever the
others' (``command_each``: legsim.HexapodSim.command_each's arguments), with its own sequence
counter and command watchdog; a sample is HEX_BOX_POSE, HEX_BOX_VEL, per leg HEX_LEG_Hj and HEX_FOOT_Hj, then
ST_STATUS (complete when it arrives). The box and the feet are float64 (the C API's doubles
bit for bit), the legs' lengths, rates, forces and rowing float32.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, field

import can
import numpy as np

from .can_link import (CMD_TIMEOUT_DEFAULT, CMD_TIMEOUT_NONE, CONTROL, FAULT, HEARTBEAT, ST_STATUS, Command,
                       Fault, HilFault, HilLink, Integrator, SimState, Status, _enum, bus_config, bus_origin,
                       describe_bus)

LEGS = 6
SLOTS = ("upper", "lower", "rowing")
HEX_CMD = 0x400          # + leg
HEX_BOX_POSE, HEX_BOX_VEL = 0x410, 0x411
HEX_LEG = 0x420          # + leg
HEX_FOOT = 0x430         # + leg
HEX_STATE_IDS = (HEX_BOX_POSE, HEX_BOX_VEL) + tuple(i + k for k in range(LEGS) for i in (HEX_LEG, HEX_FOOT)) + \
    (ST_STATUS,)
HEX_HIL_IDS = HEX_STATE_IDS + (FAULT, HEARTBEAT)
_FOOT_STATES = ("free", "stuck", "sliding")
_TICK = {HEX_BOX_POSE: "Hb_Tick", HEX_BOX_VEL: "Hv_Tick", ST_STATUS: "St_Tick",
         **{HEX_LEG + k: "Hl_Tick" for k in range(LEGS)}, **{HEX_FOOT + k: "Hf_Tick" for k in range(LEGS)}}


class HexMode(enum.IntEnum):
    KEEP = 0
    FORCE = 1
    SERVO = 2


@dataclass
class HexState:
    """One state sample of the hexapod (numpy arrays, SI units, world axes; the box's angular
    velocity in its own frame), as legsim.HexapodSim.state() names them."""
    tick: int
    t_s: float
    step_count: int
    state: SimState
    status: Status
    legsim_status: int
    ctrl_seq: int
    box_m: np.ndarray
    box_quat: np.ndarray
    box_velocity_mps: np.ndarray
    box_omega_radps: np.ndarray
    kinetic_energy_j: float
    impacts: int
    length_m: np.ndarray          # (6, 2) float32 values
    rate_mps: np.ndarray          # (6, 2): the state's length rates
    actuator_force_n: np.ndarray  # (6, 2)
    rowing_rad: np.ndarray        # (6,)
    rowing_rate_radps: np.ndarray
    rowing_torque_nm: np.ndarray
    foot_state: list              # "free" / "stuck" / "sliding"
    foot_m: np.ndarray            # (6, 3) float64
    foot_force_n: np.ndarray      # (6, 3) float64
    leg_status: list              # each leg node's Status
    leg_seq: list                 # each leg's last accepted HEX_CMD counter
    modes: list                   # each leg's (upper, lower, rowing) HexMode: FORCE or SERVO
    faults: list = field(default_factory=list)


class HexapodLink(HilLink):
    """One bench's connection to the hexapod's node. Not thread-safe."""

    def __init__(self, interface: str | None = None, channel: str | int | None = None, *,
                 bus: can.BusABC | None = None, dbc=None, timeout: float = 5.0, given_by=None, **bus_kwargs):
        own = bus is None
        description = None
        if own:
            cfg = bus_config(interface, channel, **bus_kwargs)
            description = describe_bus(cfg, bus_origin(interface, channel, cfg, given_by))
            filters = [{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in HEX_HIL_IDS]
            bus = can.Bus(**cfg, can_filters=filters)
        super().__init__(bus=bus, dbc=dbc, timeout=timeout)
        if own:
            self._own_bus, self.description = True, description
        self._seq.update({HEX_CMD + k: 0 for k in range(LEGS)})

    # ---- commands ------------------------------------------------------------------------

    def command(self, leg: int, upper=None, lower=None, rowing=None) -> int:
        """Leg's HEX_CMD: each slot None (KEEP) or (mode, set-point, feed-forward): FORCE N / N m,
        SERVO m / rad with a feed-forward N / N m. Returns its counter."""
        sig = {"Hc_Seq": self.next_seq(HEX_CMD + leg)}
        for name, slot in zip(SLOTS, (upper, lower, rowing)):
            mode, value, ff = (HexMode.KEEP, 0.0, 0.0) if slot is None else slot
            sig[f"Hc_Mode_{name}"] = int(mode)
            sig[f"Hc_Setpoint_{name}"] = float(value)
            sig[f"Hc_Ff_{name}"] = float(ff)
        self._send(self.encode(f"HEX_CMD_H{leg}", sig))
        return sig["Hc_Seq"]

    def command_servo(self, leg: int, lengths, rowing: float, ff=(0.0, 0.0), ff_rowing: float = 0.0) -> int:
        """Leg's servos: its two lengths (m) and rowing angle (rad), with feed-forwards."""
        return self.command(leg, (HexMode.SERVO, lengths[0], ff[0]), (HexMode.SERVO, lengths[1], ff[1]),
                            (HexMode.SERVO, rowing, ff_rowing))

    def command_pose(self, length_m, rowing_rad, feedforward_n=None, feedforward_nm=None) -> None:
        """Every leg's servos, one frame per leg: legsim.HexapodSim.command_pose's arguments."""
        length_m, rowing_rad = np.asarray(length_m, float), np.asarray(rowing_rad, float)
        ff = np.zeros((LEGS, 2)) if feedforward_n is None else np.asarray(feedforward_n, float)
        fm = np.zeros(LEGS) if feedforward_nm is None else np.asarray(feedforward_nm, float)
        for k in range(LEGS):
            self.command_servo(k, length_m[k], rowing_rad[k], ff[k], fm[k])

    def command_force(self, leg: int, forces, torque: float) -> int:
        return self.command(leg, (HexMode.FORCE, forces[0], 0.0), (HexMode.FORCE, forces[1], 0.0),
                            (HexMode.FORCE, torque, 0.0))

    def command_each(self, mode, value, feedforward=None, legs=range(LEGS)) -> None:
        """Each slot on its own, one frame per leg of `legs`: legsim.HexapodSim.command_each's
        arguments (6 x 3, per leg upper, lower, rowing; mode "keep" / "force" / "servo" or a
        HexMode; value N, N m, m or rad; feedforward N or N m, None: 0)."""
        value = np.asarray(value, float)
        ff = np.zeros((LEGS, 3)) if feedforward is None else np.asarray(feedforward, float)
        mode = [[HexMode[m.upper()] if isinstance(m, str) else HexMode(m) for m in row] for row in mode]
        if value.shape != (LEGS, 3) or ff.shape != (LEGS, 3) or [len(r) for r in mode] != [3] * LEGS:
            raise ValueError("mode, value, feedforward: 6 x 3 each (per leg: upper, lower, rowing)")
        for k in legs:
            self.command(k, *[None if mode[k][j] == HexMode.KEEP else (mode[k][j], value[k, j], ff[k, j])
                              for j in range(3)])

    # ---- control -------------------------------------------------------------------------

    def reset(self, box_height: float, stance: int = 0b111111, *, servo: bool = True, use_held: bool = False,
              integrator: str | int = "rk4", step_s: float = 1e-3, cmd_timeout_ms: int | None = None) -> HexState:
        """New session: the box level at (0, 0, box_height) (float32 on the bus), each leg at its
        stand (or, use_held, at the SERVO set-points sent since the previous RESET), the feet of
        `stance` (bit l: leg l) stuck; servo: every slot SERVO, holding that pose (with the held
        feed-forwards), else every slot FORCE at zero (each HEX_CMD slot then sets its own). cmd_timeout_ms: None = hil_sim's default, 0 = none."""
        timeout = CMD_TIMEOUT_DEFAULT if cmd_timeout_ms is None else \
            (CMD_TIMEOUT_NONE if cmd_timeout_ms == 0 else int(cmd_timeout_ms))
        sig = {"Ctrl_Integrator": _enum(Integrator, integrator), "Ctrl_StepSize": round(step_s * 1e9),
               "Ctrl_ActInit": 1 if servo else 0, "Ctrl_UseLengths": 1 if use_held else 0,
               "Ctrl_CmdTimeout": timeout, "Ctrl_HexBoxHeight": float(box_height), "Ctrl_HexStance": int(stance)}
        self._states.clear()
        return self._control(Command.RESET, **sig)

    # ---- receiving -----------------------------------------------------------------------

    def _handle(self, msg: can.Message) -> None:
        fid = msg.arbitration_id
        if msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame or fid not in HEX_HIL_IDS:
            if self._trace is not None:
                self._trace.write(msg, rx=True)
            return
        if fid in (FAULT, HEARTBEAT):
            super()._handle(msg)
            return
        if self._trace is not None:
            self._trace.write(msg, rx=True)
        try:
            sig = self.db.decode_message(fid, msg.data, decode_choices=False, scaling=True)
        except (ValueError, KeyError):
            return
        tick = sig[_TICK[fid]]
        parts = self._partial.setdefault(tick, {})
        parts[fid] = sig
        if fid != ST_STATUS:
            return
        del self._partial[tick]
        for old in [k for k in self._partial if k != tick]:
            del self._partial[old]
        if all(i in parts for i in HEX_STATE_IDS):
            s = self._hex_state_from(parts)
            self.last_state = s
            self._states.append(s)

    def _hex_state_from(self, p: dict) -> HexState:
        b, v, st = p[HEX_BOX_POSE], p[HEX_BOX_VEL], p[ST_STATUS]
        leg = [p[HEX_LEG + k] for k in range(LEGS)]
        foot = [p[HEX_FOOT + k] for k in range(LEGS)]
        s = HexState(
            tick=st["St_Tick"], t_s=st["St_Time"], step_count=st["St_StepCount"], state=SimState(st["St_State"]),
            status=Status(st["St_Status"]), legsim_status=st["St_LegsimStatus"], ctrl_seq=st["St_CtrlSeq"],
            box_m=np.array([b["Hb_X"], b["Hb_Y"], b["Hb_Z"]]),
            box_quat=np.array([b["Hb_Qw"], b["Hb_Qx"], b["Hb_Qy"], b["Hb_Qz"]]),
            box_velocity_mps=np.array([v["Hv_Vx"], v["Hv_Vy"], v["Hv_Vz"]]),
            box_omega_radps=np.array([v["Hv_Wx"], v["Hv_Wy"], v["Hv_Wz"]]),
            kinetic_energy_j=v["Hv_Energy"], impacts=v["Hv_Impacts"],
            length_m=np.array([[g["Hl_Length_upper"], g["Hl_Length_lower"]] for g in leg]),
            rate_mps=np.array([[g["Hl_Rate_upper"], g["Hl_Rate_lower"]] for g in leg]),
            actuator_force_n=np.array([[g["Hl_Force_upper"], g["Hl_Force_lower"]] for g in leg]),
            rowing_rad=np.array([g["Hl_Rowing"] for g in leg]),
            rowing_rate_radps=np.array([g["Hl_RowingRate"] for g in leg]),
            rowing_torque_nm=np.array([g["Hl_RowingTorque"] for g in leg]),
            foot_state=[_FOOT_STATES[g["Hl_FootState"]] for g in leg],
            foot_m=np.array([[f["Hf_X"], f["Hf_Y"], f["Hf_Z"]] for f in foot]),
            foot_force_n=np.array([[f["Hf_Fx"], f["Hf_Fy"], f["Hf_Fz"]] for f in foot]),
            leg_status=[Status(g["Hl_Status"]) for g in leg], leg_seq=[g["Hl_Seq"] for g in leg],
            modes=[tuple(HexMode(g[f"Hl_Mode_{name}"]) for name in SLOTS) for g in leg])
        s.faults, self._pending_faults = self._pending_faults, []
        return s


__all__ = ["HexapodLink", "HexState", "HexMode", "LEGS", "SLOTS", "HEX_CMD", "HEX_BOX_POSE", "HEX_BOX_VEL",
           "HEX_LEG", "HEX_FOOT", "HEX_STATE_IDS", "Fault", "HilFault", "CONTROL"]
