"""Models: a leg description from a model TOML file, or compiled into the library.

A model TOML (``models/leg.toml`` is the leg) is parsed by the library's own
loader (``firmware_core/host/model_toml.hpp``), the same code the C++ CLI
uses, with the same checks and messages as the firmware's code generator: one
parser, one meaning. A file that does not load raises :class:`legsim.ModelError`
(or ``CapacityError``, ``BadInputError``) with the loader's message, e.g.
``models/leg.toml: joint 'D': body 7 does not exist (ids are 1..6)``.
"""
from __future__ import annotations

import ctypes as C
import os
from pathlib import Path

import numpy as np

from ._lib import Library, load_library
from .errors import BadInputError, Status, error_for

DEFAULT_VARIANT = "revolute"
_MSG_LEN = 512


def _name(raw: bytes) -> str:
    return raw.decode("utf-8", "replace")


class Model:
    """A leg description (``legsim_model_desc``) owned by Python for a library.

    Make one with :meth:`from_toml`, :meth:`from_toml_string` or :meth:`builtin`.
    All values are SI: m, kg, kg m^2, N, m/s^2. The description is read-only: change
    the model file and load it again (the C core keeps it by pointer).

    Attributes: ``desc`` (the ctypes ``legsim_model_desc``), ``library``,
    ``variant``, ``source`` (the file, or ``"compiled-in leg"``).
    """

    def __init__(self, desc, library: Library, variant: str, source: str):
        self.desc = desc
        self.library = library
        self.variant = variant
        self.source = source

    # ---- construction ----
    @classmethod
    def from_toml(cls, path, variant: str | None = None, *, precision: str | None = None,
                  lib_path=None) -> "Model":
        """Loads ``variant`` ("revolute" by default, else a ``[variant.X]`` of the file)
        of the model file at ``path`` with the library's loader."""
        lib = load_library(precision, lib_path)
        _need_loader(lib)
        desc = lib.ModelDesc()
        msg = C.create_string_buffer(_MSG_LEN)
        path = os.fspath(path)
        st = lib.cdll.legsim_model_load_toml(path.encode(), _variant_arg(variant), C.byref(desc),
                                             msg, _MSG_LEN)
        lib.check(st, "legsim_model_load_toml", msg.value.decode(errors="replace"))
        return cls(desc, lib, variant or DEFAULT_VARIANT, str(path))

    @classmethod
    def from_toml_string(cls, text: str, variant: str | None = None, *,
                         source_name: str = "<string>", precision: str | None = None,
                         lib_path=None) -> "Model":
        """Like :meth:`from_toml` for TOML text in memory; ``source_name`` stands for the
        file in messages."""
        lib = load_library(precision, lib_path)
        _need_loader(lib)
        desc = lib.ModelDesc()
        msg = C.create_string_buffer(_MSG_LEN)
        data = text.encode()
        st = lib.cdll.legsim_model_parse_toml(data, len(data), source_name.encode(),
                                              _variant_arg(variant), C.byref(desc), msg, _MSG_LEN)
        lib.check(st, "legsim_model_parse_toml", msg.value.decode(errors="replace"))
        return cls(desc, lib, variant or DEFAULT_VARIANT, source_name)

    @classmethod
    def builtin(cls, variant: str = DEFAULT_VARIANT, *, symbol: str = "leg",
                precision: str | None = None, lib_path=None) -> "Model":
        """The model compiled into the library (``legsim_model_<symbol>_<variant>``,
        generated at build time: symbol "leg" from ``models/leg.toml``, "robot" from
        ``models/robot.toml`` when the build's capacities hold it, e.g.
        ``Model.builtin(symbol="robot")``). The description is copied, so it lives as
        long as this object."""
        lib = load_library(precision, lib_path)
        sym = f"legsim_model_{symbol}_{variant}"
        try:
            compiled = lib.ModelDesc.in_dll(lib.cdll, sym)
        except ValueError:
            known = builtin_variants(symbol=symbol, precision=precision, lib_path=lib_path)
            raise BadInputError(Status.ERR_BAD_INPUT, "Model.builtin",
                                f"{lib.path} has no compiled-in model {symbol!r} variant "
                                f"{variant!r} (it has: {', '.join(known) or 'none'})") from None
        desc = lib.ModelDesc.from_buffer_copy(compiled)
        return cls(desc, lib, variant, f"compiled-in {symbol}")

    def for_library(self, library: Library) -> "Model":
        """This description for another library (the other precision): the description
        is precision-independent (doubles); the capacities must match."""
        if library is self.library:
            return self
        if C.sizeof(library.ModelDesc) != C.sizeof(self.desc):
            raise ValueError(f"{library.path} has other capacities than {self.library.path}")
        return Model(library.ModelDesc.from_buffer_copy(self.desc), library, self.variant,
                     self.source)

    def check(self) -> None:
        """Runs the core's checks (``legsim_model_check``); raises ModelError/CapacityError."""
        msg = C.create_string_buffer(_MSG_LEN)
        st = self.library.cdll.legsim_model_check(C.byref(self.desc), msg, _MSG_LEN)
        self.library.check(st, "legsim_model_check", msg.value.decode(errors="replace"))

    # ---- contents ----
    @property
    def name(self) -> str:
        return _name(self.desc.name)

    @property
    def gravity(self) -> np.ndarray:
        """Gravity (m/s^2, world x and y)."""
        return np.array(self.desc.gravity_mps2[:], dtype=float)

    @property
    def body_names(self) -> list[str]:
        return [_name(b.name) for b in self.desc.body[:self.desc.n_bodies]]

    @property
    def masses(self) -> np.ndarray:
        """Body masses (kg), in body order."""
        return np.array([b.mass_kg for b in self.desc.body[:self.desc.n_bodies]])

    @property
    def lengths(self) -> np.ndarray:
        """Body lengths (m)."""
        return np.array([b.length_m for b in self.desc.body[:self.desc.n_bodies]])

    @property
    def inertias(self) -> np.ndarray:
        """Body inertias about their centres of mass (kg m^2)."""
        return np.array([b.inertia_kgm2 for b in self.desc.body[:self.desc.n_bodies]])

    @property
    def joint_names(self) -> list[str]:
        return [_name(j.name) for j in self.desc.joint[:self.desc.n_joints]]

    @property
    def actuator_names(self) -> list[str]:
        return [_name(a.name) for a in self.desc.actuator[:self.desc.n_actuators]]

    @property
    def strokes(self) -> np.ndarray:
        """(n_actuators, 2): shortest and longest length of each actuator (m)."""
        return np.array([[a.stroke_min_m, a.stroke_max_m]
                         for a in self.desc.actuator[:self.desc.n_actuators]]).reshape(-1, 2)

    @property
    def max_forces(self) -> np.ndarray:
        """Largest |axial force| of each actuator (N)."""
        return np.array([a.max_force_n for a in self.desc.actuator[:self.desc.n_actuators]])

    @property
    def force_names(self) -> list[str]:
        return [_name(f.name) for f in self.desc.force[:self.desc.n_forces]]

    @property
    def pose_names(self) -> list[str]:
        return [_name(p.name) for p in self.desc.pose[:self.desc.n_poses]]

    @property
    def foot(self) -> tuple[int, np.ndarray]:
        """(body index or -1, body-fixed point (xi, eta) in m) of the foot."""
        return int(self.desc.foot_body), np.array(self.desc.foot_point[:], dtype=float)

    @property
    def contact_names(self) -> list[str]:
        """Names of the foot contacts (a robot's ``right.foot``, ``left.foot``)."""
        n = getattr(self.desc, "n_contacts", 0)
        return [_name(c.name) for c in self.desc.contact[:n]] if n else []

    @property
    def ground(self) -> dict:
        """The ground line: ``point`` (m), ``slope`` (rad), ``mu_static``, ``mu_kinetic``."""
        gd = self.desc.ground
        return {"point": np.array(gd.point[:], dtype=float), "slope": float(gd.slope_rad),
                "mu_static": float(gd.mu_static), "mu_kinetic": float(gd.mu_kinetic)}

    def __repr__(self) -> str:
        return (f"<legsim.Model {self.name!r} variant {self.variant!r} from {self.source}, "
                f"{self.desc.n_bodies} bodies, {self.desc.n_joints} joints, "
                f"{self.desc.n_actuators} actuators>")


