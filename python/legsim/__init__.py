"""legsim: the Python API of the legsim core.

Loads the core's shared library (``liblegsim.so`` in double, ``liblegsim_f32.so``
in float) in-process through ctypes and wraps its C API (legsim.h): models from
TOML files or compiled in, options, assembly, velocity and acceleration analysis,
inverse dynamics, statics and its worst-case sweep, forward dynamics, reactions.
Values are numpy arrays in SI units; every failing status raises a
:class:`LegsimError` subclass carrying the status code and its C name.

    >>> import legsim
    >>> sim = legsim.Sim("models/leg.toml", integrator="rk4", step=1e-3)  # from the repository root
    >>> q = sim.assemble_pose("stand")
    >>> sim.statics().round(3)   # actuator forces holding the leg (N)
    array([-93.929,   1.387])
    >>> sim.assemble([0.80, 0.35])
    Traceback (most recent call last):
    legsim.UnreachableError: legsim_assemble: LEGSIM_ERR_UNREACHABLE (lengths cannot be reached)

See python/README.md for the whole API.
"""
from ._lib import LIB_NAMES, Library, find_library, library_available, load_library
from .errors import (BadInputError, CapacityError, ContactError, DisabledError, DivergedError, LayoutMismatch,
                     LegsimError, LibraryNotFound, ModelError, NoEquilibriumError,
                     NotConvergedError, NullError, OutOfStrokeError, SingularError, StateError,
                     Status, StorageError, UnreachableError, error_for, status_name)
from .hexapod import Hexapod, HexapodSim
from .model import Model, builtin_variants, model_variants
from .resources import cli_path, data_dir, data_path
from .sim import (COND_SINGULAR, COND_WARN, CONTACT_DTYPE, CONTACT_STATES, DISABLE, EVENTS,
                  INTEGRATORS, STATICS_RULES, CONTACT_LAWS, Report, Sim, WorstCase,
                  disable_mask)

__version__ = "0.1.0"  # = python/pyproject.toml, project() of CMakeLists.txt

__all__ = [
    "Sim", "Model", "Hexapod", "HexapodSim", "Report", "WorstCase", "Library", "Status",
    "model_variants", "builtin_variants", "data_dir", "data_path", "cli_path", "find_library", "library_available", "load_library",
    "status_name", "error_for", "disable_mask",
    "LegsimError", "NullError", "StorageError", "ModelError", "CapacityError", "BadInputError",
    "OutOfStrokeError", "NotConvergedError", "SingularError", "UnreachableError",
    "NoEquilibriumError", "DisabledError", "StateError", "DivergedError", "ContactError",
    "LibraryNotFound", "LayoutMismatch",
    "DISABLE", "EVENTS", "INTEGRATORS", "COND_WARN", "COND_SINGULAR", "LIB_NAMES",
    "CONTACT_STATES", "CONTACT_DTYPE", "STATICS_RULES", "CONTACT_LAWS",
]
