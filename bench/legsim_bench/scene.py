"""Scenes (scenes/*.toml, schema in scenes/README.md): what to run and what to check.

legsim_cli is the one reader of scene files (firmware_core/host/scene_parse.cpp): the bench
runs `legsim_cli SCENE --check` and builds its Scene from the resolved scene it prints (JSON),
refusals included, in legsim_cli's words. Dynamics runs on hil_sim over CAN, the other
analyses in legsim_cli. What is the bench's own stays here: the step grid and the exchanges
with hil_sim (boundaries, setpoints), the verdicts' default tolerances, and what its CAN link
and its reference model can carry (a scene legsim_cli runs may still be one the bench cannot).

Pure Python (json, subprocess, math): `legsim-bench record` runs where imports are slow (the
QEMU VM), so nothing here pulls numpy, scipy or matplotlib.

    from legsim_bench.scene import load_scene, shipped_scenes, find_root
    sc = load_scene("upper_step_50N")          # a scene of scenes/ by name, or a path
    sc.n_steps, sc.boundaries(), sc.setpoints(k)

Times in a scene are seconds; the bench works on the step grid: a time t is step round(t / h)
(legsim_cli refuses a time off the grid, by more than 1e-9 s). The bench is a sampled
controller: it sends its actuator setpoints at every exchange with hil_sim (every
`record_every` steps, and at every schedule or injection time), and hil_sim holds them until
the next one.
"""
from __future__ import annotations

import json
import math
import os
import re
import subprocess
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Scene", "ModelInfo", "SceneError", "RootNotFound", "Schedule", "ActuatorCommand", "Injection",
           "Checks", "StrokeCheck", "load_scene", "parse_scene", "scene_from_resolved", "find_root", "cli_path",
           "shipped_scenes", "is_hexapod_scene", "resolve_scene", "fault_codes", "scenes_dir", "ACTUATORS", "VARIANTS",
           "BUILTIN_MODEL", "DEFAULT_CHECKS", "ROBOT_DEFAULT_CHECKS", "DISABLE_FLAGS", "SEQ_SIGNALS"]

ACTUATORS = ("upper", "lower")
VARIANTS = ("revolute", "slot")          # Ctrl_Variant of the DBC (a model file may have more)
TIMED = ("dynamics", "inverse_dynamics")
BUILTIN_MODEL = "builtin:leg"
BUILTIN_ROBOT = "builtin:robot"          # models/robot.toml, compiled in when the capacities hold it
# legsim_default_options() of legsim.h: RESET carries no solver options, hil_sim runs these
DEFAULT_OPTIONS = {"rho_inf": 0.8, "max_newton_iter": 25, "newton_tol": 1e-10}
# legsim_disable bits (legsim.h), as Ctrl_Disable carries them
DISABLE_FLAGS = {"gravity": 0, "force_elements": 1, "reactions": 2, "projection": 3,
                 "actuators": 4, "stroke_limits": 5}
# sequence-counter signals of the bench -> hil_sim frames of can/legsim.dbc
SEQ_SIGNALS = {"CONTROL": "Ctrl_Seq", "ACT_CMD": "Act_Seq", "LOAD_CMD": "Load_Seq"}
GRID_TOL_S = 1e-9
CLI_TIMEOUT_S = 120


class SceneError(ValueError):
    """A scene file that cannot be run: the message names the file and the key."""


class RootNotFound(RuntimeError):
    """The legsim repository (models/leg.toml, can/legsim.dbc) could not be located."""


# ---- the repository --------------------------------------------------------------------

def _is_root(p: Path) -> bool:
    return (p / "models" / "leg.toml").is_file() and (p / "can" / "legsim.dbc").is_file()


def find_root(start: str | os.PathLike | None = None) -> Path:
    """The legsim repository: $LEGSIM_ROOT, else the first directory holding models/leg.toml
    and can/legsim.dbc walking up from `start` (or this package, then the working directory)."""
    env = os.environ.get("LEGSIM_ROOT")
    if env:
        p = Path(env).expanduser().resolve()
        if not _is_root(p):
            raise RootNotFound(f"LEGSIM_ROOT={env} does not hold models/leg.toml and can/legsim.dbc")
        return p
    starts = [Path(start)] if start is not None else [Path(__file__).resolve().parent, Path.cwd()]
    for s in starts:
        s = s.resolve()
        for p in (s, *s.parents):
            if _is_root(p):
                return p
    raise RootNotFound(
        "cannot find the legsim repository (a directory with models/leg.toml and can/legsim.dbc) "
        f"above {', '.join(str(s) for s in starts)}: run from inside the repository or set "
        "LEGSIM_ROOT=/path/to/legsim")


