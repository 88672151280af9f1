"""Runs a scene against hil_sim over CAN and records everything (no analysis here).

The recording is plain JSON (`legsim-bench-recording/1`): the scene's TOML text, every
state sample hil_sim sent (positions, velocities, actuator lengths/rates/forces, reactions,
time, status, faults), every frame the bench sent that the reference model has to replay
(actuator commands and loads, as the float32 values on the bus, with the step they took
effect), the injected bad inputs, and the heartbeat. `legsim_bench.checks` turns it into
checks; nothing here imports numpy beyond what can_link needs, nor scipy or matplotlib, so
`legsim-bench record` stays light inside the QEMU VM.

Timeline of one exchange at a boundary step k (see Scene.boundaries()):
    ACT_CMD with both setpoints at t = k h (unless silent)   -> applies from step k on
    injected bad frames (if any at k)                       -> FAULT frames, nothing changes
    CONTROL STEP n (n = next boundary - k)                  -> one state sample at step k + n
"""
from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

from .scene import ACTUATORS, SEQ_SIGNALS, Scene, find_root, parse_scene

FORMAT = "legsim-bench-recording/1"

__all__ = ["record", "save_recording", "load_recording", "scene_of", "HilProcess",
           "hil_sim_path", "f32", "FORMAT", "RecordingError"]


class RecordingError(RuntimeError):
    pass


def f32(x: float) -> float:
    """x as the float32 the DBC carries (IEEE 754 round to nearest)."""
    return struct.unpack("<f", struct.pack("<f", float(x)))[0]


def _fault_dict(f) -> dict:
    code = f.code.name if hasattr(f.code, "name") else str(f.code)
    return {"code": code, "frame_id": int(f.frame_id), "frame_len": int(f.frame_len),
            "seq": int(f.seq), "detail": int(f.detail), "value": float(f.value),
            "step": int(f.step_count), "count": int(f.count), "signal": f.signal}


def _contact_dict(c) -> dict:
    return {"state": c.state.name.lower(), "events": [e.name.lower() for e in type(c.events) if e in c.events],
            "normal": float(c.normal), "tangential": float(c.tangential),
            "friction_use": float(c.friction_use), "x": float(c.x), "y": float(c.y),
            "slip": float(c.slip), "impulse_n": float(c.impulse_n), "impulse_t": float(c.impulse_t)}


def _state_dict(s, t_wall0: float) -> dict:
    robot = {} if getattr(s, "legs", 1) < 2 else {
        "legs": int(s.legs), "act_seqs": [int(x) for x in s.act_seqs],
        "contacts": [_contact_dict(c) for c in s.contacts]}
    return {**robot,
        "t": float(s.t), "step": int(s.step_count),
        "q": [float(v) for v in s.q], "qd": [float(v) for v in s.qd],
        "lengths": [float(v) for v in s.lengths], "rates": [float(v) for v in s.rates],
        "forces": [float(v) for v in s.forces],
        "reactions": [float(v) for v in s.reactions.reshape(-1)],
        "residual": float(s.residual), "condition": float(s.condition),
        "status": int(s.status), "status_names": list(s.status_names),
        "stroke_mask": int(s.stroke_mask), "state": s.state.name,
        "legsim_status": int(s.legsim_status),
        "last_fault": s.last_fault.name if hasattr(s.last_fault, "name") else str(s.last_fault),
        "iterations": int(s.iterations), "act_seq": int(s.act_seq), "ctrl_seq": int(s.ctrl_seq),
        "step_ns": int(s.step_ns), "faults": [_fault_dict(f) for f in s.faults],
        "wall": float(s.received - t_wall0) if s.received else None,
    }


def _progress(total: int, desc: str, enabled: bool | None):
    """A tqdm bar over steps (off when not a terminal, or enabled=False); no-op without tqdm."""
    if enabled is False:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=total, desc=desc, unit="step", leave=False, dynamic_ncols=True,
                disable=None if enabled is None else not enabled, file=sys.stderr)


