"""Scenes (scenes/*.toml, schema in scenes/README.md): what to run and what to check.

legsim_cli reads the same files (firmware_core/host/scene_parse.cpp) with the same rules and
messages; dynamics runs on hil_sim over CAN, the other analyses in legsim_cli.

Pure Python (tomllib, math): `legsim-bench record` runs where imports are slow (the QEMU VM),
so nothing here pulls numpy, scipy or matplotlib.

    from legsim_bench.scene import load_scene, shipped_scenes, find_root
    sc = load_scene("upper_step_50N")          # a scene of scenes/ by name, or a path
    sc.n_steps, sc.boundaries(), sc.setpoints(k)

Times in a scene are seconds; the bench works on the step grid: a time t is step round(t / h)
(it must lie on the grid, within 1e-9 s). The bench is a sampled controller: it sends its
actuator setpoints at every exchange with hil_sim (every `record_every` steps, and at every
schedule or injection time), and hil_sim holds them until the next one.
"""
from __future__ import annotations

import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Scene", "ModelInfo", "SceneError", "RootNotFound", "Schedule", "ActuatorCommand", "Injection",
           "Checks", "StrokeCheck", "load_scene", "parse_scene", "find_root", "cli_path", "shipped_scenes",
           "resolve_scene", "fault_codes", "scenes_dir", "ACTUATORS", "VARIANTS", "INTEGRATORS",
           "ANALYSES", "BUILTIN_MODEL", "RENAMED_KEYS", "DEFAULT_CHECKS",
           "DISABLE_FLAGS", "FRAME_IDS", "SEQ_SIGNALS", "FD_LENGTHS"]

ACTUATORS = ("upper", "lower")
VARIANTS = ("revolute", "slot")          # Ctrl_Variant of the DBC (a model file may have more)
INTEGRATORS = ("rk4", "generalized_alpha")
ANALYSES = ("dynamics", "statics", "statics_sweep", "inverse_dynamics", "assembly")
TIMED = ("dynamics", "inverse_dynamics")
BUILTIN_MODEL = "builtin:leg"
BUILTIN_ROBOT = "builtin:robot"          # models/robot.toml, compiled in when the capacities hold it
# legsim_default_options() of legsim.h (tests compare them with legsim_cli --check)
DEFAULT_OPTIONS = {"rho_inf": 0.8, "max_newton_iter": 25, "newton_tol": 1e-10}
MAX_RECORD_EVERY = 10_000_000           # the DBC's largest STEP (Ctrl_NSteps)
# The bounds legsim_cli applies (firmware_core/host/scene_parse.cpp, toml_limits.hpp, legsim.h).
MAX_TOML_BYTES = 1024 * 1024
MAX_SAMPLES = 1_000_000                 # n_steps / record_every + 1
MAX_FREQUENCY_HZ = 1e3
MAX_PHASE_RAD = 1e3                     # LEGSIM_MAX_COORD
MAX_TIME_S = 1e9                        # LEGSIM_MAX_TIME_S
MAX_FORCE_N = 1e6                       # LEGSIM_MAX_FORCE_N
NEWTON_TOL_RANGE = (1e-15, 1e-3)        # LEGSIM_MIN/MAX_NEWTON_TOL
# legsim_disable bits (legsim.h), as Ctrl_Disable carries them
DISABLE_FLAGS = {"gravity": 0, "force_elements": 1, "reactions": 2, "projection": 3,
                 "actuators": 4, "stroke_limits": 5}
