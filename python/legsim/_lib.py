"""Finding and loading the shared library, and the ctypes mirror of legsim.h.

The core comes as ``liblegsim.so`` (double) and ``liblegsim_f32.so`` (float),
each holding the C API, the compiled-in leg (``legsim_model_leg_*``), the
run-time model loader (``firmware_core/host/model_toml.hpp``) and the build's
facts (``firmware_core/host/build_info.h``).

Where a library is looked for (:func:`find_library`), first match wins:

1. the ``lib_path`` argument (a file, or a directory holding the file);
2. ``$LEGSIM_LIB_DIR`` (or its ``firmware_core/``): when set, only there;
3. the library inside this package (``legsim/lib/``: an installed wheel,
   python/pyproject.toml);
4. the build tree of the repository: ``build/host/firmware_core/`` under
   ``$LEGSIM_ROOT``, else under the repository this package sits in;
5. an installed library: ``ctypes.util.find_library`` (the loader's cache),
   then ``<sys.prefix>/lib``, ``/usr/local/lib``, ``/usr/lib`` (and their
   multiarch directories).

The struct sizes depend on the build (precision and ``LEGSIM_MAX_*``
capacities). They come from the library itself (``legsim_build_info``, the
values of its ``legsim/config.h`` and the ``sizeof`` of each public struct,
checked against this mirror), so no header is needed. A library without
``legsim_build_info`` (built before it existed) falls back to the
``legsim/config.h`` of its build tree or install prefix.
"""
from __future__ import annotations

import ctypes as C
import ctypes.util
import os
import re
import sys
import sysconfig
from pathlib import Path

import numpy as np

from .errors import LayoutMismatch, LibraryNotFound, Status, error_for

LIB_NAMES = {"double": "liblegsim.so", "float": "liblegsim_f32.so"}
_LINK_NAMES = {"double": "legsim", "float": "legsim_f32"}
_GENERATED_DIRS = {"double": "generated", "float": "generated_f32"}

STORAGE_ALIGN = 16  # LEGSIM_STORAGE_ALIGN (also checked against the library's facts)

# every fact the mirror needs (legsim/config.h names)
_CONFIG_KEYS = ("LEGSIM_USE_FLOAT", "LEGSIM_NAME_LEN", "LEGSIM_MAX_BODIES", "LEGSIM_MAX_JOINTS",
                "LEGSIM_MAX_ACTUATORS", "LEGSIM_MAX_FORCES", "LEGSIM_MAX_POSES",
                "LEGSIM_MAX_POSE_DRIVERS", "LEGSIM_MAX_CONTACTS")


# ---- discovery -------------------------------------------------------------
PACKAGE_DIR = Path(__file__).resolve().parent  # a wheel's lib/, bin/, share/legsim/ are here


def _repo_roots() -> list[Path]:
    """$LEGSIM_ROOT, then the repository holding this package (python/legsim/)."""
    roots = []
    env = os.environ.get("LEGSIM_ROOT")
    if env:
        roots.append(Path(env))
    here = Path(__file__).resolve()
    for d in here.parents:
        if (d / "firmware_core").is_dir() and (d / "python" / "legsim").is_dir():
            roots.append(d)
            break
    return roots


def _installed_candidates(precision: str) -> list[Path]:
    name = LIB_NAMES[precision]
    out = []
    found = ctypes.util.find_library(_LINK_NAMES[precision])  # e.g. "liblegsim.so.0"
    dirs = [Path(sys.prefix) / "lib", Path("/usr/local/lib"), Path("/usr/lib"), Path("/lib")]
    multiarch = sysconfig.get_config_var("MULTIARCH")
    if multiarch:
        dirs = [p for d in dirs for p in (d, d / multiarch)]
    for d in dirs:
        if found:
            out.append(d / found)
        out.append(d / name)
    return out