def record(scene: Scene, link, *, progress: bool | None = None, log=None) -> dict:
    """Runs `scene` on the hil_sim behind `link` (a can_link.HilLink) and returns the recording.
    hil_sim errors (no answer, a refused RESET/STEP, HALTED) end the run early; they are in
    recording["errors"] and the checks fail on them.

    Only dynamics has frames in the DBC: a scene of another analysis runs in legsim_cli (the
    core on this host, legsim_bench.analyses) and `link` is not used; so does a robot dynamics
    scene given no link (link=None: its legsim_cli run, checked as the CLI's). A scene with its own
    model file needs a hil_sim started with --model FILE (HilProcess.for_scene).

    A robot scene (a model with contacts) runs on `hil_sim --robot` / `--model ROBOT.toml`:
    its four actuators' commands go to each leg's ACT_CMD (ACT_CMD_L1 for leg 1), its leg
    force elements to each leg's LOAD_CMD, contact_law and [[contact]] free in the RESET;
    every sample records per foot its state, events (Ct_Events), N, T, position, slip."""
    log = log or (lambda msg: None)
    if not scene.over_can or (link is None and scene.robot):
        # no frames for it, or a robot scene with no bus given: legsim_cli (its CLI path)
        from .analyses import record_analysis
        return record_analysis(scene, FORMAT, log=log)
    from .can_link import ACT_CMD, CONTROL, LOAD_CMD, ActMode, HilError, HilFault, SimState

    legs = 2 if scene.robot else 1
    if scene.robot and hasattr(link, "use_model"):
        raise RecordingError("the reference link plays the one leg only; a robot scene needs hil_sim --robot")
    if hasattr(link, "use_model"):       # the reference model playing hil_sim: same model file
        link.use_model(scene.model_path)
    elif not scene.builtin_model:
        log(f"{scene.name}: model {scene.model_path}: hil_sim must run it (hil_sim --model FILE; "
            "--start-hil does that)")
    rec: dict = {
        "format": FORMAT, "scene_name": scene.name,
        "scene_path": str(scene.path) if scene.path else None, "scene_source": scene.source,
        "started": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "host": platform.node(), "python": platform.python_version(),
        "bus": str(getattr(link.bus, "channel_info", "")),
        "heartbeat": None, "samples": [], "commands": [], "loads": [], "injections": [],
        "late_faults": [], "errors": [], "complete": False, "initial_lengths": None,
        "legs": legs, "actuators": list(scene.actuator_names),
    }
    t_wall0 = time.monotonic()
    try:
        hb = link.heartbeat(timeout=min(3.0, float(getattr(link, "timeout", 3.0))))
        rec["heartbeat"] = {"protocol_version": hb.protocol_version, "state": hb.state.name,
                            "uptime_ms": hb.uptime_ms, "fault_count": hb.fault_count}
    except HilError as e:
        log(f"warning: no HEARTBEAT from hil_sim ({e}); trying anyway")
    link.drain(0.02)

    mode_of = {"force": ActMode.FORCE, "length": ActMode.LENGTH}
    last_ok = {"ACT_CMD": 0, "LOAD_CMD": 0, "CONTROL": 0}
    silent_until = -1
    bar = None
    feet = {}
    if scene.robot:   # the feet's RESET options (Ctrl_ContactLaw, Ctrl_FreeContacts)
        free = sum(1 << scene.model_info.contacts.index(c) for c, v in scene.contacts.items() if v == "free")
        feet = {"contact_law": scene.contact_law, "free_contacts": free}
    try:
        s0 = link.reset(variant=scene.variant, integrator=scene.integrator, step_s=scene.step_s,
                        pose=scene.pose, lengths=scene.lengths,
                        hold_length=scene.init == "hold_length", disable=scene.disable_bits,
                        cmd_timeout_ms=scene.cmd_timeout_ms, **feet)
        if getattr(s0, "legs", 1) != legs:
            raise RecordingError(f"the hil_sim on this bus runs {getattr(s0, 'legs', 1)} leg(s), the scene's "
                                 f"model {legs} (a robot scene needs hil_sim --robot or --model ROBOT.toml)")
        if s0.step_ns != scene.step_ns:
            raise RecordingError(f"hil_sim runs h = {s0.step_ns} ns, the scene asked {scene.step_ns} ns")
        rec["samples"].append(_state_dict(s0, t_wall0))
        last_ok["CONTROL"] = s0.ctrl_seq
        rec["initial_lengths"] = [float(v) for v in s0.lengths]

        if scene.foot_load is not None:
            fx, fy = (f32(v) for v in scene.foot_load)
            seq = link.set_load(0, fx, fy)
            last_ok["LOAD_CMD"] = seq
            rec["loads"].append({"step": 0, "t": 0.0, "index": 0, "value": [fx, fy], "seq": seq})
        if scene.robot:   # the legs' force elements: leg k's LOAD_CMD, its own index
            per_leg = len(scene.model_info.forces) // legs
            for name, v in scene.forces.items():
                i = scene.model_info.forces.index(name)
                fx, fy = f32(v[0]), f32(v[1] if len(v) > 1 else 0.0)
                seq = link.set_load(i % per_leg, fx, fy, leg=i // per_leg)
                rec["loads"].append({"step": 0, "t": 0.0, "index": i, "name": name, "value": [fx, fy],
                                     "seq": seq})
        if scene.robot and scene.box_load is not None:   # leg 0's LOAD_CMD 2: box.load, 3: box.moment
            fx, fy, mz = (f32(v) for v in scene.box_load)
            for index, name, value in ((2, "box.load", [fx, fy]), (3, "box.moment", [mz, 0.0])):
                seq = link.set_load(index, *value, leg=0)
                rec["loads"].append({"step": 0, "t": 0.0, "index": index, "name": name, "value": value,
                                     "seq": seq, "box": True})

        bounds = scene.boundaries()
        inj_at: dict[int, list] = {}
        for inj in scene.injections:
            inj_at.setdefault(inj.step, []).append(inj)
        bar = _progress(scene.n_steps, scene.name, progress)
        for i, k in enumerate(bounds):
            n = (bounds[i + 1] if i + 1 < len(bounds) else scene.n_steps) - k
            for inj in inj_at.get(k, []):
                if inj.is_silence:
                    silent_until = max(silent_until, k + inj.silence_steps)
            if k >= silent_until and any(c is not None for c in scene.commands):
                sp = scene.setpoints(k, rec["initial_lengths"])
                args, logged = [], {}
                names = scene.actuator_names if scene.robot else ACTUATORS
                for a, v in enumerate(sp):
                    if v is None:
                        args.append(None)
                        continue
                    mode, value = v
                    value = f32(value)
                    args.append((mode_of[mode], value))
                    logged[names[a]] = [mode, value]
                if scene.robot:   # each leg's own ACT_CMD (leg 1: ACT_CMD_L1)
                    seqs = [link.command(*args[2 * g:2 * g + 2], leg=g) for g in range(legs)
                            if any(x is not None for x in args[2 * g:2 * g + 2])]
                    seq = seqs[0]
                    logged["seqs"] = seqs
                else:
                    seq = link.command(*args)
                last_ok["ACT_CMD"] = seq
                rec["commands"].append({"step": k, "t": scene.t(k), "seq": seq, **logged})
            for inj in inj_at.get(k, []):
                rec["injections"].append(_inject(link, scene, inj, k, last_ok,
                                                 ids={"CONTROL": CONTROL, "ACT_CMD": ACT_CMD,
                                                      "LOAD_CMD": LOAD_CMD}))
            try:
                s = link.step(n)
            except HilFault as e:
                rec["errors"].append({"step": k, "error": f"STEP {n} refused: {e.fault}",
                                      "fault": _fault_dict(e.fault)})
                break
            rec["samples"].append(_state_dict(s, t_wall0))
            link.faults()  # the same faults are in s.faults: keep the link's queue empty
            last_ok["CONTROL"] = s.ctrl_seq
            if bar is not None:
                bar.update(n)
            if s.state == SimState.HALTED:
                rec["errors"].append({"step": s.step_count,
                                      "error": f"hil_sim HALTED (legsim_status {s.legsim_status})"})
                break
            if s.step_count != k + n:
                rec["errors"].append({"step": k, "error": f"STEP {n} from step {k} answered with "
                                      f"step {s.step_count}"})
                break
        else:
            rec["complete"] = True
    except (HilError, RecordingError) as e:
        rec["errors"].append({"step": rec["samples"][-1]["step"] if rec["samples"] else None,
                              "error": str(e)})
    finally:
        if bar is not None:
            bar.close()
    # faults that came after the last sample (none expected)
    try:
        link.poll(0.05)
        rec["late_faults"] = [_fault_dict(f) for f in link.faults()]
    except Exception:  # noqa: BLE001 - a closing bus must not lose the recording
        pass
    rec["wall_time_s"] = time.monotonic() - t_wall0
    return rec


def _inject(link, scene: Scene, inj, k: int, last_ok: dict, ids: dict) -> dict:
    """Sends one bad input; returns what was sent (the checks match the faults to it)."""
    out = {"step": k, "t": scene.t(k), "label": inj.label, "expect": inj.expect,
           "expect_signal": inj.expect_signal}
    if inj.is_silence:
        out.update(kind="silence", silence_steps=inj.silence_steps,
                   last_command_step=None, frame_id=ids["ACT_CMD"])
        out["timeout_ms"] = scene.cmd_timeout_ms
        return out
    import can

    signals = dict(inj.signals)
    seq = None
    if inj.frame is not None:
        seq_name = SEQ_SIGNALS[inj.frame]
        if inj.seq == "next":
            seq = link.next_seq(ids[inj.frame])
        elif inj.seq == "stale":
            seq = last_ok[inj.frame]
        else:
            seq = int(inj.seq)
        signals.setdefault(seq_name, seq)
        seq = signals[seq_name]
        if inj.frame == "CONTROL":
            signals.setdefault("Ctrl_Command", 2)
            signals.setdefault("Ctrl_NSteps", 1)
            signals.setdefault("Ctrl_StepSize", scene.step_ns)
            signals.setdefault("Ctrl_RtStepsPerTick", 1)
        msg = link.encode(inj.frame, signals, strict=False)
        data = bytes(msg.data)
    else:
        data = bytes(64)
    data = data[:inj.length]
    msg = can.Message(arbitration_id=inj.frame_id, data=data, is_extended_id=False, is_fd=True,
                      bitrate_switch=False)
    link.send_raw(msg)
    out.update(kind="frame", frame=inj.frame, frame_id=inj.frame_id, length=len(data), seq=seq,
               signals={k2: (v if isinstance(v, (int, float)) else str(v)) for k2, v in signals.items()})
    return out


# ---- files -----------------------------------------------------------------------------

def save_recording(rec: dict, path: str | os.PathLike) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(rec, indent=1, allow_nan=True))
    tmp.replace(path)
    return path