# bench -> hil_sim frames of can/legsim.dbc and their sequence-counter signals
FRAME_IDS = {"CONTROL": 0x080, "ACT_CMD": 0x100, "LOAD_CMD": 0x110}
SEQ_SIGNALS = {"CONTROL": "Ctrl_Seq", "ACT_CMD": "Act_Seq", "LOAD_CMD": "Load_Seq"}
FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)
GRID_TOL_S = 1e-9


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
    start of the run, i.e. the assembled length: filled in by the runner)."""
    kind: str
    value: float = 0.0
    before: float = 0.0
    after: float = 0.0
    t0: float = 0.0
    offset: float = 0.0
    amplitude: float = 0.0
    frequency: float = 0.0
    phase: float = 0.0

    def __call__(self, t: float, initial: float | None = None) -> float:
        if self.kind == "hold":
            return self.value
        if self.kind == "step":
            return self.after if t >= self.t0 - GRID_TOL_S else self.before
        if self.kind == "sinusoid":
            return self.offset + self.amplitude * math.sin(2 * math.pi * self.frequency * t + self.phase)
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
        if self.kind == "sinusoid":
            ph = f" phase {self.phase:g}" if self.phase else ""
            return f"{self.offset:g} + {self.amplitude:g} sin(2pi {self.frequency:g} Hz t{ph}) {unit}"
        return "hold the initial length"

    def extremes(self) -> tuple[float, float] | None:
        if self.kind == "hold":
            return self.value, self.value
        if self.kind == "step":
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
    compare: str = "all"               # "all" | "until_stroke": reference window
    stroke: StrokeCheck | None = None
    slips: tuple[str, ...] | None = None   # a robot: the feet that must go from stuck to sliding
    lifts: tuple[str, ...] | None = None   # a robot: the feet that must lift off and touch down stuck
    resolution_ratio: float = 0.1      # float32 quantum of a signal <= ratio * its tolerance

    def tolerances(self) -> dict[str, float]:
        return {k: getattr(self, k) for k in CHECK_KEYS if getattr(self, k) is not None}


@dataclass(frozen=True)
class ModelInfo:
    """What the scene reader needs of a model file (its own reading of the TOML: pure Python,
    no core): variant names, actuators (name, stroke, max_force), pose and force names."""
    path: Path
    builtin: bool                      # the compiled-in leg (models/leg.toml at build time)
    variants: tuple[str, ...]
    actuators: tuple[tuple[str, tuple[float, float], float], ...]
    poses: tuple[str, ...]
    forces: tuple[tuple[str, str], ...]   # (name, kind)
    contacts: tuple[str, ...] = ()        # a robot's feet ("right.foot", "left.foot")
    legs: int = 1                         # a robot's [[leg]]s

    @property
    def robot(self) -> bool:
        """A model with contacts: a robot file ([box] + [[leg]], docs/design/robot-on-ground.md)."""
        return bool(self.contacts)

    @staticmethod
    def _load(path: Path, where: str) -> dict:
        try:
            return tomllib.loads(Path(path).read_text())
        except OSError as e:
            raise SceneError(f"{where}: model {path}: cannot read: {e.strerror or e}") from None
        except tomllib.TOMLDecodeError as e:
            raise SceneError(f"{where}: model {path}: not valid TOML: {e}") from None

    @classmethod
    def read(cls, path: Path, builtin: bool, where: str) -> "ModelInfo":
        data = cls._load(path, where)
        try:
            if "box" in data and "leg" in data:
                # a robot file: each [[leg]] places a leg file; names take the leg's prefix, in
                # the loader's order (the box, then each leg's items in its file's order)
                acts, forces, contacts = [], [], []
                for ld in data["leg"]:
                    leg = cls._load(Path(path).parent / str(ld["file"]), where)
                    pre = str(ld.get("prefix", str(ld["name"]) + "."))
                    acts += [(pre + str(a["name"]), (float(a["stroke"][0]), float(a["stroke"][1])),
                              float(a["max_force"])) for a in leg.get("actuator", [])]
                    forces += [(pre + str(f["name"]), str(f.get("kind", ""))) for f in leg.get("force", [])]
                    if "foot" in leg:
                        contacts.append(pre + "foot")
                return cls(Path(path), builtin, ("revolute",), tuple(acts),
                           tuple(str(p) for p in data.get("pose", {})), tuple(forces), tuple(contacts),
                           len(data["leg"]))
            acts = tuple((str(a["name"]), (float(a["stroke"][0]), float(a["stroke"][1])),
                          float(a["max_force"])) for a in data.get("actuator", []))
            forces = tuple((str(f["name"]), str(f.get("kind", ""))) for f in data.get("force", []))
        except (KeyError, TypeError, ValueError, IndexError) as e:
            raise SceneError(f"{where}: model {path}: bad [[actuator]], [[force]] or [[leg]] ({e!r})") from None
        variants = ("revolute", *[str(v) for v in data.get("variant", {})])
        return cls(Path(path), builtin, variants, acts, tuple(str(p) for p in data.get("pose", {})),
                   forces)


@dataclass
class Scene:
    name: str
    description: str
    path: Path | None
    source: str                        # the TOML text (recordings carry it)
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
        if self.robot and self.model == BUILTIN_ROBOT:
            return ["--robot"]
        return [] if self.builtin_model else ["--model", str(self.model_path)]

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

    def setpoints(self, k: int, initial_lengths=None) -> list[tuple[str, float] | None]:
        """(mode, value) per actuator at step k (None: no command for it)."""
        t = self.t(k)
        out = []
        for a, c in enumerate(self.commands):
            if c is None:
                out.append(None)
                continue
            init = None if initial_lengths is None else float(initial_lengths[a])
            out.append((c.mode, c.schedule(t, init)))
        return out

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
        """The values legsim_cli --check prints for the same file (tests compare the two)."""
        cmds = {}
        for c in self.commands:
            if c is None:
                continue
            s = c.schedule
            if s.kind == "hold":
                sig = {"value": s.value}
            elif s.kind == "initial":
                sig = {"value": "initial"}
            elif s.kind == "step":
                sig = {"step": {"t0": s.t0, "before": s.before, "after": s.after}}
            else:
                sig = {"sinusoid": {"offset": s.offset, "amplitude": s.amplitude,
                                    "frequency": s.frequency, "phase": s.phase}}
            cmds[c.name] = {"mode": c.mode, **sig}
        timed = self.analysis in TIMED
        raw = tomllib.loads(self.source) if self.source else {}
        return {"name": self.name, "model": self.model,
                "model_path": "" if self.model.startswith("builtin:") else str(self.model_path),
                "variant": self.variant, "analysis": self.analysis, "integrator": self.integrator,
                "step_ns": self.step_ns, "n_steps": self.n_steps if timed else 0,
                "record_every": self.record_every, "pose": self.pose_name,
                "lengths": list(self.lengths) if self.lengths is not None else None,
                "grid": self.grid, "init": self.init, "cmd_timeout_ms": self.cmd_timeout_ms,
                "safe_state": self.safe_state, "disable": self.disable_bits, "rho_inf": self.rho_inf,
                "max_newton_iter": self.max_newton_iter, "newton_tol": self.newton_tol,
                "statics_rule": self.statics_rule, "contact_law": self.contact_law, "forces": {k: list(v) for k, v in self.forces.items()}, "commands": cmds,
                "contacts": dict(self.contacts),
                "box_load": list(self.box_load) if self.box_load is not None else None,
                # the bench's sections as written (legsim_cli --check prints them so)
                "checks": _json_numbers(raw.get("checks")), "inject": _json_numbers(raw.get("inject", []))}

    def _where(self) -> str:
        return str(self.path) if self.path else self.name


# ---- parsing ---------------------------------------------------------------------------

_TOP_KEYS = {"description", "name", "demo", "model", "variant", "analysis", "integrator",
             "step_s", "duration", "record_every", "disable", "rho_inf", "max_newton_iter",
             "newton_tol", "pose", "lengths", "grid", "init", "cmd_timeout_ms", "safe_state",
             "box_load",
             "forces", "command", "contact", "inject", "checks", "statics_rule", "contact_law"}
CONTACT_STATES = ("stuck", "free")
# legsim_statics_rule: what fixes the statics of a stance on two stuck feet (legsim.h)
STATICS_RULES = ("equal_friction", "min_tangential")
# legsim_contact_law: the feet's transitions in a step (legsim.h): each foot by its own
# Coulomb cone, or the paper's rule (the foot with the smaller |T| is released)
CONTACT_LAWS = ("lcp", "paper")
# The keys and values of the two former schemas and what they are now (legsim_cli says the
# same words: firmware_core/host/scene_parse.cpp).
RENAMED_KEYS = {
    "output_every": "'output_every' is now 'record_every' (steps between recorded samples)",
    "decimation": "'decimation' is now 'record_every' (steps between recorded samples)",
    "step": "'step' is now 'step_s' (the step size, s); 'step = { t0, before, after }' is a step "
            "signal in a [[command]]",
    "foot_load": "'foot_load' is now a force element value: [forces] foot_load = [Fx, Fy] (N)",
}
RENAMED_VALUES = {"force_zero": "zero_force", "zero-force": "zero_force", "hold-length": "hold_length"}
ACTUATOR_MODES = ("zero_force", "hold_length")
# [checks] keys that apply to each analysis, and the tolerances used when a scene gives none
_DYN_CHECKS = (set(CHECK_KEYS) - set(ROBOT_CHECK_KEYS)) | {"compare", "stroke", "resolution_ratio"}
# a robot scene (legsim_cli against RobotModel, legsim_bench.verdict.analyses)
ROBOT_CHECKS_FOR = {
    "dynamics": {"position_m", "angle_rad", "residual", "actuator_force_n", "reaction_n", "ground_force_n",
                 "stays_put_m", "growth_rel", "slips", "lifts", "slip_onset_steps"},
    "assembly": {"position_m", "angle_rad", "residual"},
    "inverse_dynamics": {"position_m", "angle_rad", "residual", "actuator_force_n", "reaction_n",
                         "ground_force_n"},
    "statics": {"position_m", "angle_rad", "residual", "statics_force_n", "statics_reaction_n",
                "ground_force_n"},
}
ROBOT_DEFAULT_CHECKS = {
    "dynamics": {"position_m": 1e-6, "angle_rad": 1e-6, "actuator_force_n": 1e-3, "ground_force_n": 1e-3,
                 "residual": 1e-8},
    "assembly": {"position_m": 1e-10, "angle_rad": 1e-10, "residual": 1e-10},
    "inverse_dynamics": {"position_m": 1e-8, "angle_rad": 1e-8, "residual": 1e-8, "actuator_force_n": 1e-6,
                         "reaction_n": 1e-6, "ground_force_n": 1e-6},
    "statics": {"position_m": 1e-10, "angle_rad": 1e-10, "residual": 1e-10, "statics_force_n": 1e-6,
                "statics_reaction_n": 1e-6, "ground_force_n": 1e-6},
}
CHECKS_FOR = {
    "dynamics": _DYN_CHECKS,
    "statics": {"position_m", "angle_rad", "residual", "statics_force_n", "statics_reaction_n",
                "balance_n", "balance_nm"},
    "statics_sweep": {"statics_force_n", "statics_reaction_n"},
    "inverse_dynamics": {"position_m", "angle_rad", "residual", "actuator_force_n", "reaction_n",
                         "moment_nm"},
    "assembly": {"position_m", "angle_rad", "residual"},
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


def _json_numbers(v):
    """As legsim_cli --check writes a bench section: a non-finite number is "nan", "inf", "-inf"."""
    if isinstance(v, dict):
        return {k: _json_numbers(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_json_numbers(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def _num(where, key, v, *, positive=False, finite=True) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise SceneError(f"{where}: {key} must be a number, not {v!r}")
    v = float(v)
    if finite and not math.isfinite(v):
        raise SceneError(f"{where}: {key} must be finite")
    if positive and not v > 0:
        raise SceneError(f"{where}: {key} must be > 0")
    return v


def _int(where, key, v, lo=None, hi=None) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise SceneError(f"{where}: {key} must be an integer, not {v!r}")
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        raise SceneError(f"{where}: {key} = {v} outside {lo}..{hi}")
    return v


def _choice(where, key, v, options) -> str:
    if isinstance(v, str) and v in RENAMED_VALUES and v not in options:
        raise SceneError(f'{where}: {key} = "{v}" is now {key} = "{RENAMED_VALUES[v]}"')
    if not isinstance(v, str) or v.lower() not in options:
        raise SceneError(f"{where}: {key} must be one of {', '.join(options)}, not {v!r}")
    return v.lower()


def _rule_choice(where, v, key="statics_rule", options=STATICS_RULES) -> str:
    """'statics_rule' or 'contact_law' with legsim_cli's words (scene_parse.cpp: choice)."""
    if v not in options:
        raise SceneError(f"{where}: '{key}' must be {' or '.join(options)} (got {v!r})")
    return v