def find_library(precision: str = "double", lib_path=None) -> Path:
    """Path of ``liblegsim.so`` (precision "double") or ``liblegsim_f32.so`` ("float").

    Looks in the order of this module's docstring; raises :class:`LibraryNotFound`
    naming every place it looked.
    """
    if precision not in LIB_NAMES:
        raise ValueError(f"precision must be 'double' or 'float', not {precision!r}")
    name = LIB_NAMES[precision]
    cands: list[Path] = []
    if lib_path is not None:
        p = Path(lib_path)
        cands.append(p / name if p.is_dir() else p)
    elif os.environ.get("LEGSIM_LIB_DIR"):
        env = Path(os.environ["LEGSIM_LIB_DIR"])
        cands += [env / name, env / "firmware_core" / name]
    else:
        cands.append(PACKAGE_DIR / "lib" / name)
        cands += [r / "build" / "host" / "firmware_core" / name for r in _repo_roots()]
        cands += _installed_candidates(precision)
    for c in cands:
        if c.is_file():
            return Path(os.path.abspath(c))  # the name asked for, not a versioned link target
    where = ", ".join(dict.fromkeys(str(c) for c in cands))
    raise LibraryNotFound(
        f"{name} not found (looked at: {where}); install the wheel (pip install ./python), "
        "build it with `cmake --preset host && cmake --build build/host`, install it "
        "(cmake --install), or set LEGSIM_LIB_DIR")


def library_available(precision: str = "double", lib_path=None) -> bool:
    """Whether :func:`find_library` finds the library for this precision."""
    try:
        find_library(precision, lib_path)
        return True
    except LibraryNotFound:
        return False


# ---- the build's facts -------------------------------------------------------
def parse_config_h(path) -> dict:
    """The integer ``#define``s of a generated ``legsim/config.h``."""
    text = Path(path).read_text()
    return {m.group(1): int(m.group(2))
            for m in re.finditer(r"^#define\s+(LEGSIM_\w+)\s+(-?\d+)\s*$", text, re.M)}


def _config_h_candidates(lib_file: Path, precision: str) -> list[Path]:
    gen = _GENERATED_DIRS[precision]
    d = lib_file.parent
    out = [base / gen / "legsim" / "config.h"
           for base in (d, d / "firmware_core", d.parent, d.parent / "firmware_core")]
    # an install prefix: <prefix>/lib[/<multiarch>]/liblegsim.so, <prefix>/include/legsim/config.h
    for pre in (d.parent, d.parent.parent):
        out.append(pre / "include" / "legsim" / "config.h")
    return out


def _build_facts(cdll, path: Path, precision: str) -> tuple[dict, str]:
    """(facts, where they came from): from legsim_build_info, else a config.h."""
    if hasattr(cdll, "legsim_build_info"):
        cdll.legsim_build_info_count.restype = C.c_int32
        cdll.legsim_build_info.restype = C.c_int
        cdll.legsim_build_info.argtypes = [C.c_int32, C.POINTER(C.c_char_p),
                                           C.POINTER(C.c_int64)]
        facts = {}
        name, value = C.c_char_p(), C.c_int64()
        for i in range(cdll.legsim_build_info_count()):
            st = cdll.legsim_build_info(i, C.byref(name), C.byref(value))
            if st != Status.OK:
                raise error_for(st, "legsim_build_info")
            facts[name.value.decode()] = int(value.value)
        return facts, "legsim_build_info"
    for cand in _config_h_candidates(path, precision):
        if cand.is_file():
            cfg = parse_config_h(cand)
            if all(k in cfg for k in _CONFIG_KEYS):
                return cfg, str(cand)
    raise LayoutMismatch(f"{path} has no legsim_build_info and no legsim/config.h was found "
                         "next to it: its struct layout is unknown (rebuild the library)")


