"""Bench scenes: what to run against hil_sim and what to check (TOML, schema in bench/README.md).

Pure Python (tomllib, math): `legsim-bench record` runs where imports are slow (the QEMU VM),
so nothing here pulls numpy, scipy or matplotlib.

    from legsim_bench.scene import load_scene, shipped_scenes, find_root
    sc = load_scene("upper_step_50N")          # a shipped scene by name, or a path
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

__all__ = ["Scene", "SceneError", "RootNotFound", "Schedule", "ActuatorCommand", "Injection",
           "Checks", "StrokeCheck", "load_scene", "parse_scene", "find_root", "shipped_scenes",
           "resolve_scene", "fault_codes", "ACTUATORS", "VARIANTS", "INTEGRATORS",
           "DISABLE_FLAGS", "FRAME_IDS", "SEQ_SIGNALS", "FD_LENGTHS"]

ACTUATORS = ("upper", "lower")
VARIANTS = ("revolute", "slot")
INTEGRATORS = ("rk4", "generalized_alpha")
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


def scenes_dir(root: Path | None = None) -> Path:
    return (root or find_root()) / "bench" / "scenes"


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
    actuator: int          # 0 upper, 1 lower
    mode: str              # "force" (N, > 0 extends) | "length" (m, the servo holds it)
    schedule: Schedule

    @property
    def name(self) -> str:
        return ACTUATORS[self.actuator]

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
CHECK_KEYS = {
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
    compare: str = "all"               # "all" | "until_stroke": reference window
    stroke: StrokeCheck | None = None
    resolution_ratio: float = 0.1      # float32 quantum of a signal <= ratio * its tolerance

    def tolerances(self) -> dict[str, float]:
        return {k: getattr(self, k) for k in CHECK_KEYS if getattr(self, k) is not None}


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
    pose: int
    lengths: tuple[float, float] | None
    init: str                          # "force_zero" | "hold_length" (Ctrl_ActInit)
    cmd_timeout_ms: int                # 0 = none
    safe_state: str                    # what hil_sim does on a command timeout (its default)
    disable: tuple[str, ...]
    foot_load: tuple[float, float] | None
    commands: tuple[ActuatorCommand | None, ActuatorCommand | None]
    injections: tuple[Injection, ...]
    checks: Checks
    demo: bool = False

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
        k = round(t * 1e9 / self.step_ns)
        if abs(k * self.step_s - t) > GRID_TOL_S:
            raise SceneError(f"{self._where()}: {what} {t!r} s is not on the step grid "
                             f"(h = {self.step_s:g} s)")
        return k

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
        h = self.step_s
        hs = f"{h * 1e3:g} ms" if h >= 1e-4 else f"{h * 1e6:g} us"
        return (f"{self.variant}, {self.integrator}, h = {hs}, {self.duration:g} s "
                f"({self.n_steps} steps, a sample every {self.record_every})")

    def _where(self) -> str:
        return str(self.path) if self.path else self.name


# ---- parsing ---------------------------------------------------------------------------

_TOP_KEYS = {"name", "description", "demo", "variant", "integrator", "step", "duration",
             "record_every", "decimation", "pose", "lengths", "init", "cmd_timeout_ms",
             "safe_state", "disable", "foot_load", "command", "inject", "checks"}


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
    if not isinstance(v, str) or v.lower() not in options:
        raise SceneError(f"{where}: {key} must be one of {', '.join(options)}, not {v!r}")
    return v.lower()


def _unknown(where, d: dict, allowed) -> None:
    extra = sorted(set(d) - set(allowed))
    if extra:
        raise SceneError(f"{where}: unknown key(s) {', '.join(extra)} (allowed: {', '.join(sorted(allowed))})")


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
        return Schedule("hold", value=_num(where, "value", v))
    if k == "step":
        s = c["step"]
        if not isinstance(s, dict):
            raise SceneError(f"{where}: step must be a table {{t0, before, after}}")
        _unknown(f"{where} step", s, {"t0", "before", "after"})
        for key in ("t0", "after"):
            if key not in s:
                raise SceneError(f"{where}: step needs {key}")
        return Schedule("step", t0=_num(where, "step.t0", s["t0"]),
                        before=_num(where, "step.before", s.get("before", 0.0)),
                        after=_num(where, "step.after", s["after"]))
    s = c["sinusoid"]
    if not isinstance(s, dict):
        raise SceneError(f"{where}: sinusoid must be a table {{offset, amplitude, frequency}}")
    _unknown(f"{where} sinusoid", s, {"offset", "amplitude", "frequency", "phase"})
    for key in ("offset", "amplitude", "frequency"):
        if key not in s:
            raise SceneError(f"{where}: sinusoid needs {key}")
    return Schedule("sinusoid", offset=_num(where, "offset", s["offset"]),
                    amplitude=_num(where, "amplitude", s["amplitude"]),
                    frequency=_num(where, "frequency", s["frequency"], positive=True),
                    phase=_num(where, "phase", s.get("phase", 0.0)))


def _model_limits(root: Path | None) -> dict | None:
    """Strokes and max forces from models/leg.toml, to refuse impossible commands early."""
    try:
        path = (root or find_root()) / "models" / "leg.toml"
        data = tomllib.loads(path.read_text())
    except (RootNotFound, OSError, tomllib.TOMLDecodeError):
        return None
    out = {}
    for a in data.get("actuator", []):
        out[a["name"]] = (tuple(map(float, a["stroke"])), float(a["max_force"]))
    return out


def parse_scene(text: str, path: str | os.PathLike | None = None, *, root: Path | None = None,
                name: str | None = None) -> Scene:
    """A Scene from TOML text (SceneError on anything that cannot be run)."""
    path = Path(path) if path is not None else None
    where = str(path) if path else (name or "scene")
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{where}: not valid TOML: {e}") from None
    _unknown(where, d, _TOP_KEYS)
    sname = d.get("name") or name or (path.stem if path else "scene")
    if not isinstance(sname, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", sname):
        raise SceneError(f"{where}: name must be letters, digits, '_', '-', '.': {sname!r}")

    variant = _choice(where, "variant", d.get("variant", "revolute"), VARIANTS)
    integrator = _choice(where, "integrator", d.get("integrator", "rk4"), INTEGRATORS)
    h = _num(where, "step", d.get("step", 0.001), positive=True)
    step_ns = round(h * 1e9)
    if abs(step_ns / 1e9 - h) > 1e-15 or not 1000 <= step_ns <= 100_000_000:
        raise SceneError(f"{where}: step must be a whole number of ns in 1 us .. 100 ms, not {h!r}")
    dur = _num(where, "duration", d.get("duration"), positive=True) if "duration" in d else None
    if dur is None:
        raise SceneError(f"{where}: duration (s) is required")
    n_steps = round(dur * 1e9 / step_ns)
    if abs(n_steps * step_ns / 1e9 - dur) > GRID_TOL_S or n_steps < 1:
        raise SceneError(f"{where}: duration {dur!r} s is not a whole number of steps of {h!r} s")
    if "record_every" in d and "decimation" in d:
        raise SceneError(f"{where}: give record_every or decimation (the same thing), not both")
    rec = _int(where, "record_every", d.get("record_every", d.get("decimation", 10)), 1, 10_000_000)

    pose = d.get("pose", "stand")
    if pose == "stand":
        pose = 0
    pose = _int(where, "pose", pose, 0, 1)
    if pose != 0:
        raise SceneError(f"{where}: only pose 'stand' (0) exists in leg.toml")
    lengths = _pair(where, "lengths", d["lengths"]) if "lengths" in d else None
    init = _choice(where, "init", d.get("init", "force_zero"), ("force_zero", "hold_length"))
    timeout = _int(where, "cmd_timeout_ms", d.get("cmd_timeout_ms", 0), 0, 65534)
    safe = _choice(where, "safe_state", d.get("safe_state", "zero-force"), ("zero-force", "hold-length"))
    disable = d.get("disable", [])
    if not isinstance(disable, list):
        raise SceneError(f"{where}: disable must be a list of names")
    disable = tuple(_choice(where, "disable", x, tuple(DISABLE_FLAGS)) for x in disable)
    foot = _pair(where, "foot_load", d["foot_load"]) if "foot_load" in d else None

    limits = _model_limits(root)
    cmds: list[ActuatorCommand | None] = [None, None]
    raw_cmds = d.get("command", [])
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
        sch = _schedule(cw, c)
        if sch.kind == "initial" and mode != "length":
            raise SceneError(f"{cw}: value = \"initial\" is for mode = \"length\" (hold the assembled length)")
        if limits and act in limits and sch.extremes() is not None:
            (smin, smax), fmax = limits[act]
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
                  demo=bool(d.get("demo", False)))
    for c in scene.commands:
        if c is not None:
            for t0 in c.schedule.breakpoints:
                scene.to_step(t0, f"{c.name} step t0")
    if timeout and rec * step_ns >= timeout * 1_000_000:
        raise SceneError(f"{where}: an exchange every {rec * step_ns / 1e6:g} ms (record_every x step) "
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

    ch = d.get("checks", {})
    if not isinstance(ch, dict):
        raise SceneError(f"{where}: [checks] must be a table")
    _unknown(f"{where} [checks]", ch, set(CHECK_KEYS) | {"compare", "stroke", "resolution_ratio"})
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
    return parse_scene(path.read_text(), path, root=root)