def cli_path(root: Path | None = None) -> Path:
    """legsim_cli: $LEGSIM_CLI, else the one of hil_sim's build ($LEGSIM_HIL_SIM's
    ../firmware_core/legsim_cli), else build/host/firmware_core/legsim_cli."""
    env = os.environ.get("LEGSIM_CLI")
    if env:
        return Path(env)
    hil = os.environ.get("LEGSIM_HIL_SIM")
    if hil:
        p = Path(hil).resolve().parent.parent / "firmware_core" / "legsim_cli"
        if p.is_file():
            return p
    return (root or find_root()) / "build" / "host" / "firmware_core" / "legsim_cli"


def scenes_dir(root: Path | None = None) -> Path:
    """scenes/: the one folder of scenes, shared with legsim_cli."""
    return (root or find_root()) / "scenes"


def fault_codes(dbc: str | os.PathLike | None = None) -> dict[str, int]:
    """FAULT codes by name, read from the DBC's value table of Fault_Code (no cantools)."""
    path = Path(dbc) if dbc is not None else find_root() / "can" / "legsim.dbc"
    text = path.read_text()
    m = re.search(r'^VAL_\s+\d+\s+Fault_Code\s+(.*?);', text, re.M)
    if not m:
        raise RootNotFound(f"{path}: no value table for Fault_Code")
    return {name: int(v) for v, name in re.findall(r'(\d+)\s+"([^"]+)"', m.group(1))}


# ---- schedules -------------------------------------------------------------------------

@dataclass(frozen=True)
class Schedule:
    """hold (value) | step (before, after, t0: `after` from t0 on) |
    sinusoid (offset + amplitude sin(2 pi frequency t + phase)) | initial (the value at the
    start of the run, i.e. the assembled length: filled in by the runner) | switch (before,
    after: `after` from the step after the one in which foot `contact` raised `event`; the
    caller says whether it has: Scene.setpoints' `fired`)."""
    kind: str
    value: float = 0.0
    before: float = 0.0
    after: float = 0.0
    t0: float = 0.0
    offset: float = 0.0
    amplitude: float = 0.0
    frequency: float = 0.0
    phase: float = 0.0
    event: str = ""          # switch: touchdown | liftoff | stick_to_slip | slip_to_stick
    contact: str = ""        # switch: the foot (a contact of the model)

    def __call__(self, t: float, initial: float | None = None, fired: bool = False) -> float:
        if self.kind == "hold":
            return self.value
        if self.kind == "step":
            return self.after if t >= self.t0 - GRID_TOL_S else self.before
        if self.kind == "sinusoid":
            return self.offset + self.amplitude * math.sin(2 * math.pi * self.frequency * t + self.phase)
        if self.kind == "switch":
            return self.after if fired else self.before
        if self.kind == "initial":
            if initial is None:
                raise ValueError("schedule 'initial' needs the initial value")
            return initial
        raise ValueError(self.kind)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.t0,) if self.kind == "step" else ()

    def describe(self, unit: str) -> str:
        if self.kind == "hold":
            return f"{self.value:g} {unit}"
        if self.kind == "step":
            return f"step {self.before:g} -> {self.after:g} {unit} at {self.t0:g} s"
        if self.kind == "switch":
            return f"{self.before:g} -> {self.after:g} {unit} after {self.contact}'s {self.event}"
        if self.kind == "sinusoid":
            ph = f" phase {self.phase:g}" if self.phase else ""
            return f"{self.offset:g} + {self.amplitude:g} sin(2pi {self.frequency:g} Hz t{ph}) {unit}"
        return "hold the initial length"

    def extremes(self) -> tuple[float, float] | None:
        if self.kind == "hold":
            return self.value, self.value
        if self.kind in ("step", "switch"):
            return min(self.before, self.after), max(self.before, self.after)
        if self.kind == "sinusoid":
            return self.offset - abs(self.amplitude), self.offset + abs(self.amplitude)
        return None


