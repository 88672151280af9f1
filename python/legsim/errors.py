"""Statuses of legsim.h as Python values and exceptions.

Every call of the C API returns a ``legsim_status``. The Python API turns every
status other than ``LEGSIM_OK`` into an exception: an instance of the subclass
of :class:`LegsimError` for that status (``SingularError`` for
``LEGSIM_ERR_SINGULAR``, ...), carrying the numeric code (``.status``), the
C name (``.status_name``), the function that failed (``.function``) and the
library's own explanation (``.text``, from ``legsim_status_str`` or a loader
message). Nothing fails silently.
"""
from __future__ import annotations

import enum


class Status(enum.IntEnum):
    """legsim_status of legsim.h (``Status.ERR_SINGULAR.c_name == "LEGSIM_ERR_SINGULAR"``)."""

    OK = 0
    ERR_NULL = 1             # a required pointer is NULL
    ERR_STORAGE = 2          # storage too small or misaligned
    ERR_MODEL = 3            # model description invalid
    ERR_CAPACITY = 4         # model exceeds the compile-time capacity
    ERR_BAD_INPUT = 5        # NaN/Inf, index out of range, or a nonsensical option
    ERR_OUT_OF_STROKE = 6    # a length command or assembly length outside the stroke
    ERR_NOT_CONVERGED = 7    # Newton iteration hit its limit
    ERR_SINGULAR = 8         # constraint Jacobian rank deficient: dead centre
    ERR_UNREACHABLE = 9      # the lengths cannot be met
    ERR_NO_EQUILIBRIUM = 10  # statics: the loads cannot be balanced
    ERR_DISABLED = 11        # stripped at compile time or disabled by the options
    ERR_STATE = 12           # state not finite or no pose assembled yet
    ERR_DIVERGED = 13        # the integrator produced a non-finite or exploding state
    ERR_CONTACT = 14         # the contact problem has no usable solution

    @property
    def c_name(self) -> str:
        """The enumerator's name in legsim.h, e.g. ``"LEGSIM_ERR_SINGULAR"``."""
        return "LEGSIM_" + self.name


def status_name(status: int) -> str:
    """The C name of a status code (``"LEGSIM_ERR_STATE"``), or ``"status N"`` if unknown."""
    try:
        return Status(int(status)).c_name
    except ValueError:
        return f"status {int(status)}"


class LegsimError(RuntimeError):
    """A legsim call returned a status other than LEGSIM_OK.

    Attributes: ``status`` (int code), ``status_name`` (e.g. ``"LEGSIM_ERR_SINGULAR"``),
    ``function`` (the C function, e.g. ``"legsim_assemble"``), ``text`` (the
    library's message). Catch a subclass (``legsim.SingularError``) for one status.
    """

    status_code: int | None = None  # set on each subclass

    def __init__(self, status: int, function: str, text: str = ""):
        self.status = int(status)
        self.status_name = status_name(self.status)
        self.function = function
        self.text = text
        super().__init__(f"{function}: {self.status_name}" + (f" ({text})" if text else ""))

    @property
    def name(self) -> str:
        """Alias of ``status_name``."""
        return self.status_name


class NullError(LegsimError):
    """LEGSIM_ERR_NULL: a required pointer was NULL (a binding bug)."""


class StorageError(LegsimError):
    """LEGSIM_ERR_STORAGE: the sim storage is too small or misaligned."""


class ModelError(LegsimError):
    """LEGSIM_ERR_MODEL: the model description (or model file) is invalid."""


class CapacityError(LegsimError):
    """LEGSIM_ERR_CAPACITY: the model exceeds the build's LEGSIM_MAX_* capacities."""


class BadInputError(LegsimError):
    """LEGSIM_ERR_BAD_INPUT: NaN/Inf, an index out of range, or a nonsensical option."""


class OutOfStrokeError(LegsimError):
    """LEGSIM_ERR_OUT_OF_STROKE: a length outside the actuator's stroke."""


class NotConvergedError(LegsimError):
    """LEGSIM_ERR_NOT_CONVERGED: a Newton iteration hit its limit."""


class SingularError(LegsimError):
    """LEGSIM_ERR_SINGULAR: rank-deficient constraint Jacobian (a dead centre)."""


class UnreachableError(LegsimError):
    """LEGSIM_ERR_UNREACHABLE: the actuator lengths cannot be met."""


class NoEquilibriumError(LegsimError):
    """LEGSIM_ERR_NO_EQUILIBRIUM: statics cannot balance the loads."""


class DisabledError(LegsimError):
    """LEGSIM_ERR_DISABLED: stripped at compile time or disabled by the options."""


class StateError(LegsimError):
    """LEGSIM_ERR_STATE: the state is not finite, or no pose is assembled yet."""


class DivergedError(LegsimError):
    """LEGSIM_ERR_DIVERGED: the integrator produced a non-finite or exploding state."""


class ContactError(LegsimError):
    """LEGSIM_ERR_CONTACT: the contact problem has no usable solution (redundant or
    inconsistent contacts)."""


ERRORS: dict[Status, type[LegsimError]] = {
    Status.ERR_NULL: NullError, Status.ERR_STORAGE: StorageError, Status.ERR_MODEL: ModelError,
    Status.ERR_CAPACITY: CapacityError, Status.ERR_BAD_INPUT: BadInputError,
    Status.ERR_OUT_OF_STROKE: OutOfStrokeError, Status.ERR_NOT_CONVERGED: NotConvergedError,
    Status.ERR_SINGULAR: SingularError, Status.ERR_UNREACHABLE: UnreachableError,
    Status.ERR_NO_EQUILIBRIUM: NoEquilibriumError, Status.ERR_DISABLED: DisabledError,
    Status.ERR_STATE: StateError, Status.ERR_DIVERGED: DivergedError,
    Status.ERR_CONTACT: ContactError,
}
for _s, _cls in ERRORS.items():
    _cls.status_code = int(_s)


def error_for(status: int, function: str, text: str = "") -> LegsimError:
    """The exception for a failing status (LegsimError itself for an unknown code)."""
    try:
        cls = ERRORS[Status(int(status))]
    except (ValueError, KeyError):
        cls = LegsimError
    return cls(status, function, text)


class LibraryNotFound(FileNotFoundError):
    """liblegsim.so / liblegsim_f32.so was not found where it was looked for."""


class LayoutMismatch(RuntimeError):
    """The library's structs differ from this binding's mirror of legsim.h."""

# Tracebacks name them as users import them: legsim.UnreachableError.
for _cls in (LegsimError, *ERRORS.values(), LibraryNotFound, LayoutMismatch, Status):
    _cls.__module__ = "legsim"
