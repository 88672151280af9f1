"""A small ctypes binding of legsim's plain C API (firmware_core/include/legsim/legsim.h).

The core is loaded in-process from its shared libraries: ``liblegsim.so``
(double) or ``liblegsim_f32.so`` (float), built by the host CMake build
(targets ``legsim`` and ``legsim_f32``). They hold the compiled-in leg as the
data symbols ``legsim_model_leg_revolute`` and ``legsim_model_leg_slot``.

Where the libraries are looked for: ``lib_path`` if given (a file or a
directory), else ``$LEGSIM_LIB_DIR``, else ``build/host/firmware_core/`` of this
repository.

The struct layouts mirror legsim.h. Their sizes depend on the build's
generated ``legsim/config.h`` (``LEGSIM_USE_FLOAT``, ``LEGSIM_MAX_*``): it is
read from the build tree next to the library (``generated/`` for the double
library, ``generated_f32/`` for the float one), and the precision is checked
against the library itself at load time (``legsim_default_options().newton_tol``
is 1e-5 in a float build, 1e-10 in a double one).

Quick use::

    from legsim_bench.core import Core
    c = Core(precision="double", integrator="rk4", step=1e-3)
    c.assemble_pose("stand")
    c.command_force(0, 50.0)
    c.step(100)
    c.q, c.reactions(), c.constraints()[1]

Every failing call raises :class:`LegsimError` with the status, its name and
``legsim_status_str``; nothing fails silently.
"""
from __future__ import annotations

import ctypes as C
import os
import re
import sys
import time

# Timings in this process must not compete with idle BLAS worker threads (2-core machines).
if "numpy" not in sys.modules:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Optional, Union

import numpy as np

def _repo_root() -> Path:
    """$LEGSIM_ROOT, else the repository this package sits in (bench/legsim_bench/)."""
    env = os.environ.get("LEGSIM_ROOT")
    if env and (Path(env) / "models" / "leg.toml").is_file():
        return Path(env).resolve()
    here = Path(__file__).resolve()
    for d in here.parents:
        if (d / "models" / "leg.toml").is_file():
            return d
    for d in [Path.cwd(), *Path.cwd().parents]:
        if (d / "models" / "leg.toml").is_file():
            return d
    return here.parents[2]


REPO_ROOT = _repo_root()
DEFAULT_LIB_DIR = REPO_ROOT / "build" / "host" / "firmware_core"
MODEL_TOML = REPO_ROOT / "models" / "leg.toml"

LIB_NAMES = {"double": "liblegsim.so", "float": "liblegsim_f32.so"}
GENERATED_DIRS = {"double": "generated", "float": "generated_f32"}

# ---- enums of legsim.h ---------------------------------------------------
STATUS_NAMES = {
    0: "LEGSIM_OK", 1: "LEGSIM_ERR_NULL", 2: "LEGSIM_ERR_STORAGE", 3: "LEGSIM_ERR_MODEL",
    4: "LEGSIM_ERR_CAPACITY", 5: "LEGSIM_ERR_BAD_INPUT", 6: "LEGSIM_ERR_OUT_OF_STROKE",
    7: "LEGSIM_ERR_NOT_CONVERGED", 8: "LEGSIM_ERR_SINGULAR", 9: "LEGSIM_ERR_UNREACHABLE",
    10: "LEGSIM_ERR_NO_EQUILIBRIUM", 11: "LEGSIM_ERR_DISABLED", 12: "LEGSIM_ERR_STATE",
    13: "LEGSIM_ERR_DIVERGED",
}
OK = 0
ERR_NULL, ERR_STORAGE, ERR_MODEL, ERR_CAPACITY, ERR_BAD_INPUT = 1, 2, 3, 4, 5
ERR_OUT_OF_STROKE, ERR_NOT_CONVERGED, ERR_SINGULAR, ERR_UNREACHABLE = 6, 7, 8, 9
ERR_NO_EQUILIBRIUM, ERR_DISABLED, ERR_STATE, ERR_DIVERGED = 10, 11, 12, 13

INTEGRATORS = {"rk4": 0, "galpha": 1}
INTEGRATOR_LABEL = {"rk4": "RK4 + projection", "galpha": "generalized-alpha (index 3)"}