def _unknown(where, d: dict, allowed) -> None:
    extra = sorted(set(d) - set(allowed))
    if extra:
        raise SceneError(f"{where}: unknown key(s) {', '.join(extra)} (allowed: {', '.join(sorted(allowed))})")


def _contact_list(where: str, d: dict, key: str, info) -> list:
    """d[key]: a list of the model's contacts (info.contacts), else a SceneError naming them."""
    feet = d[key]
    if not isinstance(feet, list) or not all(isinstance(x, str) and x in info.contacts for x in feet):
        raise SceneError(f"{where}: '{key}' must be a list of the model's contacts ({', '.join(info.contacts)})")
    return feet


def _fmt(x: float) -> str:
    """Shortest round-trip form, as legsim_cli writes numbers (std::to_chars)."""
    r = repr(float(x))
    return r[:-2] if r.endswith(".0") else r


def _on_grid(where: str, t: float, step_ns: int, what: str) -> int:
    k = round(t * 1e9 / step_ns)
    if abs(k * step_ns / 1e9 - t) > GRID_TOL_S:
        raise SceneError(f"{where}: {what} {_fmt(t)} s is not on the step grid (h = {_fmt(step_ns / 1e9)} s)")
    return k


def _pair(where, key, v) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2:
        raise SceneError(f"{where}: {key} must be a list of two numbers")
    return (_num(where, key, v[0]), _num(where, key, v[1]))


def _schedule(where: str, c: dict) -> Schedule:
    kinds = [k for k in ("value", "step", "sinusoid") if k in c]
    if len(kinds) != 1:
        raise SceneError(f"{where}: give exactly one of value, step, sinusoid")
    k = kinds[0]
    if k == "value":
        v = c["value"]
        if v == "initial":
            return Schedule("initial")
        return Schedule("hold", value=_num(where, "value (a number, or \"initial\")", v))
    if k == "step":
        s = c["step"]
        if not isinstance(s, dict):
            raise SceneError(f"{where}: step must be a table {{t0, before, after}}")
        _unknown(f"{where} step", s, {"t0", "before", "after"})
        for key in ("t0", "after"):
            if key not in s:
                raise SceneError(f"{where}: step needs {key}")
        t0 = _num(where, "step.t0", s["t0"])
        if not 0 <= t0 <= MAX_TIME_S:
            raise SceneError(f"{where}: step: 't0' must be in [0, {MAX_TIME_S:g}] s (got {_fmt(t0)})")
        return Schedule("step", t0=t0,
                        before=_num(where, "step.before", s.get("before", 0.0)),
                        after=_num(where, "step.after", s["after"]))
    s = c["sinusoid"]
    if not isinstance(s, dict):
        raise SceneError(f"{where}: sinusoid must be a table {{offset, amplitude, frequency}}")
    _unknown(f"{where} sinusoid", s, {"offset", "amplitude", "frequency", "phase"})
    for key in ("offset", "amplitude", "frequency"):
        if key not in s:
            raise SceneError(f"{where}: sinusoid needs {key}")
    freq = _num(where, "frequency", s["frequency"], positive=True)
    if freq > MAX_FREQUENCY_HZ:
        raise SceneError(f"{where}: frequency must be at most {MAX_FREQUENCY_HZ:g} Hz (got {_fmt(freq)})")
    phase = _num(where, "phase", s.get("phase", 0.0))
    if abs(phase) > MAX_PHASE_RAD:
        raise SceneError(f"{where}: phase must be in [-{MAX_PHASE_RAD:g}, {MAX_PHASE_RAD:g}] rad "
                         f"(got {_fmt(phase)})")
    return Schedule("sinusoid", offset=_num(where, "offset", s["offset"]),
                    amplitude=_num(where, "amplitude", s["amplitude"]),
                    frequency=freq, phase=phase)