# ---- the loaded library --------------------------------------------------------
class Library:
    """One loaded shared library with its ctypes types and prototypes.

    Attributes: ``path``, ``precision`` ("double" or "float"), ``cdll`` (the
    ``ctypes.CDLL``), ``config`` (the build's facts: ``LEGSIM_MAX_BODIES``, ...),
    ``config_source``, ``real`` (``ctypes.c_double`` or ``c_float``), ``np_real``,
    ``sim_size`` (bytes of a sim), and the struct types ``ModelDesc``,
    ``Options``, ``Report``, ``Reaction``, ``WorstCase``.
    Get one with :func:`load_library` (cached per file).
    """

    def __init__(self, path: Path, precision: str | None = None):
        self.path = Path(path)
        self.cdll = C.CDLL(str(self.path))
        guess = precision or ("float" if "_f32" in self.path.name else "double")
        self.config, self.config_source = _build_facts(self.cdll, self.path, guess)
        use_float = bool(self.config["LEGSIM_USE_FLOAT"])
        self.precision = precision = precision or ("float" if use_float else "double")
        if use_float != (precision == "float"):
            raise LayoutMismatch(f"{self.path}: asked for {precision}, but the library is built "
                                 f"with LEGSIM_USE_FLOAT={int(use_float)}")
        self.real = C.c_float if use_float else C.c_double
        self.np_real = np.float32 if use_float else np.float64
        self._define_types()
        self._check_layout()
        self._prototypes()
        self.sim_size = int(self.cdll.legsim_sim_size())

    def _define_types(self):
        cfg, real = self.config, self.real
        NL = cfg["LEGSIM_NAME_LEN"]
        MB, MJ = cfg["LEGSIM_MAX_BODIES"], cfg["LEGSIM_MAX_JOINTS"]
        MA, MF = cfg["LEGSIM_MAX_ACTUATORS"], cfg["LEGSIM_MAX_FORCES"]
        MP, MPD = cfg["LEGSIM_MAX_POSES"], cfg["LEGSIM_MAX_POSE_DRIVERS"]
        MC = max(1, cfg.get("LEGSIM_MAX_CONTACTS", 0))  # LEGSIM_CONTACT_SLOTS
        d, i32 = C.c_double, C.c_int32

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
            _fields_ = [("name", C.c_char * NL), ("n_drivers", i32),
                        ("driver", CoordDriver * MPD), ("guess", (d * 3) * MB)]

        class ContactDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("body", i32), ("point", d * 2)]

        class GroundDesc(C.Structure):
            _fields_ = [("point", d * 2), ("slope_rad", d), ("mu_static", d), ("mu_kinetic", d)]

        class ModelDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("gravity_mps2", d * 2),
                        ("n_bodies", i32), ("n_joints", i32), ("n_actuators", i32),
                        ("n_forces", i32), ("n_poses", i32),
                        ("body", BodyDesc * MB), ("joint", JointDesc * MJ),
                        ("actuator", ActuatorDesc * MA), ("force", ForceDesc * MF),
                        ("pose", PoseDesc * MP), ("foot_body", i32), ("foot_point", d * 2),
                        ("n_contacts", i32), ("contact", ContactDesc * MC),
                        ("ground", GroundDesc)]

        class Contact(C.Structure):
            _fields_ = [("state", C.c_int), ("normal_n", real), ("tangential_n", real),
                        ("friction_use", real), ("position", real * 2), ("slip_mps", real),
                        ("impulse_ns", real * 2), ("holds", i32)]

        class Options(C.Structure):
            _fields_ = [("integrator", C.c_int), ("step_s", d), ("disable", C.c_uint32),
                        ("rho_inf", d), ("max_newton_iter", i32), ("newton_tol", d),
                        ("statics_rule", C.c_int), ("contact_law", C.c_int)]

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

        class HexapodLegDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("leg", ModelDesc), ("hip_m", d * 3),
                        ("heading_rad", d)]

        class HexapodDesc(C.Structure):
            _fields_ = [("name", C.c_char * NL), ("gravity_mps2", d * 3), ("box_mass_kg", d),
                        ("box_size_m", d * 3), ("box_inertia_kgm2", d * 3), ("yoke_mass_kg", d),
                        ("yoke_com_m", d * 3), ("yoke_inertia_kgm2", d * 3), ("hip_offset_m", d),
                        ("bar_radius_m", d), ("rowing_gear_ratio", d), ("rowing_max_torque_nm", d),
                        ("rowing_stroke_rad", d * 2), ("rowing_servo_kp_nm_per_rad", d),
                        ("rowing_servo_kd_nms_per_rad", d), ("n_legs", i32), ("leg", HexapodLegDesc * 6),
                        ("ground_point_m", d * 3), ("ground_normal", d * 3), ("mu_static", d),
                        ("mu_kinetic", d), ("n_box_contacts", i32), ("box_contact_m", (d * 3) * 4)]

        class HexapodPose(C.Structure):
            _fields_ = [("box_m", d * 3), ("box_quat", d * 4), ("rowing_rad", d * 6),
                        ("length_m", (d * 2) * 6)]

        class HexapodStanding(C.Structure):
            _fields_ = [("com_m", d * 3), ("foot_m", (d * 3) * 6), ("foot_force_n", (d * 3) * 6),
                        ("actuator_force_n", (d * 2) * 6), ("rowing_torque_nm", d * 6),
                        ("margin_m", d)]

        J = 11  # LEGSIM_HEXAPOD_MAX_LEG_JOINTS

        class HexapodInverse(C.Structure):
            _fields_ = [("t_s", d), ("box_m", d * 3), ("box_quat", d * 4), ("box_velocity_mps", d * 3),
                        ("box_omega_radps", d * 3), ("stance", i32 * 6), ("foot_m", (d * 3) * 6),
                        ("foot_velocity_mps", (d * 3) * 6), ("foot_acceleration_mps2", (d * 3) * 6),
                        ("actuator_force_n", (d * 2) * 6), ("rowing_torque_nm", d * 6),
                        ("foot_force_n", (d * 3) * 6), ("cone_ratio", d * 6), ("n_joints", i32 * 6),
                        ("joint_force_n", ((d * 3) * J) * 6), ("joint_moment_nm", ((d * 3) * J) * 6)]

        class HexapodCommands(C.Structure):
            _fields_ = [("mode", (i32 * 3) * 6), ("value", (d * 3) * 6), ("feedforward", (d * 3) * 6)]

        class HexapodSweep(C.Structure):
            _fields_ = [("leg", i32), ("stance_mask", C.c_uint32), ("box_height_m", d), ("distance_m", d * 2),
                        ("n_distance", i32), ("heading_rad", d * 2), ("n_heading", i32)]

        class HexapodSweepPoint(C.Structure):
            _fields_ = [("index", i32), ("status", C.c_int), ("distance_m", d), ("heading_rad", d),
                        ("rowing_rad", d), ("length_m", d * 2), ("standing", HexapodStanding)]

        class HexapodGait(C.Structure):
            _fields_ = [("period_s", d), ("duty", d), ("step_length_m", d), ("step_height_m", d),
                        ("turn_rad", d), ("box_height_m", d)]

        class HexapodSetpoint(C.Structure):
            _fields_ = [("foot_box_m", (d * 3) * 6), ("stance", i32 * 6), ("rowing_rad", d * 6),
                        ("length_m", (d * 2) * 6), ("box_m", d * 3), ("box_quat", d * 4)]

        class HexapodState(C.Structure):
            _fields_ = [("t_s", d), ("box_m", d * 3), ("box_quat", d * 4), ("box_velocity_mps", d * 3),
                        ("box_omega_radps", d * 3), ("rowing_rad", d * 6), ("length_m", (d * 2) * 6),
                        ("foot_m", (d * 3) * 6), ("foot_force_n", (d * 3) * 6),
                        ("actuator_force_n", (d * 2) * 6), ("rowing_torque_nm", d * 6), ("foot_state", i32 * 6),
                        ("kinetic_energy_j", d), ("events", i32), ("impacts", i32), ("cone_solved", i32),
                        ("cone_by_sweeps", i32), ("cone_max_iterations", i32), ("cone_max_residual", d),
                        ("actuator_stop", (i32 * 2) * 6), ("rowing_stop", i32 * 6), ("stop_impacts", i32), ("length_rate_mps", (d * 2) * 6),
                        ("rowing_rate_radps", d * 6), ("n_box_contacts", i32),
                        ("box_contact_m", (d * 3) * 4), ("box_contact_force_n", (d * 3) * 4),
                        ("box_contact_state", i32 * 4)]

        self.HexapodState = HexapodState
        self.HexapodDesc, self.HexapodPose, self.HexapodStanding = HexapodDesc, HexapodPose, HexapodStanding
        self.HexapodGait, self.HexapodSetpoint = HexapodGait, HexapodSetpoint
        self.HexapodSweep, self.HexapodSweepPoint = HexapodSweep, HexapodSweepPoint
        self.HexapodCommands, self.HexapodInverse = HexapodCommands, HexapodInverse
        self.ModelDesc, self.Options, self.Report = ModelDesc, Options, Report
        self.Reaction, self.WorstCase = Reaction, WorstCase
        self.Contact = Contact

    def _check_layout(self):
        """Each struct of the mirror has the library's size (when it says)."""
        cfg = self.config
        pairs = [("legsim_real", self.real), ("legsim_model_desc", self.ModelDesc),
                 ("legsim_options", self.Options), ("legsim_report", self.Report),
                 ("legsim_reaction", self.Reaction), ("legsim_worst_case", self.WorstCase),
                 ("legsim_contact", self.Contact), ("legsim_hexapod_desc", self.HexapodDesc),
                 ("legsim_hexapod_pose", self.HexapodPose),
                 ("legsim_hexapod_standing", self.HexapodStanding),
                 ("legsim_hexapod_commands", self.HexapodCommands), ("legsim_hexapod_inverse", self.HexapodInverse), ("legsim_hexapod_sweep", self.HexapodSweep), ("legsim_hexapod_sweep_point", self.HexapodSweepPoint),
                 ("legsim_hexapod_gait", self.HexapodGait), ("legsim_hexapod_setpoint", self.HexapodSetpoint),
                 ("legsim_hexapod_state", self.HexapodState)]
        bad = [f"{n}: library {cfg[f'sizeof({n})']} bytes, binding {C.sizeof(t)}"
               for n, t in pairs
               if f"sizeof({n})" in cfg and cfg[f"sizeof({n})"] != C.sizeof(t)]
        if cfg.get("LEGSIM_STORAGE_ALIGN", STORAGE_ALIGN) != STORAGE_ALIGN:
            bad.append(f"LEGSIM_STORAGE_ALIGN {cfg['LEGSIM_STORAGE_ALIGN']} != {STORAGE_ALIGN}")
        if bad:
            raise LayoutMismatch(f"{self.path}: the binding does not match legsim.h: "
                                 + "; ".join(bad))

    def _prototypes(self):
        R = self.real
        P, RP, st = C.c_void_p, C.POINTER(R), C.c_int
        MP, OP = C.POINTER(self.ModelDesc), C.POINTER(self.Options)
        NAMES = C.POINTER(C.c_char * self.config["LEGSIM_NAME_LEN"])
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
            "legsim_contact_event_time": (st, [P, C.c_int32, C.POINTER(C.c_double)]),
            "legsim_stroke_event_time": (st, [P, C.c_int32, C.POINTER(C.c_double)]),
            "legsim_contacts_check": (st, [P]),
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
            "legsim_assemble_foot": (st, [P, RP]),
            "legsim_velocity_analysis": (st, [P, RP]),
            "legsim_acceleration_analysis": (st, [P, RP]),
            "legsim_inverse_dynamics": (st, [P, RP, RP, RP, RP]),
            "legsim_inverse_dynamics_on_ground": (st, [P, C.c_uint32, RP, RP, RP, RP]),
            "legsim_statics": (st, [P, RP]),
            "legsim_statics_sweep": (st, [P, C.c_int32, C.POINTER(self.WorstCase)]),
            "legsim_step": (st, [P, C.c_int32]),
            "legsim_reactions": (st, [P, C.POINTER(self.Reaction)]),
            "legsim_multipliers": (st, [P, RP]),
            "legsim_command_force": (st, [P, C.c_int32, R]),
            "legsim_command_length": (st, [P, C.c_int32, R]),
            "legsim_set_force": (st, [P, C.c_int32, RP]),
            "legsim_n_contacts": (C.c_int32, [P]),
            "legsim_contacts": (st, [P, C.POINTER(self.Contact)]),
            "legsim_set_contact_state": (st, [P, C.c_int32, C.c_int]),
            "legsim_assemble_on_ground": (st, [P, RP, R]),
            # the run-time model loader (firmware_core/host/model_toml.hpp)
            "legsim_model_load_toml": (st, [C.c_char_p, C.c_char_p, MP, C.c_char_p, C.c_size_t]),
            "legsim_model_parse_toml": (st, [C.c_char_p, C.c_size_t, C.c_char_p, C.c_char_p, MP,
                                             C.c_char_p, C.c_size_t]),
            "legsim_model_toml_variants": (st, [C.c_char_p, NAMES, C.c_int32,
                                                C.POINTER(C.c_int32), C.c_char_p, C.c_size_t]),
            "legsim_hexapod_load_toml": (st, [C.c_char_p, C.POINTER(self.HexapodDesc), C.c_char_p,
                                              C.c_size_t]),
            "legsim_hexapod_storage_size": (C.c_size_t, []),
            "legsim_hexapod_statics": (st, [C.POINTER(self.HexapodDesc), C.POINTER(self.HexapodPose),
                                            C.c_uint32, C.POINTER(C.c_double), P, C.c_size_t,
                                            C.POINTER(self.HexapodStanding)]),
            "legsim_hexapod_leg_reach": (st, [C.POINTER(self.HexapodDesc), C.c_int32, C.POINTER(C.c_double), P,
                                              C.c_size_t, C.POINTER(C.c_double), C.POINTER(C.c_double)]),
            "legsim_hexapod_reaction_sweep": (st, [C.POINTER(self.HexapodDesc), C.POINTER(self.HexapodSweep),
                                                   C.c_int32, C.c_int32, P, C.c_size_t,
                                                   C.POINTER(self.HexapodSweepPoint)]),
            "legsim_hexapod_gait_setpoints": (st, [C.POINTER(self.HexapodDesc), C.POINTER(self.HexapodGait),
                                                   C.c_double, P, C.c_size_t, C.POINTER(self.HexapodSetpoint)]),
            "legsim_hexapod_support_margin": (st, [C.POINTER(C.c_double * 3), C.c_int32, C.POINTER(C.c_double),
                                                   C.POINTER(C.c_double)]),
            "legsim_hexapod_sim_size": (C.c_size_t, []),
            "legsim_hexapod_sim_init": (st, [P, C.c_size_t, C.POINTER(self.HexapodDesc), C.POINTER(self.HexapodPose),
                                             C.c_uint32, C.POINTER(P)]),
            "legsim_hexapod_command": (st, [P, C.POINTER(C.c_double * 2), C.POINTER(C.c_double)]),
            "legsim_hexapod_inverse_storage_size": (C.c_size_t, []),
            "legsim_hexapod_inverse_dynamics": (st, [C.POINTER(self.HexapodDesc), C.POINTER(self.HexapodGait),
                                                     C.c_double, P, C.c_size_t, C.POINTER(self.HexapodInverse)]),
            "legsim_hexapod_gait_state": (st, [C.POINTER(self.HexapodDesc), C.POINTER(self.HexapodGait), C.c_double,
                                               P, C.c_size_t, C.POINTER(C.c_double), C.POINTER(C.c_double),
                                               C.POINTER(C.c_double), C.c_int32, C.POINTER(C.c_int32)]),
            "legsim_hexapod_command_each": (st, [P, C.POINTER(self.HexapodCommands)]),
            "legsim_hexapod_command_pose": (st, [P, C.POINTER(C.c_double * 2), C.POINTER(C.c_double),
                                                 C.POINTER(C.c_double * 2), C.POINTER(C.c_double)]),
            "legsim_hexapod_step": (st, [P, C.c_double, C.c_int32]),
            "legsim_hexapod_set_integrator": (st, [P, C.c_int]),
            "legsim_hexapod_set_velocity": (st, [P, C.POINTER(C.c_double), C.POINTER(C.c_double)]),
            "legsim_hexapod_get_state": (st, [P, C.POINTER(self.HexapodState)]),
            "legsim_hexapod_body_poses": (st, [P, C.POINTER(C.c_double), C.c_int32, C.POINTER(C.c_int32)]),
        }
        self.has_toml_loader = hasattr(self.cdll, "legsim_model_load_toml")
        for fname, (res, args) in protos.items():
            if "toml" in fname and not self.has_toml_loader:
                continue
            f = getattr(self.cdll, fname)
            f.restype = res
            f.argtypes = args

    # ---- small helpers used by the API classes ----
    def status_str(self, status: int) -> str:
        """The library's one-line explanation of a status."""
        s = self.cdll.legsim_status_str(int(status))
        return s.decode() if s else ""

    def check(self, status: int, function: str, text: str | None = None) -> None:
        """Raises the exception for a failing status (see legsim.errors)."""
        if status != Status.OK:
            raise error_for(status, function, self.status_str(status) if text is None else text)

    def default_options(self):
        """``legsim_default_options()`` as the ctypes Options struct."""
        return self.cdll.legsim_default_options()

    def __repr__(self) -> str:
        return f"<legsim.Library {self.precision} {self.path}>"


_LIBRARIES: dict = {}


def load_library(precision: str | None = None, lib_path=None) -> Library:
    """The loaded :class:`Library` (found by :func:`find_library`; cached per file).

    precision: "double" or "float"; None means "double", or, when ``lib_path`` is a
    file, whatever that library is built with."""
    if precision is None and lib_path is not None and Path(lib_path).is_file():
        path = Path(lib_path).resolve()
    else:
        path = find_library(precision or "double", lib_path)
    key = str(path)
    if key not in _LIBRARIES:
        _LIBRARIES[key] = Library(path, precision)
    lib = _LIBRARIES[key]
    if precision is not None and lib.precision != precision:
        raise LayoutMismatch(f"{path}: asked for {precision}, but the library is "
                             f"{lib.precision}")
    return lib