DISABLE = {
    "gravity": 1 << 0,
    "force_elements": 1 << 1,
    "reactions": 1 << 2,
    "projection": 1 << 3,
    "actuators": 1 << 4,
    "stroke_limits": 1 << 5,
}
EVENTS = {
    "stroke_min": 1 << 0,
    "stroke_max": 1 << 1,
    "force_saturated": 1 << 2,
    "near_singular": 1 << 3,
}
COND_WARN = 1e3
COND_SINGULAR = 1e5
ACTUATOR_FORCE, ACTUATOR_LENGTH = 0, 1
STORAGE_ALIGN = 16
FRAME = -1

# capacities of the top-level CMakeLists.txt (used only when no config.h is found)
_DEFAULT_CONFIG = {
    "LEGSIM_NAME_LEN": 24, "LEGSIM_MAX_BODIES": 8, "LEGSIM_MAX_JOINTS": 10,
    "LEGSIM_MAX_ACTUATORS": 3, "LEGSIM_MAX_FORCES": 4, "LEGSIM_MAX_POSES": 2,
    "LEGSIM_MAX_POSE_DRIVERS": 3, "LEGSIM_WITH_RK4": 1, "LEGSIM_WITH_GENERALIZED_ALPHA": 1,
    "LEGSIM_WITH_STATICS": 1, "LEGSIM_WITH_INVERSE_DYNAMICS": 1, "LEGSIM_WITH_FORCE_ELEMENTS": 1,
}


class LegsimError(RuntimeError):
    """A legsim call returned a status other than LEGSIM_OK."""

    def __init__(self, status: int, function: str, text: str):
        self.status = int(status)
        self.name = STATUS_NAMES.get(self.status, f"status {status}")
        self.function = function
        self.text = text
        super().__init__(f"{function}: {self.name} ({text})")


class LibraryNotFound(FileNotFoundError):
    pass


# ---- config.h ------------------------------------------------------------
def parse_config_h(path: Union[str, Path]) -> dict:
    """The integer #defines of a generated legsim/config.h."""
    out = {}
    for m in re.finditer(r"^#define\s+(LEGSIM_\w+)\s+(-?\d+)\s*$", Path(path).read_text(), re.M):
        out[m.group(1)] = int(m.group(2))
    return out


def _find_config(lib_file: Path, precision: str) -> Optional[Path]:
    gen = GENERATED_DIRS[precision]
    env = os.environ.get("LEGSIM_CONFIG_H")
    if env and Path(env).is_file():
        return Path(env)
    d = lib_file.parent
    for base in (d, d / "firmware_core", d.parent, d.parent / "firmware_core"):
        p = base / gen / "legsim" / "config.h"
        if p.is_file():
            return p
    return None


def find_library(precision: str = "double", lib_path=None) -> Path:
    """Path of liblegsim.so / liblegsim_f32.so (see the module docstring)."""
    if precision not in LIB_NAMES:
        raise ValueError(f"precision must be 'double' or 'float', not {precision!r}")
    name = LIB_NAMES[precision]
    cands = []
    if lib_path is not None:
        p = Path(lib_path)
        cands.append(p / name if p.is_dir() else p)
    else:
        env = os.environ.get("LEGSIM_LIB_DIR")
        if env:
            cands.append(Path(env) / name)
            cands.append(Path(env) / "firmware_core" / name)
        cands.append(DEFAULT_LIB_DIR / name)
    for c in cands:
        if c.is_file():
            return c.resolve()
    raise LibraryNotFound(
        f"{name} not found (looked at: {', '.join(str(c) for c in cands)}); build it with "
        "`cmake -S . -B build/host -G Ninja -DCMAKE_BUILD_TYPE=Release && cmake --build build/host` "
        "or set LEGSIM_LIB_DIR")


def library_available(precision: str = "double") -> bool:
    try:
        find_library(precision)
        return True
    except LibraryNotFound:
        return False


def library_missing(precision: str = "double") -> bool:
    """True, after saying where it was looked for, when the library is not built."""
    try:
        find_library(precision)
        return False
    except LibraryNotFound as e:
        print(e, file=sys.stderr)
        return True