@dataclass(frozen=True)
class ActuatorCommand:
    actuator: int          # the model's actuator index (the leg: 0 upper, 1 lower)
    mode: str              # "force" (N, > 0 extends) | "length" (m, the servo holds it)
    schedule: Schedule
    actuator_name: str = ""   # a robot's prefixed name ("right.upper"); "" for the leg's

    @property
    def name(self) -> str:
        return self.actuator_name or ACTUATORS[self.actuator]

    def describe(self) -> str:
        return f"{self.name}: {self.mode} {self.schedule.describe('N' if self.mode == 'force' else 'm')}"


@dataclass(frozen=True)
class Injection:
    """A bad input sent before the exchange at step `step`: a raw frame, or a silence (no
    ACT_CMD for `silence_steps` steps). `expect` is a Fault_Code name of the DBC."""
    step: int
    expect: str
    label: str
    frame: str | None = None          # DBC message name, or None with frame_id for foreign ids
    frame_id: int | None = None
    signals: dict = field(default_factory=dict)
    seq: str | int = "next"           # next | stale | an integer
    length: int = 64
    expect_signal: str | None = None
    silence_steps: int = 0

    @property
    def is_silence(self) -> bool:
        return self.silence_steps > 0


@dataclass(frozen=True)
class StrokeCheck:
    actuator: int
    end: str                           # "min" | "max"
    tolerance_m: float


# tolerances (and options) of [checks]; None = not checked
ROBOT_CHECK_KEYS = {
    "ground_force_n": "per foot the normal and tangential ground force vs RobotModel (N)",
    "growth_rel": "the measured growth rate of the drift vs RobotModel's linearized modes (relative)",
    "in_stroke_m": "every actuator's length within its stroke widened by this, at every sample (m)",
    "slip_onset_steps": "the first stick_to_slip vs RobotModel's stuck-stuck |T|/N reaching mu_static "
                        "(steps), and which foot the contact law releases",
}
CHECK_KEYS = {
    **ROBOT_CHECK_KEYS,
    "position_m": "x, y of every body vs the reference model (m)",
    "angle_rad": "angle of every body vs the reference model (rad)",
    "reaction_n": "joint reaction forces vs the reference model (N)",
    "moment_nm": "joint reaction moments vs the reference model (N m)",
    "actuator_force_n": "actuator axial forces vs the reference model (N)",
    "residual": "max |Phi(q)| of the received positions, leg.toml's joint equations (m | rad)",
    "balance_n": "static balance of every body with the received reactions and forces (N)",
    "balance_nm": "static balance of moments (N m)",
    "stays_put_m": "largest displacement of any body from the first sample (m)",
    "statics_force_n": "received actuator forces vs the reference statics (N)",
    "statics_reaction_n": "received reactions vs the reference statics (N)",
}


@dataclass(frozen=True)
class Checks:
    position_m: float | None = None
    angle_rad: float | None = None
    reaction_n: float | None = None
    moment_nm: float | None = None
    actuator_force_n: float | None = None
    residual: float | None = None
    balance_n: float | None = None
    balance_nm: float | None = None
    stays_put_m: float | None = None
    statics_force_n: float | None = None
    statics_reaction_n: float | None = None
    ground_force_n: float | None = None
    growth_rel: float | None = None
    slip_onset_steps: float | None = None
    in_stroke_m: float | None = None
    events: bool = False               # a robot: against the event-locating reference (robot_events)
    compare: str = "all"               # "all" | "until_stroke": reference window
    stroke: StrokeCheck | None = None
    slips: tuple[str, ...] | None = None   # a robot: the feet that must go from stuck to sliding
    lifts: tuple[str, ...] | None = None   # a robot: the feet that must lift off and touch down stuck
    resolution_ratio: float = 0.1      # float32 quantum of a signal <= ratio * its tolerance

    def tolerances(self) -> dict[str, float]:
        return {k: getattr(self, k) for k in CHECK_KEYS if getattr(self, k) is not None}


@dataclass(frozen=True)
class ModelInfo:
    """What the bench needs of the scene's model, as legsim_cli read it: its file (the reference
    models read it themselves), actuators (name, stroke, max_force), poses, force elements
    (name, kind), contacts and legs."""
    path: Path
    builtin: bool                      # compiled in (models/leg.toml or models/robot.toml at build time)
    variants: tuple[str, ...]
    actuators: tuple[tuple[str, tuple[float, float], float], ...]
    poses: tuple[str, ...]
    forces: tuple[tuple[str, str], ...]   # (name, kind)
    contacts: tuple[str, ...] = ()        # a robot's feet ("right.foot", "left.foot")
    legs: int = 1                         # a robot's legs (one foot each)

    @property
    def robot(self) -> bool:
        """A model with contacts: a robot file ([box] + [[leg]], docs/design/robot-on-ground.md)."""
        return bool(self.contacts)