def _model(where: str, spec, path: Path | None, root: Path | None) -> ModelInfo:
    """The scene's model: "builtin:leg" (hil_sim's and legsim_cli's compiled-in leg; the bench
    reads the file it was compiled from, models/leg.toml) or a file relative to the scene."""
    if not isinstance(spec, str) or not spec:
        raise SceneError(f"{where}: model must name a model file (or \"{BUILTIN_MODEL}\")")
    if spec.startswith("builtin:"):
        if spec not in (BUILTIN_MODEL, BUILTIN_ROBOT):
            raise SceneError(f"{where}: unknown builtin model {spec[8:]!r} (this build has: leg, robot)")
        try:
            r = root or find_root()
        except RootNotFound as e:
            raise SceneError(f"{where}: {e}") from None
        return ModelInfo.read(r / "models" / (spec[8:] + ".toml"), True, where)
    p = Path(spec)
    if not p.is_absolute():
        p = (path.parent if path is not None else Path.cwd()) / p
    return ModelInfo.read(p, False, where)


def _robot_scene(d: dict, where: str, text: str, path: Path | None, root: Path | None, info: ModelInfo,
                 **kw) -> Scene:
    """The rest of a scene whose model has contacts (a robot file): legsim_cli runs it (the
    in-process bench; the DBC has no robot frames here), the bench checks it against RobotModel
    (legsim_bench.verdict.analyses). Actuators by their prefixed names; [[contact]] initial states.
    The refusals are legsim_cli's words (scene_parse.cpp: parse_scene, bind_scene)."""
    analysis = kw["analysis"]
    if analysis == "statics_sweep":
        raise SceneError(f"{where}: statics_sweep of a model with contacts is not in this core yet (the legs "
                         "move, the feet cannot stay on the ground): run dynamics, statics, inverse_dynamics or "
                         "assembly")
    if "inject" in d:
        raise SceneError(f"{where}: [[inject]] is not for a robot scene (the bench's injections are the one leg's "
                         "frames; tests/hil/test_robot_can.py sends the robot bad frames)")
    names = tuple(a[0] for a in info.actuators)
    raw_cmds = d.get("command", [])
    if raw_cmds and analysis not in TIMED:
        raise SceneError(f"{where}: [[command]] applies to dynamics and inverse_dynamics only")
    if not isinstance(raw_cmds, list):
        raise SceneError(f"{where}: 'command' must be an array of tables ([[command]])")
    cmds: list[ActuatorCommand | None] = [None] * len(names)
    for i, c in enumerate(raw_cmds):
        if not isinstance(c, dict):
            raise SceneError(f"{where}: 'command' must be an array of tables ([[command]])")
        _unknown(f"{where}: command #{i + 1}", c, {"actuator", "mode", "value", "step", "sinusoid"})
        act = c.get("actuator")
        if not isinstance(act, str):
            raise SceneError(f"{where}: command #{i + 1}: 'actuator' must be a string")
        cw = f"{where}: command '{act}'"
        if act not in names:
            raise SceneError(f"{cw}: the model has no actuator '{act}'")
        a = names.index(act)
        if cmds[a] is not None:
            raise SceneError(f"{cw}: a second command for the same actuator")
        mode = c.get("mode")
        if mode not in ("force", "length"):
            raise SceneError(f"{cw}: 'mode' must be force or length (got {mode!r})")
        sch = _schedule(cw, c)
        if analysis == "inverse_dynamics" and mode != "length":
            raise SceneError(f"{cw}: inverse_dynamics prescribes lengths: use mode = \"length\"")
        if sch.kind == "initial" and mode != "length":
            raise SceneError(f"{cw}: value = \"initial\" is for mode = \"length\" (hold the assembled length)")
        if sch.kind == "step":
            _on_grid(where, sch.t0, kw["step_ns"], f"command '{act}': step t0 =")
        if sch.extremes() is not None:
            _, (smin, smax), fmax = info.actuators[a]
            lo, hi = sch.extremes()
            if mode == "force" and max(abs(lo), abs(hi)) > fmax:
                raise SceneError(f"{cw}: forces up to {_fmt(max(abs(lo), abs(hi)))} N exceed max_force "
                                 f"{_fmt(fmax)} N")
            if mode == "length" and (lo < smin or hi > smax):
                raise SceneError(f"{cw}: lengths {_fmt(lo)}..{_fmt(hi)} m leave the stroke [{_fmt(smin)}, "
                                 f"{_fmt(smax)}]")
        cmds[a] = ActuatorCommand(a, mode, sch, act)

    contacts: dict[str, str] = {}
    raw = d.get("contact", [])
    if raw and analysis not in ("dynamics", "assembly"):
        raise SceneError(f"{where}: [[contact]] applies to dynamics and assembly only")
    if not isinstance(raw, list) or not all(isinstance(x, dict) for x in raw):
        raise SceneError(f"{where}: 'contact' must be an array of tables ([[contact]])")
    for i, c in enumerate(raw):
        _unknown(f"{where}: contact #{i + 1}", c, {"name", "state"})
        cname = c.get("name")
        if not isinstance(cname, str):
            raise SceneError(f"{where}: contact #{i + 1}: missing key 'name'")
        cw = f"{where}: contact '{cname}'"
        if cname in contacts:
            raise SceneError(f"{cw}: a second [[contact]] for the same contact")
        state = c.get("state")
        if state not in CONTACT_STATES:
            raise SceneError(f"{cw}: 'state' must be stuck or free (got {state!r})")
        if cname not in info.contacts:
            raise SceneError(f"{cw}: the model has no contact '{cname}' (contacts: {', '.join(info.contacts)})")
        contacts[cname] = state

    ch = d.get("checks")
    if ch is None:
        ch = dict(ROBOT_DEFAULT_CHECKS[analysis])
    if not isinstance(ch, dict):
        raise SceneError(f"{where}: [checks] must be a table")
    _unknown(f"{where} [checks] (robot {analysis})", ch, ROBOT_CHECKS_FOR[analysis])
    slips = None
    if "slips" in ch:
        # the feet that must slip (stick_to_slip): RobotModel's stance on stuck feet is then
        # no reference, and the checks against it do not apply
        slips = _contact_list(f"{where} [checks]", ch, "slips", info)
        # with slip_onset_steps the stance is compared up to the first slip, where it still holds
        before = ("position_m", "angle_rad", "ground_force_n") if "slip_onset_steps" in ch else ()
        against = sorted(k for k in ch if k not in ("slips", "residual", "slip_onset_steps") + before)
        if against:
            raise SceneError(f"{where} [checks]: {', '.join(against)} compare with RobotModel's stance on "
                             "stuck feet, which 'slips' leaves: leave them out")
        slips = tuple(slips)
    if "slip_onset_steps" in ch and not slips:
        raise SceneError(f"{where} [checks]: 'slip_onset_steps' needs 'slips' (the foot that slips first)")
    lifts = None
    if "lifts" in ch:
        # the feet that must lift off and touch down again (stuck): RobotModel's stance on
        # both stuck feet is the reference until the first lift-off only
        lifts = _contact_list(f"{where} [checks]", ch, "lifts", info)
        against = sorted(k for k in ch if k not in ("lifts", "residual", "position_m", "angle_rad"))
        if against or slips:
            raise SceneError(f"{where} [checks]: {', '.join(against or ['slips'])} compare with RobotModel's "
                             "stance on stuck feet, which 'lifts' leaves: leave them out")
        lifts = tuple(lifts)
    checks = Checks(**{k: _num(f"{where} [checks]", k, ch[k], positive=True) for k in CHECK_KEYS if k in ch},
                    slips=slips, lifts=lifts)
    if not checks.tolerances():
        raise SceneError(f"{where}: [checks] names nothing to check")
    return Scene(name=kw["sname"], description=str(d.get("description", "")), path=path, source=text,
                 variant=kw["variant"], integrator=kw["integrator"], step_ns=kw["step_ns"],
                 n_steps=kw["n_steps"], record_every=kw["rec"], pose=kw["pose"], lengths=kw["lengths"],
                 init=kw["init"], cmd_timeout_ms=_int(where, "cmd_timeout_ms", d.get("cmd_timeout_ms", 0), 0, 65534),
                 safe_state=_choice(where, "safe_state", d.get("safe_state", "zero_force"), ACTUATOR_MODES),
                 disable=kw["disable"], foot_load=None, commands=tuple(cmds), injections=(), checks=checks,
                 demo=bool(d.get("demo", False)), analysis=analysis, model=kw["model_spec"], model_info=info,
                 pose_name=kw["pose_name"], forces=kw["forces"], rho_inf=kw["rho_inf"],
                 max_newton_iter=kw["max_iter"], newton_tol=kw["newton_tol"], contacts=contacts,
                 statics_rule=kw["statics_rule"], contact_law=kw["contact_law"], box_load=kw["box_load"])