# ---- the types of legsim.h for one configuration --------------------------
class Api:
    """A loaded library with its ctypes types and prototypes (one per library file)."""

    def __init__(self, lib_file: Path, precision: str):
        self.path = Path(lib_file)
        self.precision = precision
        cfg_path = _find_config(self.path, precision)
        cfg = dict(_DEFAULT_CONFIG)
        if cfg_path is not None:
            cfg.update(parse_config_h(cfg_path))
        else:
            cfg["LEGSIM_USE_FLOAT"] = 1 if precision == "float" else 0
        self.config = cfg
        self.config_path = cfg_path
        self.lib = C.CDLL(str(self.path))
        real = C.c_float if cfg["LEGSIM_USE_FLOAT"] else C.c_double
        self.real = real
        self.np_real = np.float32 if cfg["LEGSIM_USE_FLOAT"] else np.float64
        self._define_types(cfg, real)
        self._prototypes()
        # the library's own precision must match the header we mirror
        tol = self.lib.legsim_default_options().newton_tol
        lib_float = tol > 1e-7
        if lib_float != bool(cfg["LEGSIM_USE_FLOAT"]):
            raise RuntimeError(f"{self.path}: precision mismatch between the library "
                               f"(default newton_tol {tol}) and {cfg_path}")
        self.sim_size = int(self.lib.legsim_sim_size())

    def _define_types(self, cfg, real):
        NL = cfg["LEGSIM_NAME_LEN"]
        MB, MJ = cfg["LEGSIM_MAX_BODIES"], cfg["LEGSIM_MAX_JOINTS"]
        MA, MF = cfg["LEGSIM_MAX_ACTUATORS"], cfg["LEGSIM_MAX_FORCES"]
        MP, MPD = cfg["LEGSIM_MAX_POSES"], cfg["LEGSIM_MAX_POSE_DRIVERS"]
        d = C.c_double
        i32 = C.c_int32

        class BodyDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("length_m", d), ("mass_kg", d),
                        ("inertia_kgm2", d)]

        class JointDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("kind", C.c_int), ("body", i32 * 2),
                        ("point", (d * 2) * 2)]

        class ActuatorDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("joint", i32), ("stroke_min_m", d),
                        ("stroke_max_m", d), ("max_force_n", d), ("servo_kp_n_per_m", d),
                        ("servo_kd_ns_per_m", d)]

        class ForceDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("kind", C.c_int), ("body", i32 * 2),
                        ("point", (d * 2) * 2), ("value", d * 2), ("stiffness_n_per_m", d),
                        ("damping_ns_per_m", d), ("rest_length_m", d)]

        class CoordDriver(C.Structure):
            _fields_ = [("body", i32), ("coord", i32), ("value", d)]

        class PoseDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("n_drivers", i32), ("driver", CoordDriver * MPD),
                        ("guess", (d * 3) * MB)]

        class ModelDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("gravity_mps2", d * 2),
                        ("n_bodies", i32), ("n_joints", i32), ("n_actuators", i32),
                        ("n_forces", i32), ("n_poses", i32),
                        ("body", BodyDesc * MB), ("joint", JointDesc * MJ),
                        ("actuator", ActuatorDesc * MA), ("force", ForceDesc * MF),
                        ("pose", PoseDesc * MP), ("foot_body", i32), ("foot_point", d * 2)]

        class Options(C.Structure):
            _fields_ = [("integrator", C.c_int), ("step_s", d), ("disable", C.c_uint32),
                        ("rho_inf", d), ("max_newton_iter", i32), ("newton_tol", d)]

        class Report(C.Structure):
            _fields_ = [("iterations", i32), ("residual", real), ("condition", real),
                        ("events", C.c_uint32)]

        class Reaction(C.Structure):
            _fields_ = [("force_n", real * 2), ("moment_nm", real)]

        class WorstCase(C.Structure):
            _fields_ = [("max_reaction_n", real * MJ), ("max_actuator_force_n", real * MA),
                        ("at_length_m", (real * MA) * MJ),
                        ("actuator_at_length_m", (real * MA) * MA),
                        ("n_poses", i32), ("n_failed", i32)]

        self.BodyDesc, self.JointDesc, self.ActuatorDesc = BodyDesc, JointDesc, ActuatorDesc
        self.ForceDesc, self.CoordDriver, self.PoseDesc = ForceDesc, CoordDriver, PoseDesc
        self.ModelDesc, self.Options, self.Report = ModelDesc, Options, Report
        self.Reaction, self.WorstCase = Reaction, WorstCase

    def _prototypes(self):
        L, R = self.lib, self.real
        P = C.c_void_p
        RP = C.POINTER(R)
        st = C.c_int
        MP = C.POINTER(self.ModelDesc)
        OP = C.POINTER(self.Options)
        protos = {
            "legsim_status_str": (C.c_char_p, [st]),
            "legsim_model_check": (st, [MP, C.c_char_p, C.c_size_t]),
            "legsim_default_options": (self.Options, []),
            "legsim_sim_size": (C.c_size_t, []),
            "legsim_init": (st, [P, C.c_size_t, MP, OP, C.POINTER(P)]),
            "legsim_set_options": (st, [P, OP]),
            "legsim_n_bodies": (C.c_int32, [P]),
            "legsim_n_coords": (C.c_int32, [P]),
            "legsim_n_constraints": (C.c_int32, [P]),
            "legsim_n_joints": (C.c_int32, [P]),
            "legsim_n_actuators": (C.c_int32, [P]),
            "legsim_n_forces": (C.c_int32, [P]),
            "legsim_model": (MP, [P]),
            "legsim_get_report": (st, [P, C.POINTER(self.Report)]),
            "legsim_clear_events": (st, [P]),
            "legsim_stroke_event_mask": (C.c_uint32, [P]),
            "legsim_time": (C.c_double, [P]),
            "legsim_step_count": (C.c_uint64, [P]),
            "legsim_get_q": (st, [P, RP]),
            "legsim_get_qd": (st, [P, RP]),
            "legsim_get_qdd": (st, [P, RP]),
            "legsim_set_state": (st, [P, RP, RP, C.c_double]),
            "legsim_constraints": (st, [P, RP, RP]),
            "legsim_jacobian": (st, [P, RP]),
            "legsim_actuator_lengths": (st, [P, RP, RP]),
            "legsim_actuator_forces": (st, [P, RP]),
            "legsim_foot_position": (st, [P, RP]),
            "legsim_assemble": (st, [P, RP]),
            "legsim_assemble_pose": (st, [P, C.c_int32]),
            "legsim_velocity_analysis": (st, [P, RP]),
            "legsim_acceleration_analysis": (st, [P, RP]),
            "legsim_inverse_dynamics": (st, [P, RP, RP, RP, RP]),
            "legsim_statics": (st, [P, RP]),
            "legsim_statics_sweep": (st, [P, C.c_int32, C.POINTER(self.WorstCase)]),
            "legsim_step": (st, [P, C.c_int32]),
            "legsim_reactions": (st, [P, C.POINTER(self.Reaction)]),
            "legsim_multipliers": (st, [P, RP]),
            "legsim_command_force": (st, [P, C.c_int32, R]),
            "legsim_command_length": (st, [P, C.c_int32, R]),
            "legsim_set_force": (st, [P, C.c_int32, RP]),
        }
        for name, (res, args) in protos.items():
            f = getattr(L, name)
            f.restype, f.argtypes = res, args

    def status_str(self, s: int) -> str:
        return self.lib.legsim_status_str(int(s)).decode()

    def model(self, variant: str = "revolute"):
        """The compiled-in model description (a ctypes ModelDesc living in the library)."""
        return self.ModelDesc.in_dll(self.lib, f"legsim_model_leg_{variant}")