@dataclass
class Scene:
    name: str
    description: str
    path: Path | None
    source: str                        # the TOML text, as written (recordings carry it)
    variant: str
    integrator: str
    step_ns: int
    n_steps: int
    record_every: int
    pose: int                          # index of the pose in the model (Ctrl_Pose)
    lengths: tuple[float, ...] | None
    init: str                          # "zero_force" | "hold_length" (Ctrl_ActInit)
    cmd_timeout_ms: int                # 0 = none
    safe_state: str                    # what hil_sim does on a command timeout (its default)
    disable: tuple[str, ...]
    foot_load: tuple[float, float] | None
    commands: tuple[ActuatorCommand | None, ActuatorCommand | None]
    injections: tuple[Injection, ...]
    checks: Checks
    demo: bool = False
    analysis: str = "dynamics"
    model: str = BUILTIN_MODEL         # as written in the scene
    model_info: ModelInfo | None = None
    pose_name: str = "stand"
    forces: dict = field(default_factory=dict)   # force element name -> tuple of values
    grid: int = 11
    rho_inf: float = DEFAULT_OPTIONS["rho_inf"]
    max_newton_iter: int = DEFAULT_OPTIONS["max_newton_iter"]
    newton_tol: float = DEFAULT_OPTIONS["newton_tol"]
    contacts: dict = field(default_factory=dict)  # [[contact]]: contact name -> "stuck" | "free"
    statics_rule: str = "equal_friction"          # a robot's statics: legsim_statics_rule
    contact_law: str = "lcp"                      # a robot's dynamics: legsim_contact_law
    box_load: tuple | None = None                 # a robot's box: (Fx, Fy N, M N m)
    start: dict | None = None                     # a robot's [start]: lift, tilt, velocity, spin
    ground: dict | None = None                    # a robot's ground as run: point, slope, mu_static, mu_kinetic
    ground_given: bool = False                    # [ground] in the scene (else the model file's)
    resolved_json: dict = field(default_factory=dict)  # legsim_cli --check's JSON (recordings carry it)

    @property
    def robot(self) -> bool:
        """The model has contacts (a robot file): checked against RobotModel."""
        return self.model_info is not None and self.model_info.robot

    @property
    def legs(self) -> int:
        """The model's legs (a robot's [[leg]]s; 1 for a leg file): hil_sim's nodes on the bus."""
        return self.model_info.legs if self.model_info is not None else 1

    @property
    def actuator_names(self) -> tuple[str, ...]:
        return tuple(a[0] for a in self.model_info.actuators) if self.model_info else ACTUATORS

    @property
    def model_path(self) -> Path | None:
        """The model file: the scene's own, or models/leg.toml for the compiled-in leg (the
        file it was compiled from: the reference model reads it)."""
        return self.model_info.path if self.model_info else None

    @property
    def builtin_model(self) -> bool:
        return self.model_info is None or self.model_info.builtin

    @property
    def over_can(self) -> bool:
        """Dynamics runs on hil_sim over CAN (the leg, and the robot as two CAN nodes); the
        other analyses have no frames in the DBC and run in legsim_cli (the core on the host),
        checked against the same reference model. A robot scene with a key that no frame
        carries runs in legsim_cli too, saying why (can_refusal)."""
        return self.analysis == "dynamics" and self.can_refusal is None

    @property
    def can_refusal(self) -> str | None:
        """Why this dynamics scene cannot run over CAN (a key no frame of can/legsim.dbc
        carries), or None. None for every key today: a robot's contact_law and free feet go
        in the RESET, box_load in leg 0's LOAD_CMD (index 2, 3)."""
        return None

    def hil_args(self) -> list[str]:
        """hil_sim's options for this scene: --model FILE unless it is the compiled-in leg
        (a robot file: hil_sim runs it as the robot's two nodes)."""
        ground = []
        if self.robot and self.ground_given:   # a scene's [ground]: hil_sim --ground
            g = self.ground
            ground = ["--ground", ",".join(repr(float(g[k])) for k in ("slope", "mu_static", "mu_kinetic"))]
        if self.robot and self.model == BUILTIN_ROBOT:
            return ["--robot", *ground]
        return ([] if self.builtin_model else ["--model", str(self.model_path)]) + ground

    @property
    def step_s(self) -> float:
        return self.step_ns / 1e9

    @property
    def duration(self) -> float:
        return self.n_steps * self.step_s

    @property
    def disable_bits(self) -> int:
        return sum(1 << DISABLE_FLAGS[d] for d in self.disable)

    def t(self, k: int) -> float:
        return k * self.step_ns / 1e9

    def boundaries(self) -> list[int]:
        """Steps where the bench talks to hil_sim (commands, injections, one STEP exchange
        each): every record_every steps, schedule breakpoints, injection starts and ends."""
        b = set(range(0, self.n_steps, self.record_every))
        for c in self.commands:
            if c is not None:
                for t0 in c.schedule.breakpoints:
                    k = self.to_step(t0, "step t0")
                    if 0 < k < self.n_steps:
                        b.add(k)
        for inj in self.injections:
            b.add(inj.step)
            if inj.is_silence and inj.step + inj.silence_steps < self.n_steps:
                b.add(inj.step + inj.silence_steps)
        return sorted(k for k in b if 0 <= k < self.n_steps)

    def to_step(self, t: float, what: str = "time") -> int:
        return _on_grid(self._where(), t, self.step_ns, what)

    def setpoints(self, k: int, initial_lengths=None, fired=frozenset()) -> list[tuple[str, float] | None]:
        """(mode, value) per actuator at step k (None: no command for it). fired: the
        (contact, event) pairs raised by the steps before k (a switch's)."""
        t = self.t(k)
        out = []
        for a, c in enumerate(self.commands):
            if c is None:
                out.append(None)
                continue
            init = None if initial_lengths is None else float(initial_lengths[a])
            s = c.schedule
            out.append((c.mode, s(t, init, (s.contact, s.event) in fired)))
        return out

    @property
    def switches(self) -> bool:
        """A command switches on a contact event."""
        return any(c is not None and c.schedule.kind == "switch" for c in self.commands)

    def silent(self, k: int) -> bool:
        return any(i.is_silence and i.step <= k < i.step + i.silence_steps for i in self.injections)

    def summary(self) -> str:
        if not self.over_can:
            how = f"{self.analysis} in legsim_cli ({self.can_refusal or 'no CAN frames for it'})"
            if self.analysis == "inverse_dynamics":
                how += f", {self.duration:g} s ({self.n_steps} steps, a sample every {self.record_every})"
            return f"{self.variant}, {how}" + ("" if self.builtin_model else f", model {self.model}")
        h = self.step_s
        hs = f"{h * 1e3:g} ms" if h >= 1e-4 else f"{h * 1e6:g} us"
        return (f"{self.variant}, {self.integrator}, h = {hs}, {self.duration:g} s "
                f"({self.n_steps} steps, a sample every {self.record_every})"
                + ("" if self.builtin_model else f", model {self.model}"))

    def resolved(self) -> dict:
        """The resolved scene as legsim_cli --check printed it (the Scene is built from it)."""
        return json.loads(json.dumps(self.resolved_json))

    def _where(self) -> str:
        return str(self.path) if self.path else self.name