def load_recording(path: str | os.PathLike) -> dict:
    path = Path(path)
    try:
        rec = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise RecordingError(f"{path}: cannot read the recording: {e}") from None
    if not isinstance(rec, dict) or rec.get("format") != FORMAT:
        raise RecordingError(f"{path}: not a legsim-bench recording ({FORMAT})")
    return rec


def scene_of(rec: dict, root: Path | None = None) -> Scene:
    """The Scene a recording was made from (parsed from the TOML text it carries)."""
    p = rec.get("scene_path")
    return parse_scene(rec["scene_source"], p, root=root, name=rec.get("scene_name"))


# ---- hil_sim as a child process ----------------------------------------------------------

def hil_sim_path(root: Path | None = None) -> Path:
    """$LEGSIM_HIL_SIM, else build/host/hil_sim/hil_sim under the repository."""
    env = os.environ.get("LEGSIM_HIL_SIM")
    if env:
        return Path(env)
    return (root or find_root()) / "build" / "host" / "hil_sim" / "hil_sim"


class HilProcess:
    """hil_sim started on a channel for the length of a `with` block (stderr to a log file).
    args: more options, e.g. scene.hil_args() = ["--model", FILE] for a scene's own model."""

    def __init__(self, channel: str = "vcan0", binary: str | os.PathLike | None = None,
                 args: list[str] | None = None, log_path: str | os.PathLike | None = None):
        self.binary = Path(binary) if binary else hil_sim_path()
        if not self.binary.is_file() or not os.access(self.binary, os.X_OK):
            raise RecordingError(
                f"hil_sim not found at {self.binary}: build it (cmake --preset host && "
                "cmake --build --preset host --target hil_sim) or set LEGSIM_HIL_SIM")
        self.channel = channel
        self.args = list(args or [])
        self.log_path = Path(log_path) if log_path else Path(
            os.environ.get("TMPDIR", "/tmp")) / f"hil_sim_bench_{os.getpid()}.log"
        self.proc: subprocess.Popen | None = None

    @classmethod
    def for_scene(cls, scene: Scene, channel: str = "vcan0", binary=None, log_path=None) -> "HilProcess":
        """A hil_sim that runs the scene's model (the compiled-in leg, or --model FILE)."""
        return cls(channel, binary, scene.hil_args(), log_path)

    def __enter__(self) -> "HilProcess":
        self.log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log = open(self.log_path, "wb")
        self.proc = subprocess.Popen([str(self.binary), "--channel", self.channel, *self.args],
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=self._log)
        time.sleep(0.05)
        if self.proc.poll() is not None:
            self._log.close()
            raise RecordingError(f"hil_sim exited at once ({self.proc.returncode}): {self.log()}")
        return self

    def log(self) -> str:
        try:
            return self.log_path.read_text(errors="replace").strip()
        except OSError:
            return ""

    def __exit__(self, *exc) -> None:
        self.stop()

    def stop(self) -> int | None:
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if not self._log.closed:
            self._log.close()
        return self.proc.returncode