_APIS: dict = {}


def load(precision: str = "double", lib_path=None) -> Api:
    """The (cached) Api of the library for this precision."""
    path = find_library(precision, lib_path)
    key = (str(path), precision)
    if key not in _APIS:
        _APIS[key] = Api(path, precision)
    return _APIS[key]


@dataclass
class Report:
    iterations: int
    residual: float
    condition: float
    events: int

    def event_names(self) -> list:
        return [k for k, v in EVENTS.items() if self.events & v]


def disable_mask(disable) -> int:
    """An int, a flag name, or an iterable of names (see DISABLE) as the bit mask."""
    if disable is None:
        return 0
    if isinstance(disable, (int, np.integer)):
        return int(disable)
    if isinstance(disable, str):
        disable = [disable]
    m = 0
    for name in disable:
        if name not in DISABLE:
            raise ValueError(f"unknown disable flag {name!r}; known: {sorted(DISABLE)}")
        m |= DISABLE[name]
    return m


class Core:
    """One legsim simulation in caller-provided (ctypes) storage.

    precision: "double" (liblegsim.so) or "float" (liblegsim_f32.so);
    variant: "revolute" or "slot" (the compiled-in leg); integrator: "rk4" or
    "galpha"; step: h in s; disable: flag names (see DISABLE) or a mask.
    Arrays come back as float64 numpy arrays whatever the precision.
    """

    def __init__(self, lib_path=None, precision: str = "double", variant: str = "revolute",
                 integrator: str = "rk4", step: float = 1e-3, disable=0, rho_inf: float = None,
                 max_newton_iter: int = None, newton_tol: float = None):
        self.api = api = load(precision, lib_path)
        self.lib = api.lib
        self.precision = precision
        self.variant = variant
        self._real = api.real
        self._model = api.model(variant)
        self._storage = C.create_string_buffer(api.sim_size + STORAGE_ALIGN)
        base = C.addressof(self._storage)
        self._addr = base + (-base) % STORAGE_ALIGN
        self.options = api.lib.legsim_default_options()
        self._apply_options(integrator, step, disable, rho_inf, max_newton_iter, newton_tol)
        out = C.c_void_p()
        self._check(self.lib.legsim_init(C.c_void_p(self._addr), api.sim_size,
                                         C.byref(self._model), C.byref(self.options),
                                         C.byref(out)), "legsim_init")
        self.sim = out
        L = self.lib
        self.n_bodies = L.legsim_n_bodies(out)
        self.n_coords = L.legsim_n_coords(out)
        self.n_constraints = L.legsim_n_constraints(out)
        self.n_joints = L.legsim_n_joints(out)
        self.n_actuators = L.legsim_n_actuators(out)
        self.n_forces = L.legsim_n_forces(out)
        R = api.real
        self._qbuf = (R * self.n_coords)()
        self._cbuf = (R * max(1, self.n_constraints))()
        self._abuf = (R * max(1, self.n_actuators))()
        self._abuf2 = (R * max(1, self.n_actuators))()
        self._rbuf = (api.Reaction * max(1, self.n_joints))()
        self._step_fn = L.legsim_step

    # ---- helpers ----
    def _check(self, status: int, fn: str):
        if status != OK:
            raise LegsimError(status, fn, self.api.status_str(status))

    def _apply_options(self, integrator=None, step=None, disable=None, rho_inf=None,
                       max_newton_iter=None, newton_tol=None):
        o = self.options
        if integrator is not None:
            if integrator not in INTEGRATORS:
                raise ValueError(f"integrator must be one of {sorted(INTEGRATORS)}")
            o.integrator = INTEGRATORS[integrator]
        if step is not None:
            o.step_s = float(step)
        if disable is not None:
            o.disable = disable_mask(disable)
        if rho_inf is not None:
            o.rho_inf = float(rho_inf)
        if max_newton_iter is not None:
            o.max_newton_iter = int(max_newton_iter)
        if newton_tol is not None:
            o.newton_tol = float(newton_tol)

    def _arr(self, values, n):
        a = (self._real * n)()
        v = np.asarray(values, dtype=float).reshape(-1)
        if v.size != n:
            raise ValueError(f"need {n} values, got {v.size}")
        for i in range(n):
            a[i] = v[i]
        return a

    @staticmethod
    def _np(buf, n) -> np.ndarray:
        return np.array(buf[:n], dtype=np.float64)

    # ---- options ----
    @property
    def integrator(self) -> str:
        return {v: k for k, v in INTEGRATORS.items()}[self.options.integrator]

    @property
    def step_size(self) -> float:
        return self.options.step_s

    def set_options(self, **kw):
        """integrator=, step=, disable=, rho_inf=, max_newton_iter=, newton_tol=."""
        saved = self.api.Options.from_buffer_copy(self.options)
        self._apply_options(**kw)
        st = self.lib.legsim_set_options(self.sim, C.byref(self.options))
        if st != OK:
            self.options = saved
        self._check(st, "legsim_set_options")

    # ---- model ----
    @property
    def model_desc(self):
        return self.lib.legsim_model(self.sim).contents

    def pose_index(self, pose) -> int:
        if isinstance(pose, (int, np.integer)):
            return int(pose)
        m = self._model
        for i in range(m.n_poses):
            if m.pose[i].name.decode() == pose:
                return i
        raise ValueError(f"no pose {pose!r}")

    def stroke(self, a: int) -> tuple:
        ad = self._model.actuator[a]
        return ad.stroke_min_m, ad.stroke_max_m

    def max_force(self, a: int) -> float:
        return self._model.actuator[a].max_force_n

    # ---- state ----
    @property
    def time(self) -> float:
        return self.lib.legsim_time(self.sim)

    @property
    def step_count(self) -> int:
        return self.lib.legsim_step_count(self.sim)

    @property
    def q(self) -> np.ndarray:
        self._check(self.lib.legsim_get_q(self.sim, self._qbuf), "legsim_get_q")
        return self._np(self._qbuf, self.n_coords)

    @property
    def qd(self) -> np.ndarray:
        self._check(self.lib.legsim_get_qd(self.sim, self._qbuf), "legsim_get_qd")
        return self._np(self._qbuf, self.n_coords)

    @property
    def qdd(self) -> np.ndarray:
        self._check(self.lib.legsim_get_qdd(self.sim, self._qbuf), "legsim_get_qdd")
        return self._np(self._qbuf, self.n_coords)

    def q_bytes(self) -> bytes:
        """The raw bytes of q and qd in the build's precision (bit-identity checks)."""
        self._check(self.lib.legsim_get_q(self.sim, self._qbuf), "legsim_get_q")
        b = bytes(self._qbuf)
        self._check(self.lib.legsim_get_qd(self.sim, self._qbuf), "legsim_get_qd")
        return b + bytes(self._qbuf)

    def set_state(self, q, qd=None, t: float = 0.0):
        qa = self._arr(q, self.n_coords)
        qda = None if qd is None else self._arr(qd, self.n_coords)
        self._check(self.lib.legsim_set_state(self.sim, qa, qda, float(t)), "legsim_set_state")

    def report(self) -> Report:
        r = self.api.Report()
        self._check(self.lib.legsim_get_report(self.sim, C.byref(r)), "legsim_get_report")
        return Report(r.iterations, float(r.residual), float(r.condition), int(r.events))

    def clear_events(self):
        self._check(self.lib.legsim_clear_events(self.sim), "legsim_clear_events")

    def stroke_event_mask(self) -> int:
        return int(self.lib.legsim_stroke_event_mask(self.sim))

    def constraints(self) -> tuple:
        """(Phi (n_constraints,), max |Phi|)."""
        mx = self._real()
        self._check(self.lib.legsim_constraints(self.sim, self._cbuf, C.byref(mx)),
                    "legsim_constraints")
        return self._np(self._cbuf, self.n_constraints), float(mx.value)

    def constraint_residual(self) -> float:
        mx = self._real()
        self._check(self.lib.legsim_constraints(self.sim, None, C.byref(mx)), "legsim_constraints")
        return float(mx.value)

    def jacobian(self) -> np.ndarray:
        buf = (self._real * (self.n_constraints * self.n_coords))()
        self._check(self.lib.legsim_jacobian(self.sim, buf), "legsim_jacobian")
        return np.array(buf[:], dtype=float).reshape(self.n_constraints, self.n_coords)

    def actuator_lengths(self) -> tuple:
        """(lengths (na,), rates (na,))."""
        self._check(self.lib.legsim_actuator_lengths(self.sim, self._abuf, self._abuf2),
                    "legsim_actuator_lengths")
        return self._np(self._abuf, self.n_actuators), self._np(self._abuf2, self.n_actuators)

    def actuator_forces(self) -> np.ndarray:
        self._check(self.lib.legsim_actuator_forces(self.sim, self._abuf), "legsim_actuator_forces")
        return self._np(self._abuf, self.n_actuators)

    def foot(self) -> np.ndarray:
        xy = (self._real * 2)()
        self._check(self.lib.legsim_foot_position(self.sim, xy), "legsim_foot_position")
        return self._np(xy, 2)

    def reactions(self) -> np.ndarray:
        """(n_joints, 3): Fx, Fy (N, world) on the first-listed body, moment (N m) about its centre."""
        self._check(self.lib.legsim_reactions(self.sim, self._rbuf), "legsim_reactions")
        return np.array([[r.force_n[0], r.force_n[1], r.moment_nm]
                         for r in self._rbuf[:self.n_joints]], dtype=float)

    def multipliers(self) -> np.ndarray:
        self._check(self.lib.legsim_multipliers(self.sim, self._cbuf), "legsim_multipliers")
        return self._np(self._cbuf, self.n_constraints)

    # ---- analyses ----
    def assemble_pose(self, pose="stand"):
        self._check(self.lib.legsim_assemble_pose(self.sim, self.pose_index(pose)),
                    "legsim_assemble_pose")

    def assemble(self, lengths=None):
        arr = None if lengths is None else self._arr(lengths, self.n_actuators)
        self._check(self.lib.legsim_assemble(self.sim, arr), "legsim_assemble")

    def velocity_analysis(self, rates):
        self._check(self.lib.legsim_velocity_analysis(self.sim, self._arr(rates, self.n_actuators)),
                    "legsim_velocity_analysis")

    def acceleration_analysis(self, accels):
        self._check(self.lib.legsim_acceleration_analysis(
            self.sim, self._arr(accels, self.n_actuators)), "legsim_acceleration_analysis")

    def inverse_dynamics(self, lengths, rates, accels) -> np.ndarray:
        """Actuator forces (na,) along the driven motion; reactions() then holds the joints'."""
        na = self.n_actuators
        self._check(self.lib.legsim_inverse_dynamics(
            self.sim, self._arr(lengths, na), self._arr(rates, na), self._arr(accels, na),
            self._abuf), "legsim_inverse_dynamics")
        return self._np(self._abuf, na)

    def statics(self) -> np.ndarray:
        self._check(self.lib.legsim_statics(self.sim, self._abuf), "legsim_statics")
        return self._np(self._abuf, self.n_actuators)

    def statics_sweep(self, n_grid: int):
        w = self.api.WorstCase()
        self._check(self.lib.legsim_statics_sweep(self.sim, int(n_grid), C.byref(w)),
                    "legsim_statics_sweep")
        return w

    # ---- dynamics ----
    def step(self, n: int = 1):
        """Advances n fixed steps (one legsim_step call). Raises LegsimError on failure."""
        self._check(self._step_fn(self.sim, int(n)), "legsim_step")

    def step_status(self, n: int = 1) -> int:
        """Like step() but returns the raw status instead of raising."""
        return int(self._step_fn(self.sim, int(n)))

    def timed_step(self, n: int) -> int:
        """Wall time (ns, time.perf_counter_ns) of one legsim_step(sim, n) call."""
        f, s = self._step_fn, self.sim
        t0 = time.perf_counter_ns()
        st = f(s, n)
        t1 = time.perf_counter_ns()
        self._check(st, "legsim_step")
        return t1 - t0

    # ---- commands ----
    def command_force(self, actuator: int, force_n: float):
        self._check(self.lib.legsim_command_force(self.sim, int(actuator), float(force_n)),
                    "legsim_command_force")

    def command_length(self, actuator: int, length_m: float):
        self._check(self.lib.legsim_command_length(self.sim, int(actuator), float(length_m)),
                    "legsim_command_length")

    def set_force(self, force: int, value):
        v = np.atleast_1d(np.asarray(value, float))
        arr = (self._real * 2)(*([float(x) for x in v[:2]] + [0.0] * (2 - min(2, v.size))))
        self._check(self.lib.legsim_set_force(self.sim, int(force), arr), "legsim_set_force")


def status_name(status: int) -> str:
    return STATUS_NAMES.get(int(status), f"status {status}")


if __name__ == "__main__":  # a smoke check
    for prec in ("double", "float"):
        c = Core(precision=prec)
        c.assemble_pose("stand")
        c.step(100)
        print(prec, c.api.path, "sim_size", c.api.sim_size, "t", c.time, "foot", c.foot(),
              "residual", c.constraint_residual())