# ---- the verdicts' default tolerances -------------------------------------------------------
# (legsim_cli checks which [checks] keys apply to each analysis; without [checks] the bench
# checks these)
ROBOT_DEFAULT_CHECKS = {
    "dynamics": {"position_m": 1e-6, "angle_rad": 1e-6, "actuator_force_n": 1e-3, "ground_force_n": 1e-3,
                 "residual": 1e-8},
    "assembly": {"position_m": 1e-10, "angle_rad": 1e-10, "residual": 1e-10},
    "inverse_dynamics": {"position_m": 1e-8, "angle_rad": 1e-8, "residual": 1e-8, "actuator_force_n": 1e-6,
                         "reaction_n": 1e-6, "ground_force_n": 1e-6},
    "statics": {"position_m": 1e-10, "angle_rad": 1e-10, "residual": 1e-10, "statics_force_n": 1e-6,
                "statics_reaction_n": 1e-6, "ground_force_n": 1e-6},
}
DEFAULT_CHECKS = {
    "dynamics": {"position_m": 1e-5, "angle_rad": 1e-5, "reaction_n": 0.01, "moment_nm": 1e-3,
                 "actuator_force_n": 0.01, "residual": 1e-6},
    "statics": {"position_m": 1e-8, "angle_rad": 1e-8, "residual": 1e-8, "statics_force_n": 1e-6,
                "statics_reaction_n": 1e-6, "balance_n": 1e-6, "balance_nm": 1e-6},
    "statics_sweep": {"statics_force_n": 1e-6, "statics_reaction_n": 1e-6},
    "inverse_dynamics": {"position_m": 1e-8, "angle_rad": 1e-8, "residual": 1e-8,
                         "actuator_force_n": 1e-6, "reaction_n": 1e-6, "moment_nm": 1e-6},
    "assembly": {"position_m": 1e-8, "angle_rad": 1e-8, "residual": 1e-8},
}