def _variant_arg(variant):
    return None if variant is None else str(variant).encode()


def _need_loader(lib: Library):
    if not lib.has_toml_loader:
        raise error_for(Status.ERR_DISABLED, "legsim_model_load_toml",
                        f"{lib.path} has no run-time model loader (rebuild the host libraries)")


def model_variants(path, *, precision: str | None = None, lib_path=None) -> list[str]:
    """Variant names of a model file: "revolute", then its ``[variant.X]`` tables in file
    order (read by the library's loader; load one to validate it)."""
    lib = load_library(precision, lib_path)
    _need_loader(lib)
    nl = lib.config["LEGSIM_NAME_LEN"]
    cap = 64
    names = ((C.c_char * nl) * cap)()
    n = C.c_int32()
    msg = C.create_string_buffer(_MSG_LEN)
    st = lib.cdll.legsim_model_toml_variants(os.fspath(path).encode(), names, cap, C.byref(n),
                                             msg, _MSG_LEN)
    lib.check(st, "legsim_model_toml_variants", msg.value.decode(errors="replace"))
    return [_name(names[i].value) for i in range(min(n.value, cap))]


def builtin_variants(*, symbol: str = "leg", precision: str | None = None, lib_path=None) -> list[str]:
    """Names of the variants of a compiled-in model (``legsim_model_<symbol>_variants``)."""
    lib = load_library(precision, lib_path)

    class Variant(C.Structure):
        _fields_ = [("name", C.c_char_p), ("model", C.c_void_p)]

    try:
        count = C.c_int32.in_dll(lib.cdll, f"legsim_model_{symbol}_variant_count").value
        arr = (Variant * count).in_dll(lib.cdll, f"legsim_model_{symbol}_variants")
    except ValueError:
        return []
    return [v.name.decode() for v in arr]