# ---- the reference model playing hil_sim (no bus) -------------------------------------------

class ReferenceLink:
    """A stand-in for can_link.HilLink with no bus: the bench's reference model answers as
    hil_sim would (lockstep, held setpoints, the command timeout and zero-force safe state,
    and hil_sim's checks of bad input: unknown id, length, stale counter, NaN/Inf, DBC ranges,
    stroke and max_force). No stroke stops. For `legsim-bench run --dry-run` (trying a scene,
    the report and the plots without CAN) and the tests; it says nothing about the core."""

    def __init__(self, root: Path | None = None, *, perturb=None):
        import numpy as np

        from . import can_link as cl

        self.cl, self.np = cl, np
        self.root = root or find_root()
        self.db = __import__("cantools").database.load_file(str(self.root / "can" / "legsim.dbc"))
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
        import can

        msg = self.db.get_message_by_name(name)
        data = {s.name: 0 for s in msg.signals}
        data.update(signals)
        payload = msg.encode(data, strict=strict, padding=False, scaling=True)
        return can.Message(arbitration_id=msg.frame_id if frame_id is None else frame_id, data=payload,
                           is_extended_id=False, is_fd=True)

    def reset(self, variant="revolute", integrator="rk4", step_s=1e-3, pose=0, *, lengths=None,
              hold_length=False, disable=0, cmd_timeout_ms=None):
        from .reference import LegModel

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
        import math

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
        from .reference import ForceCommand, LengthCommand

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