def _fmt(x: float) -> str:
    """Shortest round-trip form, as legsim_cli writes numbers (std::to_chars)."""
    r = repr(float(x))
    return r[:-2] if r.endswith(".0") else r


def _on_grid(where: str, t: float, step_ns: int, what: str) -> int:
    k = round(t * 1e9 / step_ns)
    if abs(k * step_ns / 1e9 - t) > GRID_TOL_S:
        raise SceneError(f"{where}: {what} {_fmt(t)} s is not on the step grid (h = {_fmt(step_ns / 1e9)} s)")
    return k


def _number(v):
    """A number of the resolved JSON: legsim_cli writes a non-finite one as "nan", "inf", "-inf"."""
    return float(v) if isinstance(v, str) and v in ("nan", "inf", "-inf") else v


# ---- the resolved scene -> Scene --------------------------------------------------------------

def _schedule(c: dict) -> Schedule:
    if "step" in c:
        s = c["step"]
        return Schedule("step", t0=s["t0"], before=s["before"], after=s["after"])
    if "switch" in c:
        s = c["switch"]
        return Schedule("switch", before=s["before"], after=s["after"], event=s["event"], contact=s["contact"])
    if "sinusoid" in c:
        s = c["sinusoid"]
        return Schedule("sinusoid", offset=s["offset"], amplitude=s["amplitude"], frequency=s["frequency"],
                        phase=s["phase"])
    return Schedule("initial") if c["value"] == "initial" else Schedule("hold", value=c["value"])


def _checks(d: dict, info: ModelInfo) -> Checks:
    ch = d["checks"]
    if ch is None:   # scenes/README.md: the tolerances without [checks]
        ch = dict((ROBOT_DEFAULT_CHECKS if info.robot else DEFAULT_CHECKS)[d["analysis"]])
    kw = {k: float(ch[k]) for k in CHECK_KEYS if k in ch}
    for key in ("compare", "resolution_ratio"):
        if key in ch:
            kw[key] = ch[key]
    if "stroke" in ch:
        s = ch["stroke"]
        kw["stroke"] = StrokeCheck([a[0] for a in info.actuators].index(s["actuator"]), s["end"],
                                   float(s.get("tolerance_m", 1e-6)))
    for key in ("slips", "lifts"):
        if key in ch:
            kw[key] = tuple(ch[key])
    if ch.get("events"):
        kw["events"] = True
    return Checks(**kw)


def _injection(x: dict) -> Injection:
    if "silence_steps" in x:
        return Injection(step=x["step"], expect=x["expect"], label=x["label"], silence_steps=x["silence_steps"])
    return Injection(step=x["step"], expect=x["expect"], label=x["label"], frame=x["frame"],
                     frame_id=x["frame_id"], signals={k: _number(v) for k, v in x["signals"].items()},
                     seq=x["seq"], length=x["length"], expect_signal=x["expect_signal"])


