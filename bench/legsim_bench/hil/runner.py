"""Runs a scene against hil_sim over CAN and records everything (no analysis here).

The recording is plain JSON (`legsim-bench-recording/1`): the scene's TOML text, every
state sample hil_sim sent (positions, velocities, actuator lengths/rates/forces, reactions,
time, status, faults), every frame the bench sent that the reference model has to replay
(actuator commands and loads, as the float32 values on the bus, with the step they took
effect), the injected bad inputs, and the heartbeat. `legsim_bench.verdict.checks` turns it into
checks; nothing here imports numpy beyond what can_link needs, nor scipy or matplotlib, so
`legsim-bench record` stays light inside the QEMU VM.

Timeline of one exchange at a boundary step k (see Scene.boundaries()):
    ACT_CMD with both setpoints at t = k h (unless silent)   -> applies from step k on
    injected bad frames (if any at k)                       -> FAULT frames, nothing changes
    CONTROL STEP n (n = next boundary - k)                  -> one state sample at step k + n
"""
from __future__ import annotations

import datetime as _dt
import os
import platform
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import can

from ..recording import FORMAT, RecordingError
from ..scene import ACTUATORS, SEQ_SIGNALS, Scene, find_root
from .can_link import ACT_CMD, CONTROL, LOAD_CMD, ActMode, HilError, HilFault, SimState
from .cli_run import record_analysis

__all__ = ["record", "replay_trace", "HilProcess", "hil_sim_path", "f32"]


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
        from tqdm import tqdm   # optional: a progress bar only
    except ImportError:
        return None
    return tqdm(total=total, desc=desc, unit="step", leave=False, dynamic_ncols=True,
                disable=None if enabled is None else not enabled, file=sys.stderr)


def record(scene: Scene, link, *, progress: bool | None = None, log=None) -> dict:
    """Runs `scene` on the hil_sim behind `link` (a can_link.HilLink) and returns the recording.
    hil_sim errors (no answer, a refused RESET/STEP, HALTED) end the run early; they are in
    recording["errors"] and the checks fail on them.

    Only dynamics has frames in the DBC: a scene of another analysis runs in legsim_cli (the
    core on this host, legsim_bench.hil.cli_run) and `link` is not used; so does a robot dynamics
    scene given no link (link=None: its legsim_cli run, checked as the CLI's). A scene with its own
    model file needs a hil_sim started with --model FILE (HilProcess.for_scene).

    A robot scene (a model with contacts) runs on `hil_sim --robot` / `--model ROBOT.toml`:
    its four actuators' commands go to each leg's ACT_CMD (ACT_CMD_L1 for leg 1), its leg
    force elements to each leg's LOAD_CMD, contact_law and [[contact]] free in the RESET;
    every sample records per foot its state, events (Ct_Events), N, T, position, slip."""
    log = log or (lambda msg: None)
    if not scene.over_can or (link is None and scene.robot):
        # no frames for it, or a robot scene with no bus given: legsim_cli (its CLI path)
        return record_analysis(scene, log=log)

    legs = scene.legs
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
        "scene_resolved": scene.resolved(),
        "started": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "host": platform.node(), "python": platform.python_version(),
        "bus": str(getattr(link.bus, "channel_info", "")),
        "heartbeat": None, "samples": [], "commands": [], "loads": [], "injections": [],
        "late_faults": [], "errors": [], "complete": False, "initial_lengths": None,
        "legs": legs, "actuators": list(scene.actuator_names),
        # the link's answer timeout (s): a replay of the session's trace waits as long
        "timeout_s": float(link.timeout),
    }
    clock = getattr(link, "clock", time.monotonic)   # a replayed trace has its own
    t_wall0 = clock()
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
    if scene.robot:   # the feet's RESET options (Ctrl_ContactLaw, Ctrl_FreeContacts; START_CMD)
        def mask(state):
            return sum(1 << scene.model_info.contacts.index(c) for c, v in scene.contacts.items() if v == state)
        feet = {"contact_law": scene.contact_law, "free_contacts": mask("free")}
        if scene.start is not None:
            feet["start"] = {**{k: scene.start[k] for k in ("lift", "tilt", "velocity", "spin")},
                             "stuck_contacts": mask("stuck"), "sliding_contacts": mask("sliding")}
    fired: set = set()   # (contact, event) raised so far: a switch's
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
                sp = scene.setpoints(k, rec["initial_lengths"], fired)
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
                if scene.robot:   # each leg's own ACT_CMD (leg k: ACT_CMD_Lk)
                    per = len(args) // legs    # each leg's actuators (n is the STEP count)
                    seqs = [link.command(*args[per * g:per * g + per], leg=g) for g in range(legs)
                            if any(x is not None for x in args[per * g:per * g + per])]
                    seq = seqs[0]
                    logged["seqs"] = seqs
                else:
                    seq = link.command(*args)
                last_ok["ACT_CMD"] = seq
                rec["commands"].append({"step": k, "t": scene.t(k), "seq": seq, **logged})
            if k == 0 and scene.robot:
                # the state at t = 0 after the scene's t = 0 commands, the contact modes checked
                # there (STEP 0), as legsim_cli's first sample: it replaces the RESET's answer
                s = link.step(0)
                rec["samples"][0] = _state_dict(s, t_wall0)
                for f, c in zip(scene.model_info.contacts, rec["samples"][0].get("contacts", [])):
                    fired.update((f, e) for e in c["events"])
                last_ok["CONTROL"] = s.ctrl_seq
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
            for f, c in zip(scene.model_info.contacts if scene.robot else (), rec["samples"][-1].get("contacts", [])):
                fired.update((f, e) for e in c["events"])
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
    rec["wall_time_s"] = clock() - t_wall0
    return rec


def replay_trace(path, scene: Scene, *, dbc=None, timeout: float = 5.0) -> dict:
    """The recording of a session decoded from its raw CAN trace: `scene` is run again by
    record() on a link whose bus plays the trace back (hil/trace.py), so that the frames go
    through the link's own decoding and the runner's own bookkeeping, as live. `timeout`: the
    live link's (its recording's "timeout_s"), so that waits end as they did live. TraceError
    if the trace cannot be read or the scene sends other frames than the trace holds."""
    from .can_link import HilLink
    from .trace import TraceBus, TraceError

    bus = TraceBus(path)
    try:
        rec = record(scene, HilLink(bus=bus, dbc=dbc, timeout=timeout), progress=False)
    finally:
        bus.shutdown()
    if bus.unsent:
        raise TraceError(f"{path}: the scene {scene.name} stopped sending {bus.unsent} frames before "
                         "the trace's end: a trace of another scene")
    rec["trace"] = str(path)
    if not rec["complete"] and bus.ran_out:
        rec["errors"].append({"step": rec["samples"][-1]["step"] if rec["samples"] else None,
                              "error": f"the trace {path} ends while the bench waits for hil_sim: "
                              "cut short, or hil_sim stopped answering in the recorded session"})
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
