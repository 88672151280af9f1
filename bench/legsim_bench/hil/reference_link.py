"""The reference model playing hil_sim: a stand-in for can_link.HilLink with no bus."""
from __future__ import annotations

import math
import time
from pathlib import Path

import can
import cantools
import numpy as np

from ..reference import ForceCommand, LegModel, LengthCommand
from ..scene import find_root
from . import can_link as cl

__all__ = ["ReferenceLink"]


class ReferenceLink:
    """A stand-in for can_link.HilLink with no bus: the bench's reference model answers as
    hil_sim would (lockstep, held setpoints, the command timeout and zero-force safe state,
    and hil_sim's checks of bad input: unknown id, length, stale counter, NaN/Inf, DBC ranges,
    stroke and max_force). No stroke stops. For `legsim-bench run --dry-run` (trying a scene,
    the report and the plots without CAN) and the tests; it says nothing about the core."""

    def __init__(self, root: Path | None = None, *, perturb=None):
        self.cl, self.np = cl, np
        self.root = root or find_root()
        self.db = cantools.database.load_file(str(self.root / "can" / "legsim.dbc"))
        self.perturb = perturb               # perturb(state) -> None: for tests of the checks
        self.bus = type("Bus", (), {"channel_info": "reference model (no bus)"})()
        self.timeout = 5.0
        self._seq = {cl.CONTROL: 0, cl.ACT_CMD: 0, cl.LOAD_CMD: 0}
        self._accepted = {cl.CONTROL: None, cl.ACT_CMD: None, cl.LOAD_CMD: None}
        self._faults: list = []
        self._pending: list = []
        self._fault_count = 0
        self.model = None
        self.model_path = self.root / "models" / "leg.toml"

    def use_model(self, path) -> None:
        """The model file of the next RESET (a scene's own, or models/leg.toml)."""
        self.model_path = Path(path) if path else self.root / "models" / "leg.toml"

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        pass

    def close(self):
        pass

    # -- link API used by record()
    def heartbeat(self, timeout=None):
        return self.cl.Heartbeat(0, self.cl.SimState.IDLE if self.model is None else self.cl.SimState.LOCKSTEP,
                                 self.cl.Status(0), 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, self._fault_count, 0, 0.0)

    def drain(self, quiet=0.05):
        self._faults.clear()
        self._pending.clear()

    def poll(self, timeout=0.0):
        return False

    def faults(self):
        out, self._faults = self._faults, []
        return out

    def next_seq(self, frame_id):
        self._seq[frame_id] = (self._seq[frame_id] + 1) & 0xFFFFFFFF
        return self._seq[frame_id]

    def encode(self, name, signals, *, strict=True, frame_id=None):
        msg = self.db.get_message_by_name(name)
        data = {s.name: 0 for s in msg.signals}
        data.update(signals)
        payload = msg.encode(data, strict=strict, padding=False, scaling=True)
        return can.Message(arbitration_id=msg.frame_id if frame_id is None else frame_id, data=payload,
                           is_extended_id=False, is_fd=True)

    def reset(self, variant="revolute", integrator="rk4", step_s=1e-3, pose=0, *, lengths=None,
              hold_length=False, disable=0, cmd_timeout_ms=None):
        np = self.np
        self.model = LegModel.from_toml(self.model_path, variant=variant)
        self.h_ns = round(step_s * 1e9)
        self.variant, self.integrator = variant, integrator
        th = self.model.stand_theta()
        if lengths is not None:
            th = self.model.theta_from_lengths(lengths, near=th)
        self.theta, self.thetad = th, np.zeros(self.model.ndof)
        self.gravity = not disable & 1
        self.steps = 0
        self.load = (0.0, 0.0)
        L = self.model.lengths(th)
        self.cmd = [("length", float(L[a])) if hold_length else ("force", 0.0) for a in range(2)]
        self.timeout_steps = 0 if not cmd_timeout_ms else -(-cmd_timeout_ms * 1_000_000 // self.h_ns)
        self.armed = self.safe = False
        self.since_cmd = 0
        self.fault_since = False
        self.last_fault = self.cl.FaultCode.NONE
        self._accepted = {k: None for k in self._accepted}
        self._seq[self.cl.CONTROL] += 1
        self._accepted[self.cl.CONTROL] = self._seq[self.cl.CONTROL]
        self._res = None
        return self._state()

    def set_load(self, index, fx, fy=0.0):
        seq = self.next_seq(self.cl.LOAD_CMD)
        if self._check(self.cl.LOAD_CMD, seq, {"Load_Index": index, "Load_Value1": fx, "Load_Value2": fy}):
            self.load = (float(fx), float(fy))
        return seq

    def command(self, upper=None, lower=None):
        seq = self.next_seq(self.cl.ACT_CMD)
        sig = {}
        for name, c in (("upper", upper), ("lower", lower)):
            mode, v = c if c is not None else (self.cl.ActMode.KEEP, 0.0)
            sig[f"Act_Mode_{name}"], sig[f"Act_Setpoint_{name}"] = int(mode), float(v)
        if self._check(self.cl.ACT_CMD, seq, sig):
            self._apply_act(sig)
        return seq

    def send_raw(self, msg):
        cl = self.cl
        fid, data = msg.arbitration_id, bytes(msg.data)
        if fid not in (cl.CONTROL, cl.ACT_CMD, cl.LOAD_CMD) or msg.is_extended_id:
            return self._fault(cl.FaultCode.UNKNOWN_ID, fid, len(data), 0, 0)
        if len(data) != 64:
            return self._fault(cl.FaultCode.BAD_LENGTH, fid, len(data), 0, 64)
        sig = self.db.decode_message(fid, data, decode_choices=False, scaling=True)
        seq = int(sig[{cl.CONTROL: "Ctrl_Seq", cl.ACT_CMD: "Act_Seq", cl.LOAD_CMD: "Load_Seq"}[fid]])
        if self._check(fid, seq, sig):
            if fid == cl.ACT_CMD:
                self._apply_act(sig)
            elif fid == cl.LOAD_CMD:
                self.load = (sig["Load_Value1"], sig["Load_Value2"])
            elif int(sig["Ctrl_Command"]) == 2:
                self._advance(int(sig["Ctrl_NSteps"]))

    def step(self, n=1, timeout=None):
        seq = self.next_seq(self.cl.CONTROL)
        self._accepted[self.cl.CONTROL] = seq
        self._advance(int(n))
        return self._state()

    # -- the plant
    def _fault(self, code, fid, flen, seq, detail, value=0.0, signal=None):
        self._fault_count += 1
        f = self.cl.Fault(code, fid, flen, seq, detail, value, self.steps, self._fault_count, signal)
        self._faults.append(f)
        self._pending.append(f)
        self.last_fault = code
        self.fault_since = True
        return f

    def _check(self, fid, seq, sig) -> bool:
        cl = self.cl
        last = self._accepted[fid]
        if last is not None and seq <= last:
            self._fault(cl.FaultCode.STALE_SEQ, fid, 64, seq, last, float(seq))
            return False
        msg = self.db.get_message_by_frame_id(fid)
        acts = {a["name"]: a for a in self._actuators()}
        for s in msg.signals:
            if s.name.startswith("Act_Setpoint_") and int(sig.get("Act_Mode_" + s.name.rsplit("_", 1)[1], 0)) == 0:
                continue  # KEEP: hil_sim checks only the signals a request uses
            v = sig.get(s.name, 0)
            if isinstance(v, float) and not math.isfinite(v):
                self._fault(cl.FaultCode.NOT_FINITE, fid, 64, seq, s.start, v, s.name)
                return False
            lo, hi = s.minimum, s.maximum
            ok = (lo is None or v >= lo) and (hi is None or v <= hi)
            if ok and s.name.startswith("Act_Setpoint_"):
                a = s.name.rsplit("_", 1)[1]
                mode = int(sig.get(f"Act_Mode_{a}", 0))
                st, fmax = acts[a]["stroke"], acts[a]["max_force"]
                ok = (mode != 1 or abs(v) <= fmax) and (mode != 2 or st[0] <= v <= st[1])
            if not ok:
                self._fault(cl.FaultCode.OUT_OF_RANGE, fid, 64, seq, s.start, float(v), s.name)
                return False
        self._accepted[fid] = seq
        return True

    def _actuators(self):
        return [{"name": a.name, "stroke": a.stroke, "max_force": a.max_force} for a in self.model.actuators]

    def _apply_act(self, sig):
        for a, name in enumerate(("upper", "lower")):
            mode = int(sig[f"Act_Mode_{name}"])
            if mode:
                self.cmd[a] = ("force" if mode == 1 else "length", float(sig[f"Act_Setpoint_{name}"]))
        self.armed = self.timeout_steps > 0
        self.safe = False
        self.since_cmd = 0

    def _advance(self, n):
        while n > 0:
            chunk = n
            if self.armed:
                if self.since_cmd >= self.timeout_steps:
                    self.armed, self.safe = False, True
                    self.cmd = [("force", 0.0), ("force", 0.0)]
                    self._fault(self.cl.FaultCode.CMD_TIMEOUT, self.cl.ACT_CMD, 0,
                                self._accepted[self.cl.ACT_CMD] or 0, self.timeout_steps)
                    continue
                chunk = min(chunk, self.timeout_steps - self.since_cmd)
            self._simulate(chunk)
            n -= chunk
            self.since_cmd += chunk

    def _simulate(self, n):
        T = n * self.h_ns / 1e9
        cmds = [ForceCommand(v) if m == "force" else LengthCommand(v) for m, v in self.cmd]
        self._res = self.model.simulate(T, t_eval=[T], actuators=cmds, foot_load=self.load,
                                        gravity=self.gravity, theta0=self.theta, thetad0=self.thetad)
        self.theta, self.thetad = self._res.theta[-1], self._res.thetad[-1]
        self.steps += n

    def _state(self):
        np, cl = self.np, self.cl
        m = self.model
        if self._res is None:
            q = m.absolute_q(self.theta)
            qd = np.zeros_like(q)
            L, Ld = m.lengths(self.theta), np.zeros(2)
            F = np.array([v if md == "force" else m.actuators[a].kp * (v - L[a])
                          for a, (md, v) in enumerate(self.cmd)])
            R = np.zeros((8, 3))
        else:
            r = self._res
            q, qd, L, Ld, F, R = r.q[-1], r.qd[-1], r.lengths[-1], r.length_rates[-1], \
                r.actuator_forces[-1], r.reactions[-1]
        f32 = np.float32
        status = cl.Status.ASSEMBLED
        if self.safe:
            status |= cl.Status.SAFE_STATE
        if self.fault_since:
            status |= cl.Status.FAULT
        if self.armed:
            status |= cl.Status.CMD_WATCHDOG
        s = cl.State(q=q.astype(f32).astype(float), qd=qd.astype(f32).astype(float),
                     lengths=L.astype(f32).astype(float), rates=Ld.astype(f32).astype(float),
                     forces=np.asarray(F).astype(f32).astype(float),
                     reactions=np.asarray(R).astype(f32).astype(float), t=self.steps * self.h_ns / 1e9,
                     step_count=self.steps, residual=0.0, condition=1.0, status=status, stroke_mask=0,
                     state=cl.SimState.LOCKSTEP, legsim_status=0, last_fault=self.last_fault,
                     iterations=0, variant=cl.Variant[self.variant.upper()],
                     integrator=cl.Integrator[self.integrator.upper()],
                     act_seq=self._accepted[cl.ACT_CMD] or 0, ctrl_seq=self._accepted[cl.CONTROL] or 0,
                     step_ns=self.h_ns, faults=self._pending, received=time.monotonic())
        self._pending = []
        self.fault_since = False
        if self.perturb is not None:
            self.perturb(s)
        return s