def scene_from_resolved(d: dict, path: str | os.PathLike | None = None, source: str = "", *,
                        root: Path | None = None) -> Scene:
    """A Scene from legsim_cli --check's JSON (as recordings carry it): SceneError when the bench
    cannot run it (its CAN link or its reference model cannot carry what the scene asks)."""
    path = Path(path) if path is not None else None
    where = str(path) if path else d["name"]
    if d.get("kind") == "hexapod":
        raise SceneError(f"{where}: a hexapod scene: legsim_cli runs it (legsim_cli {path or where}); the bench "
                         "has no hexapod (hil_sim has none; legsim-bench hexapod walks it in process)")
    mi = d["model_info"]
    if d["model"].startswith("builtin:"):
        try:
            r = root or find_root()
        except RootNotFound as e:
            raise SceneError(f"{where}: {e}") from None
        model_path, builtin = r / "models" / (d["model"][len("builtin:"):] + ".toml"), True
    else:
        model_path, builtin = Path(d["model_path"]), False
    info = ModelInfo(model_path, builtin, (d["variant"],),
                     tuple((a["name"], (a["stroke"][0], a["stroke"][1]), a["max_force"]) for a in mi["actuators"]),
                     tuple(mi["poses"]), tuple((f["name"], f["kind"]) for f in mi["forces"]),
                     tuple(mi["contacts"]), mi["legs"])
    names = [a[0] for a in info.actuators]
    cmds: list[ActuatorCommand | None] = [None] * len(names)
    for name, c in d["commands"].items():
        a = names.index(name)
        cmds[a] = ActuatorCommand(a, c["mode"], _schedule(c), name if info.robot else "")
    forces = {k: tuple(v) for k, v in d["forces"].items()}
    pose_name = d["pose"]
    scene = Scene(name=d["name"], description=d["description"], path=path, source=source,
                  variant=d["variant"], integrator=d["integrator"], step_ns=d["step_ns"], n_steps=d["n_steps"],
                  record_every=d["record_every"], pose=info.poses.index(pose_name) if pose_name else 0,
                  lengths=tuple(d["lengths"]) if d["lengths"] is not None else None, init=d["init"],
                  cmd_timeout_ms=d["cmd_timeout_ms"], safe_state=d["safe_state"],
                  disable=tuple(k for k, b in DISABLE_FLAGS.items() if d["disable"] >> b & 1),
                  foot_load=None if info.robot else forces.get("foot_load"), commands=tuple(cmds),
                  injections=tuple(_injection(x) for x in d["inject"]), checks=_checks(d, info),
                  demo=d["demo"], analysis=d["analysis"], model=d["model"], model_info=info,
                  pose_name=pose_name, forces=forces, grid=d["grid"], rho_inf=d["rho_inf"],
                  max_newton_iter=d["max_newton_iter"], newton_tol=d["newton_tol"], contacts=dict(d["contacts"]),
                  statics_rule=d["statics_rule"], contact_law=d["contact_law"],
                  box_load=tuple(d["box_load"]) if d["box_load"] is not None else None, resolved_json=d,
                  start=d.get("start"), ground=d.get("ground"), ground_given=bool(d.get("ground_given")))
    if not info.robot:
        _bench_can_run_leg(scene, where)
    return scene


def _bench_can_run_leg(sc: Scene, where: str) -> None:
    """What the bench's CAN link (can/legsim.dbc) and its leg reference model can carry: the
    scene is legsim_cli's to run, the bench refuses it saying why."""
    names = sc.actuator_names
    if names != ACTUATORS:
        raise SceneError(f"{where}: the bench runs the leg's actuators {', '.join(ACTUATORS)} (the DBC's "
                         f"signals and the reference model); the model has {', '.join(names) or 'none'}")
    extra = sorted(set(sc.forces) - {"foot_load"})
    if extra:
        raise SceneError(f"{where}: the bench's reference model knows the force element foot_load only "
                         f"(got {', '.join(extra)})")
    model_forces = [f[0] for f in sc.model_info.forces]
    if sc.foot_load is not None and model_forces.index("foot_load") != 0:
        raise SceneError(f"{where}: foot_load is force element #{model_forces.index('foot_load')} of the model; "
                         "the bench sends it as LOAD_CMD Load_Index 0 (the leg's first [[force]])")
    if sc.variant != "revolute" and sc.analysis in ("statics", "statics_sweep", "inverse_dynamics"):
        raise SceneError(f"{where}: {sc.analysis} of the {sc.variant!r} variant: the bench's reference model "
                         "has statics and inverse dynamics for the revolute knee only (2 lengths, 2 dof)")
    if sc.analysis == "dynamics":
        if sc.variant not in VARIANTS:
            raise SceneError(f"{where}: over CAN the variant is Ctrl_Variant: revolute or slot (got {sc.variant!r})")
        if sc.pose > 1:
            raise SceneError(f"{where}: over CAN the pose is Ctrl_Pose 0..1; {sc.pose_name!r} is pose #{sc.pose}")
        for key, dv in DEFAULT_OPTIONS.items():
            if getattr(sc, key) != dv:
                raise SceneError(f"{where}: {key} = {getattr(sc, key)!r}: RESET carries no solver options and "
                                 f"hil_sim runs the core's default ({dv!r}); dynamics over CAN cannot use another")