def parse_scene(text: str, path: str | os.PathLike | None = None, *, root: Path | None = None,
                name: str | None = None) -> Scene:
    """A Scene from TOML text (SceneError on anything that cannot be run). The rules are
    legsim_cli's (scenes/README.md); on top, what the bench cannot do says why."""
    path = Path(path) if path is not None else None
    where = str(path) if path else (name or "scene")
    if len(text.encode("utf-8", "surrogatepass")) > MAX_TOML_BYTES:
        raise SceneError(f"{where}: TOML input refused: larger than {MAX_TOML_BYTES} bytes")
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{where}: not valid TOML: {e}") from None
    except RecursionError:  # tomllib recurses per nesting level
        raise SceneError(f"{where}: TOML input refused: nested too deeply") from None
    for old, msg in RENAMED_KEYS.items():
        if old in d:
            raise SceneError(f"{where}: {msg}")
    _unknown(where, d, _TOP_KEYS)
    sname = d.get("name") or name or (path.stem if path else "scene")
    if not isinstance(sname, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", sname):
        raise SceneError(f"{where}: name must be letters, digits, '_', '-', '.': {sname!r}")
    if not isinstance(d.get("demo", False), bool):
        raise SceneError(f"{where}: demo must be true or false")

    analysis = _choice(where, "analysis", d.get("analysis", "dynamics"), ANALYSES)
    timed = analysis in TIMED
    dynamics = analysis == "dynamics"

    def only(key, applies, which):
        if key in d and not applies:
            raise SceneError(f"{where}: '{key}' applies to {which} only")

    model_spec = d.get("model", BUILTIN_MODEL)
    info = _model(where, model_spec, path, root)
    variant = d.get("variant", "revolute")
    if not isinstance(variant, str) or variant not in info.variants:
        raise SceneError(f"{where}: variant {variant!r} is not in the model {info.path.name} "
                         f"(available: {', '.join(info.variants)})")
    integrator = _choice(where, "integrator", d.get("integrator", "rk4"), INTEGRATORS)
    h = _num(where, "step_s", d.get("step_s", 0.001))
    step_ns = round(h * 1e9)
    if not h > 0 or abs(step_ns / 1e9 - h) > 1e-15 or not 1000 <= step_ns <= 100_000_000:
        raise SceneError(f"{where}: 'step_s' must be a whole number of ns in 1 us .. 100 ms (got {_fmt(h)})")
    rho_inf = _num(where, "rho_inf", d.get("rho_inf", DEFAULT_OPTIONS["rho_inf"]))
    if not 0 <= rho_inf <= 1:
        raise SceneError(f"{where}: 'rho_inf' must be in [0, 1] (got {_fmt(rho_inf)})")
    max_iter = _int(where, "max_newton_iter", d.get("max_newton_iter", DEFAULT_OPTIONS["max_newton_iter"]),
                    1, 1000)
    newton_tol = _num(where, "newton_tol", d.get("newton_tol", DEFAULT_OPTIONS["newton_tol"]), positive=True)
    if not NEWTON_TOL_RANGE[0] <= newton_tol <= NEWTON_TOL_RANGE[1]:
        raise SceneError(f"{where}: 'newton_tol' must be in [{NEWTON_TOL_RANGE[0]:g}, "
                         f"{NEWTON_TOL_RANGE[1]:g}] (m, rad; got {_fmt(newton_tol)})")
    disable = d.get("disable", [])
    if not isinstance(disable, list):
        raise SceneError(f"{where}: disable must be a list of names")
    disable = tuple(_choice(where, "disable", x, tuple(DISABLE_FLAGS)) for x in disable)

    only("duration", timed, "dynamics and inverse_dynamics")
    only("record_every", timed, "dynamics and inverse_dynamics")
    n_steps, rec = 0, 1
    if timed:
        if "duration" not in d:
            raise SceneError(f"{where}: missing key 'duration' (s)")
        dur = _num(where, "duration", d["duration"], positive=True)
        n_steps = math.floor(dur * 1e9 / step_ns + 0.5)
        if abs(n_steps * step_ns / 1e9 - dur) > GRID_TOL_S:
            lo = math.floor(dur * 1e9 / step_ns)
            raise SceneError(f"{where}: 'duration' {_fmt(dur)} s is not a whole number of steps of "
                             f"{_fmt(h)} s ({_fmt(lo * step_ns / 1e9)} or {_fmt((lo + 1) * step_ns / 1e9)} "
                             "s would be)")
        if not 1 <= n_steps <= 1e9:
            raise SceneError(f"{where}: 'duration' / 'step_s' must give 1 to 1e9 steps")
        rec = _int(where, "record_every", d.get("record_every", 1), 1, MAX_RECORD_EVERY)
        if n_steps // rec + 1 > MAX_SAMPLES:
            raise SceneError(f"{where}: 'duration' / ('step_s' x 'record_every') asks for "
                             f"{n_steps // rec + 1} samples, more than {MAX_SAMPLES}: raise 'record_every'")

    pose_name = d.get("pose", info.poses[0] if info.poses else None)
    if pose_name is None:
        raise SceneError(f"{where}: the model has no pose to assemble")
    if not isinstance(pose_name, str):
        raise SceneError(f"{where}: pose must be the name of a pose of the model (e.g. pose = \"stand\")")
    if pose_name not in info.poses:
        raise SceneError(f"{where}: pose {pose_name!r} is not in the model (poses: "
                         f"{', '.join(info.poses) or 'none'})")
    pose = info.poses.index(pose_name)
    lengths = None
    if "lengths" in d:
        if analysis == "statics_sweep":
            raise SceneError(f"{where}: 'lengths' does not apply to statics_sweep")
        v = d["lengths"]
        if not isinstance(v, list) or len(v) != len(info.actuators):
            raise SceneError(f"{where}: 'lengths' must hold {len(info.actuators)} values, one per actuator")
        lengths = tuple(_num(where, "lengths", x) for x in v)
        for a, (an, (smin, smax), _) in enumerate(info.actuators):
            if not smin <= lengths[a] <= smax:
                raise SceneError(f"{where}: lengths[{a}] = {_fmt(lengths[a])} m is outside the stroke of "
                                 f"actuator '{an}' [{_fmt(smin)}, {_fmt(smax)}]")
    only("grid", analysis == "statics_sweep", "statics_sweep")
    only("statics_rule", analysis in ("statics", "inverse_dynamics"), "statics and inverse_dynamics")
    statics_rule = _rule_choice(where, d.get("statics_rule", "equal_friction"))
    if "statics_rule" in d and not info.robot:
        raise SceneError(f"{where}: 'statics_rule' applies to a model with contacts only (a stance on two feet)")
    only("contact_law", dynamics, "dynamics")
    contact_law = _rule_choice(where, d.get("contact_law", "lcp"), "contact_law", CONTACT_LAWS)
    if "contact_law" in d and not info.robot:
        raise SceneError(f"{where}: 'contact_law' applies to a model with contacts only (a robot's feet)")
    # a load on a robot's box: [Fx, Fy] N at its centre and M N m (legsim_cli: box_load_add)
    only("box_load", analysis in ("dynamics", "statics", "inverse_dynamics"), "statics, dynamics and inverse_dynamics")
    box_load = None
    if "box_load" in d:
        v = d["box_load"]
        if not isinstance(v, list) or len(v) != 3:
            raise SceneError(f"{where}: 'box_load' must be [Fx, Fy, M] (N, N, N m: a load on the box)")
        box_load = tuple(_num(where, "'box_load'", x) for x in v)
        if any(abs(x) > MAX_FORCE_N for x in box_load):
            raise SceneError(f"{where}: 'box_load' must be within +-{MAX_FORCE_N:g} (N, N, N m)")
        if not info.robot:
            raise SceneError(f"{where}: 'box_load' applies to a model with contacts only (the robot's box)")
        for fname, _ in info.forces:
            if fname in ("box.load", "box.moment"):
                raise SceneError(f"{where}: 'box_load': the model has a force element named '{fname}' already")
    grid = _int(where, "grid", d.get("grid", 11), 2, 1000)
    only("init", dynamics, "dynamics")
    init = _choice(where, "init", d.get("init", "zero_force"), ACTUATOR_MODES)
    for key in ("cmd_timeout_ms", "safe_state", "inject"):
        only(key, dynamics, "dynamics (over CAN)")
    timeout = _int(where, "cmd_timeout_ms", d.get("cmd_timeout_ms", 0), 0, 65534)
    safe = _choice(where, "safe_state", d.get("safe_state", "zero_force"), ACTUATOR_MODES)

    forces = {}
    fv = d.get("forces", {})
    if not isinstance(fv, dict):
        raise SceneError(f"{where}: 'forces' must be a table: NAME = [Fx, Fy] or NAME = torque")
    kinds = dict(info.forces)
    for fname, v in fv.items():
        w = f"forces.{fname}"
        vals = [v] if not isinstance(v, list) else v
        if not 1 <= len(vals) <= 2:
            raise SceneError(f"{where}: {w} must be a number or an array of 1 or 2 numbers")
        vals = tuple(_num(where, w, x) for x in vals)
        if any(abs(x) > MAX_FORCE_N for x in vals):
            raise SceneError(f"{where}: {w} must be within +-{MAX_FORCE_N:g} (N or N m)")
        if fname not in kinds:
            raise SceneError(f"{where}: {w}: the model has no force element '{fname}'")
        if kinds[fname] == "point" and len(vals) != 2:
            raise SceneError(f"{where}: {w}: a point force takes [Fx, Fy] (N)")
        if kinds[fname] == "torque" and len(vals) != 1:
            raise SceneError(f"{where}: {w}: a torque takes one value (N m)")
        if kinds[fname] == "spring_damper":
            raise SceneError(f"{where}: {w}: a spring_damper has no value to set")
        forces[fname] = vals

    act_names = tuple(a[0] for a in info.actuators)
    if info.robot:
        return _robot_scene(d, where, text, path, root, info, sname=sname, analysis=analysis,
                            model_spec=model_spec, variant=variant, integrator=integrator,
                            step_ns=step_ns, n_steps=n_steps, rec=rec, pose=pose, pose_name=pose_name,
                            lengths=lengths, init=init, disable=disable, forces=forces,
                            rho_inf=rho_inf, max_iter=max_iter, newton_tol=newton_tol,
                            statics_rule=statics_rule, contact_law=contact_law, box_load=box_load)
    # The bench knows the leg: the DBC carries two actuators, upper and lower, and its
    # reference model the one force element foot_load.
    if act_names != ACTUATORS:
        raise SceneError(f"{where}: the bench runs the leg's actuators {', '.join(ACTUATORS)} (the DBC's "
                         f"signals and the reference model); the model has {', '.join(act_names) or 'none'}")
    extra = sorted(set(forces) - {"foot_load"})
    if extra:
        raise SceneError(f"{where}: the bench's reference model knows the force element foot_load only "
                         f"(got {', '.join(extra)})")
    foot = forces.get("foot_load")
    load_index = [f[0] for f in info.forces].index("foot_load") if foot is not None else 0
    if load_index != 0:
        raise SceneError(f"{where}: foot_load is force element #{load_index} of the model; the bench "
                         "sends it as LOAD_CMD Load_Index 0 (the leg's first [[force]])")
    if variant != "revolute" and analysis in ("statics", "statics_sweep", "inverse_dynamics"):
        raise SceneError(f"{where}: {analysis} of the {variant!r} variant: the bench's reference model "
                         "has statics and inverse dynamics for the revolute knee only (2 lengths, 2 dof)")
    if dynamics:
        # what RESET and the frames cannot carry: refused, with the reason
        if variant not in VARIANTS:
            raise SceneError(f"{where}: over CAN the variant is Ctrl_Variant: revolute or slot (got {variant!r})")
        if pose > 1:
            raise SceneError(f"{where}: over CAN the pose is Ctrl_Pose 0..1; {pose_name!r} is pose #{pose}")
        for key, dv in DEFAULT_OPTIONS.items():
            if key in d and d[key] != dv:
                raise SceneError(f"{where}: {key} = {d[key]!r}: RESET carries no solver options and hil_sim "
                                 f"runs the core's default ({dv!r}); dynamics over CAN cannot use another")

    cmds: list[ActuatorCommand | None] = [None, None]
    raw_cmds = d.get("command", [])
    if raw_cmds and not timed:
        raise SceneError(f"{where}: [[command]] applies to dynamics and inverse_dynamics only")
    if not isinstance(raw_cmds, list):
        raise SceneError(f"{where}: command must be an array of tables [[command]]")
    for i, c in enumerate(raw_cmds):
        cw = f"{where} [[command]] #{i + 1}"
        if not isinstance(c, dict):
            raise SceneError(f"{cw}: must be a table")
        _unknown(cw, c, {"actuator", "mode", "value", "step", "sinusoid"})
        act = _choice(cw, "actuator", c.get("actuator"), ACTUATORS)
        a = ACTUATORS.index(act)
        if cmds[a] is not None:
            raise SceneError(f"{cw}: a second command for actuator {act}")
        mode = _choice(cw, "mode", c.get("mode"), ("force", "length"))
        if analysis == "inverse_dynamics" and mode != "length":
            raise SceneError(f"{cw}: inverse_dynamics prescribes lengths: use mode = \"length\"")
        sch = _schedule(cw, c)
        if sch.kind == "initial" and mode != "length":
            raise SceneError(f"{cw}: value = \"initial\" is for mode = \"length\" (hold the assembled length)")
        if sch.kind == "step":
            _on_grid(where, sch.t0, step_ns, f"command '{act}': step t0 =")
        if sch.extremes() is not None:
            _, (smin, smax), fmax = info.actuators[a]
            lo, hi = sch.extremes()
            if mode == "force" and max(abs(lo), abs(hi)) > fmax:
                raise SceneError(f"{cw}: |force| up to {max(abs(lo), abs(hi)):g} N exceeds max_force {fmax:g} N")
            if mode == "length" and (lo < smin or hi > smax):
                raise SceneError(f"{cw}: lengths {lo:g}..{hi:g} m leave the stroke {smin:g}..{smax:g} m")
        cmds[a] = ActuatorCommand(a, mode, sch)

    codes = None
    try:
        codes = fault_codes((root or find_root()) / "can" / "legsim.dbc")
    except (RootNotFound, OSError):
        pass

    scene = Scene(name=sname, description=str(d.get("description", "")), path=path, source=text,
                  variant=variant, integrator=integrator, step_ns=step_ns, n_steps=n_steps,
                  record_every=rec, pose=pose, lengths=lengths, init=init,
                  cmd_timeout_ms=timeout, safe_state=safe, disable=disable, foot_load=foot,
                  commands=(cmds[0], cmds[1]), injections=(), checks=Checks(),
                  demo=bool(d.get("demo", False)), analysis=analysis, model=model_spec,
                  model_info=info, pose_name=pose_name, forces=forces, grid=grid, rho_inf=rho_inf,
                  max_newton_iter=max_iter, newton_tol=newton_tol)
    if timeout and rec * step_ns >= timeout * 1_000_000:
        raise SceneError(f"{where}: an exchange every {rec * step_ns / 1e6:g} ms (record_every x step_s) "
                         f"would let the {timeout} ms command timeout trip between ACT_CMDs")

    injections = []
    raw_inj = d.get("inject", [])
    if not isinstance(raw_inj, list):
        raise SceneError(f"{where}: inject must be an array of tables [[inject]]")
    for i, x in enumerate(raw_inj):
        iw = f"{where} [[inject]] #{i + 1}"
        if not isinstance(x, dict):
            raise SceneError(f"{iw}: must be a table")
        _unknown(iw, x, {"at", "frame", "signals", "seq", "length", "expect", "expect_signal",
                         "silence", "label"})
        if "at" not in x or "expect" not in x:
            raise SceneError(f"{iw}: needs at (s) and expect (a Fault_Code name)")
        k = scene.to_step(_num(iw, "at", x["at"]), "at")
        if not 0 <= k < n_steps:
            raise SceneError(f"{iw}: at = {x['at']} s is outside the run (0 .. {dur:g} s)")
        expect = str(x["expect"]).upper()
        if codes is not None and expect not in codes:
            raise SceneError(f"{iw}: expect = {x['expect']!r} is not a Fault_Code of the DBC "
                             f"({', '.join(codes)})")
        label = str(x.get("label", ""))
        if "silence" in x:
            if "frame" in x:
                raise SceneError(f"{iw}: give frame or silence, not both")
            ns = scene.to_step(_num(iw, "silence", x["silence"], positive=True), "silence")
            if timeout == 0:
                raise SceneError(f"{iw}: a silence needs cmd_timeout_ms > 0")
            injections.append(Injection(step=k, expect=expect, label=label or f"silence {x['silence']:g} s",
                                        silence_steps=ns))
            continue
        fr = x.get("frame")
        if isinstance(fr, str):
            frame = fr.upper()
            if frame not in FRAME_IDS:
                raise SceneError(f"{iw}: frame must be one of {', '.join(FRAME_IDS)} or an integer id")
            fid = FRAME_IDS[frame]
        elif isinstance(fr, int) and not isinstance(fr, bool) and 0 <= fr < (1 << 11):
            frame, fid = None, fr
        else:
            raise SceneError(f"{iw}: frame must be a DBC message name or an 11-bit id")
        sig = x.get("signals", {})
        if not isinstance(sig, dict):
            raise SceneError(f"{iw}: signals must be a table")
        for sk, sv in sig.items():
            if isinstance(sv, bool) or not isinstance(sv, (int, float)):
                raise SceneError(f"{iw}: signal {sk} must be a number (nan and inf allowed)")
        seq = x.get("seq", "next")
        if not (seq in ("next", "stale") or (isinstance(seq, int) and not isinstance(seq, bool)
                                              and 0 <= seq < 2 ** 32)):
            raise SceneError(f"{iw}: seq must be \"next\", \"stale\" or a 32-bit integer")
        if frame is None and seq == "stale":
            raise SceneError(f"{iw}: seq = \"stale\" needs a DBC frame")
        length = _int(iw, "length", x.get("length", 64), 0, 64)
        if length not in FD_LENGTHS:
            raise SceneError(f"{iw}: length must be a CAN FD payload length {FD_LENGTHS}")
        esig = x.get("expect_signal")
        injections.append(Injection(step=k, expect=expect, label=label or f"{fr} {sig}", frame=frame,
                                    frame_id=fid, signals=dict(sig), seq=seq, length=length,
                                    expect_signal=str(esig) if esig is not None else None))
    scene.injections = tuple(sorted(injections, key=lambda i: i.step))

    ch = d.get("checks")
    if ch is None:
        ch = dict(DEFAULT_CHECKS[analysis])   # scenes/README.md: the tolerances without [checks]
    if not isinstance(ch, dict):
        raise SceneError(f"{where}: [checks] must be a table")
    _unknown(f"{where} [checks] ({analysis})", ch, CHECKS_FOR[analysis])
    kw = {k: _num(f"{where} [checks]", k, ch[k], positive=True) for k in CHECK_KEYS if k in ch}
    if "compare" in ch:
        kw["compare"] = _choice(f"{where} [checks]", "compare", ch["compare"], ("all", "until_stroke"))
    if "resolution_ratio" in ch:
        kw["resolution_ratio"] = _num(f"{where} [checks]", "resolution_ratio", ch["resolution_ratio"], positive=True)
    if "stroke" in ch:
        s = ch["stroke"]
        sw = f"{where} [checks.stroke]"
        if not isinstance(s, dict):
            raise SceneError(f"{sw}: must be a table {{actuator, end, tolerance_m}}")
        _unknown(sw, s, {"actuator", "end", "tolerance_m"})
        kw["stroke"] = StrokeCheck(ACTUATORS.index(_choice(sw, "actuator", s.get("actuator"), ACTUATORS)),
                                   _choice(sw, "end", s.get("end"), ("min", "max")),
                                   _num(sw, "tolerance_m", s.get("tolerance_m", 1e-6), positive=True))
    scene.checks = Checks(**kw)
    if not scene.checks.tolerances() and not scene.injections and scene.checks.stroke is None:
        raise SceneError(f"{where}: [checks] names nothing to check")
    return scene


def shipped_scenes(root: Path | None = None) -> list[Path]:
    d = scenes_dir(root)
    return sorted(d.glob("*.toml")) if d.is_dir() else []


def resolve_scene(spec: str | os.PathLike, root: Path | None = None) -> Path:
    """A scene path from a path or the name of a shipped scene ("upper_step_50N", "demo")."""
    p = Path(spec)
    if p.suffix == ".toml" or p.exists():
        if not p.is_file():
            raise SceneError(f"{p}: no such scene file")
        return p
    ships = shipped_scenes(root)
    if str(spec) == "demo":
        demos = [s for s in ships if _is_demo(s)]
        if demos:
            return demos[0]
        raise SceneError("no shipped scene is marked demo = true")
    for s in ships:
        if s.stem.lower() == str(spec).lower():
            return s
    names = ", ".join(s.stem for s in ships) or "none"
    raise SceneError(f"no scene {spec!r}: not a file, nor a shipped scene ({names})")


def _is_demo(path: Path) -> bool:
    try:
        return bool(tomllib.loads(path.read_text()).get("demo", False))
    except (OSError, tomllib.TOMLDecodeError):
        return False


def load_scene(spec: str | os.PathLike, root: Path | None = None) -> Scene:
    path = resolve_scene(spec, root)
    if path.stat().st_size > MAX_TOML_BYTES:  # refused before it is read
        raise SceneError(f"{path}: TOML input refused: larger than {MAX_TOML_BYTES} bytes")
    return parse_scene(path.read_text(), path, root=root)