# ---- reading a scene: legsim_cli --check -------------------------------------------------------

def _check(args: list[str], where: str, text: str | None, root: Path | None) -> dict:
    cli = cli_path(root)
    if not cli.is_file():
        raise SceneError(f"{where}: legsim_cli reads the scene files, and it is not at {cli}: build it "
                         "(cmake --build --preset host --target legsim_cli) or set LEGSIM_CLI")
    try:
        r = subprocess.run([str(cli), *args, "--check"], input=text, capture_output=True, text=True,
                           timeout=CLI_TIMEOUT_S)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise SceneError(f"{where}: cannot run {cli}: {e}") from None
    if r.returncode != 0:
        msg = r.stderr.strip().removeprefix("legsim_cli: error: ")
        raise SceneError(msg or f"{where}: legsim_cli --check exit {r.returncode}")
    try:
        return json.loads(r.stdout)
    except json.JSONDecodeError as e:
        raise SceneError(f"{where}: legsim_cli --check wrote no JSON ({e})") from None


def parse_scene(text: str, path: str | os.PathLike | None = None, *, root: Path | None = None,
                name: str | None = None) -> Scene:
    """A Scene from TOML text, read by legsim_cli as if it were the file at `path` (its name,
    its folder for a relative model path; else `name` in the working directory). SceneError
    on anything that cannot be run, in legsim_cli's words."""
    as_path = str(path) if path is not None else (name or "scene")
    d = _check(["-", "--as", as_path], as_path, text, root)
    return scene_from_resolved(d, Path(path) if path is not None else None, text, root=root)


def load_scene(spec: str | os.PathLike, root: Path | None = None) -> Scene:
    path = resolve_scene(spec, root)
    d = _check([str(path)], str(path), None, root)
    try:
        source = path.read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(f"{path}: cannot read: {e}") from None
    return scene_from_resolved(d, path, source, root=root)


def is_hexapod_scene(path: str | os.PathLike) -> bool:
    """The scene's `model` is a hexapod file ([yoke], [rowing] or [[box_contact]]: a block's
    included, as the model loader tells one, legsim_toml_is_hexapod_file): legsim_cli runs it (scenes/README.md, "The hexapod"); the bench has no
    hexapod (hil_sim has none, the reference models are planar). False for a file that does not
    parse (legsim_cli then says why)."""
    try:
        spec = tomllib.loads(Path(path).read_text())
        model = spec.get("model")
        if not isinstance(model, str) or not model or model.startswith("builtin:"):
            return False
        mp = Path(model) if Path(model).is_absolute() else Path(path).parent / model
        m = tomllib.loads(mp.read_text())
        return "yoke" in m or "rowing" in m or "box_contact" in m
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False


def shipped_scenes(root: Path | None = None, *, hexapod: bool = False) -> list[Path]:
    """The scenes of scenes/ the bench runs; with hexapod=True the hexapod's too (legsim_cli's
    only: is_hexapod_scene)."""
    d = scenes_dir(root)
    paths = sorted(d.glob("*.toml")) if d.is_dir() else []
    return paths if hexapod else [p for p in paths if not is_hexapod_scene(p)]


def resolve_scene(spec: str | os.PathLike, root: Path | None = None) -> Path:
    """A scene path from a path or the name of a shipped scene ("upper_step_50N", "demo")."""
    p = Path(spec)
    if p.suffix == ".toml" or p.exists():
        if not p.is_file():
            raise SceneError(f"{p}: no such scene file")
        return p
    ships = shipped_scenes(root, hexapod=True)
    if str(spec) == "demo":
        for s in shipped_scenes(root):
            try:
                if _check([str(s)], str(s), None, root)["demo"]:
                    return s
            except SceneError:
                continue
        raise SceneError("no shipped scene is marked demo = true")
    for s in ships:
        if s.stem.lower() == str(spec).lower():
            return s
    names = ", ".join(s.stem for s in ships) or "none"
    raise SceneError(f"no scene {spec!r}: not a file, nor a shipped scene ({names})")
