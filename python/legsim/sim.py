"""Sim: one legsim simulation (``legsim_sim``) in storage owned by Python.

Units are SI throughout: m, rad, s, kg, N, N m. Generalized coordinates are
absolute: ``q = (x_i, y_i, phi_i)`` per body, the centre of mass (m) and the
angle of the body's axis (rad). Arrays come back as float64 numpy arrays in
both precisions (a float build's values widened exactly).

Every call checks the C status: a failing one raises the subclass of
:class:`legsim.LegsimError` for it (e.g. ``UnreachableError`` for
``LEGSIM_ERR_UNREACHABLE``) and, as the C API promises, leaves the state as it
was. Arguments are checked for size (ValueError); NaN and Inf are passed on to
the core, which refuses them with ``BadInputError``.
"""
from __future__ import annotations

import ctypes as C
import math
import os
from dataclasses import dataclass, field
from typing import Iterable, Union

import numpy as np

from ._lib import STORAGE_ALIGN, Library, load_library
from .errors import BadInputError, Status

# ranges of legsim.h (LEGSIM_MAX_COORD, LEGSIM_MAX_FORCE_N), for the messages that name an
# argument outside its range (tests/python/test_api_errors.py checks them against legsim.h)
MAX_COORD = 1e3         # m
MAX_FORCE_N = 1e6       # N (loads; also N m for torques)
from .model import Model

INTEGRATORS = {"rk4": 0, "galpha": 1}
"""``"rk4"``: explicit RK4 on the index-1 form with projection; ``"galpha"``:
implicit index-3 generalized-alpha (Arnold & Bruls)."""

DISABLE = {
    "gravity": 1 << 0,
    "force_elements": 1 << 1,   # point forces, torques, spring-dampers
    "reactions": 1 << 2,        # no multipliers at the end of a step
    "projection": 1 << 3,       # RK4: no projection onto Phi = 0, Phi_q qd = 0
    "actuators": 1 << 4,        # actuators exert no force (passive joints)
    "stroke_limits": 1 << 5,    # do not stop actuators at their stroke ends
}
"""Disable flags of legsim.h (``enum legsim_disable``) by name."""

EVENTS = {
    "stroke_min": 1 << 0,
    "stroke_max": 1 << 1,
    "force_saturated": 1 << 2,
    "near_singular": 1 << 3,
    "liftoff": 1 << 4,                # a foot's normal force would pull: free
    "touchdown": 1 << 5,              # a free foot reached the ground: impulse
    "stick_to_slip": 1 << 6,          # a stuck foot left the static friction cone
    "slip_to_stick": 1 << 7,          # a sliding foot's velocity changed sign
    "contact_inconsistent": 1 << 8,   # no consistent contact mode: the last one kept
    "contact_ambiguous": 1 << 9,      # several consistent modes: the priority picked one
    "events_deferred": 1 << 10,       # more contact events in a step than it locates
    "event_inexact": 1 << 11,         # an event's root finding ran out of iterations
}
"""Event bits of legsim.h (``enum legsim_event``) by name."""

STATICS_RULES = {"equal_friction": 0, "min_tangential": 1}
"""``legsim_statics_rule`` of legsim.h by name: the rule that fixes the statics of a
stance on two stuck feet (equal friction use T/N on both; or least T_0^2 + T_1^2)."""

CONTACT_LAWS = {"lcp": 0, "paper": 1}
"""``legsim_contact_law`` of legsim.h by name: the feet's transitions in a step ("lcp":
each foot by its own Coulomb cone; "paper": while both feet are on the ground the foot with
the smaller |T| is released when a foot leaves its cone, the other stays stuck)."""

CONTACT_STATES = {"free": 0, "stuck": 1, "sliding": 2}
"""``legsim_contact_state`` of legsim.h by name."""

CONTACT_DTYPE = np.dtype([("state", "U8"), ("normal", "f8"), ("tangential", "f8"),
                          ("friction_use", "f8"), ("position", "f8", (2,)), ("slip", "f8"),
                          ("impulse", "f8", (2,)), ("holds", "?")])
"""Fields of :meth:`Sim.contacts`: state name, N and T (N), |T|/N, foot position (m),
slip velocity along the ground (m/s), last impact impulse (normal, tangential; N s),
whether the static friction cone holds the force (N >= 0, |T| <= mu_static N)."""

COND_WARN = 1e3       # condition estimate above which "near_singular" is raised
COND_SINGULAR = 1e5   # an assembly landing above this is refused (SingularError)


def disable_mask(disable) -> int:
    """An int mask, a flag name, or an iterable of flag names (see DISABLE) as a mask."""
    if disable is None:
        return 0
    if isinstance(disable, (int, np.integer)):
        return int(disable)
    if isinstance(disable, str):
        disable = [disable]
    mask = 0
    for name in disable:
        if name not in DISABLE:
            raise ValueError(f"unknown disable flag {name!r}; known: {sorted(DISABLE)}")
        mask |= DISABLE[name]
    return mask


@dataclass
class Report:
    """``legsim_report`` of the last solve: Newton ``iterations``, ``residual`` (max |Phi|,
    m or rad), ``condition`` estimate, and the ``events`` bits raised since
    :meth:`Sim.clear_events`."""

    iterations: int
    residual: float
    condition: float
    events: int

    def event_names(self) -> list[str]:
        """The raised events by name (see EVENTS)."""
        return [k for k, v in EVENTS.items() if self.events & v]


@dataclass
class WorstCase:
    """Worst-case statics over a grid of the first two actuators' strokes.

    ``max_reaction_n`` (n_joints,): largest |reaction force| of each joint (N);
    ``max_actuator_force_n`` (n_actuators,): largest |axial force| (N);
    ``at_length_m`` (n_joints, n_actuators): actuator lengths where each joint's
    maximum occurs (m); ``actuator_at_length_m`` (n_actuators, n_actuators): where each
    actuator's maximum occurs; ``n_poses`` evaluated, ``n_failed`` not assembled."""

    max_reaction_n: np.ndarray
    max_actuator_force_n: np.ndarray
    at_length_m: np.ndarray
    actuator_at_length_m: np.ndarray
    n_poses: int
    n_failed: int


ModelLike = Union[Model, str, os.PathLike, None]


class Sim:
    """One simulation of a model, with its state, options and workspace.

    Parameters
    ----------
    model : Model, path, or None
        A :class:`Model`, the path of a model TOML file (loaded with ``variant``), or
        None for the leg compiled into the library (``variant`` of it).
    variant : str, optional
        Model variant, "revolute" by default (the leg also has "slot").
    precision : "double" or "float"
        Which library: ``liblegsim.so`` or ``liblegsim_f32.so``. Default: the
        model's library for a Model, that of ``lib_path`` if it names a file, else
        "double".
    lib_path : path, optional
        The library file or its directory (see :func:`legsim.find_library`).
    integrator : "rk4" or "galpha"
    step : float
        Fixed step h (s).
    disable : flag names, a name, or a mask
        See DISABLE.
    rho_inf, max_newton_iter, newton_tol : optional
        Generalized-alpha spectral radius at infinity in [0, 1]; Newton iteration
        limit; Newton tolerance on the constraint residual (m, rad). Defaults:
        the library's (0.8, 25, 1e-10 double / 1e-5 float).

    Nothing is assembled yet: call :meth:`assemble_pose` or :meth:`assemble`.

    Low-level access (for timing or calls the API does not wrap): ``library``
    (:class:`legsim.Library`, its ``cdll`` is the ctypes library) and ``handle``
    (the ``legsim_sim *``).
    """

    def __init__(self, model: ModelLike = None, *, variant: str | None = None,
                 precision: str | None = None, lib_path=None, integrator: str = "rk4",
                 step: float = 1e-3, disable=0, rho_inf: float | None = None,
                 max_newton_iter: int | None = None, newton_tol: float | None = None,
                 statics_rule: str | None = None, contact_law: str | None = None):
        if isinstance(model, Model):
            if variant is not None and variant != model.variant:
                raise ValueError("variant is given by the Model; load the other variant instead")
            lib = model.library if precision is None and lib_path is None \
                else load_library(precision, lib_path)
            model = model.for_library(lib)
        else:
            lib = load_library(precision, lib_path)
            if model is None:
                model = Model.builtin(variant or "revolute", precision=lib.precision,
                                      lib_path=lib.path)
            else:
                model = Model.from_toml(model, variant, precision=lib.precision,
                                        lib_path=lib.path)
        self.library: Library = lib
        self.model: Model = model  # kept: the core reads the description by pointer
        self.precision = lib.precision
        self.variant = model.variant
        self._real = lib.real
        self._storage = C.create_string_buffer(lib.sim_size + STORAGE_ALIGN)
        base = C.addressof(self._storage)
        self._addr = base + (-base) % STORAGE_ALIGN
        self._options = lib.default_options()
        self._apply_options(self._options, integrator, step, disable, rho_inf, max_newton_iter,
                            newton_tol, statics_rule, contact_law)
        out = C.c_void_p()
        self._check(lib.cdll.legsim_init(C.c_void_p(self._addr), lib.sim_size,
                                         C.byref(model.desc), C.byref(self._options),
                                         C.byref(out)), "legsim_init")
        self.handle = out
        L = lib.cdll
        self.n_bodies = int(L.legsim_n_bodies(out))
        self.n_coords = int(L.legsim_n_coords(out))
        self.n_constraints = int(L.legsim_n_constraints(out))
        self.n_joints = int(L.legsim_n_joints(out))
        self.n_actuators = int(L.legsim_n_actuators(out))
        self.n_forces = int(L.legsim_n_forces(out))
        R = lib.real
        self._qbuf = (R * self.n_coords)()
        self._cbuf = (R * max(1, self.n_constraints))()
        self._abuf = (R * max(1, self.n_actuators))()
        self._abuf2 = (R * max(1, self.n_actuators))()
        self._rbuf = (lib.Reaction * max(1, self.n_joints))()
        self.n_contacts = int(L.legsim_n_contacts(out)) if hasattr(L, "legsim_n_contacts") else 0
        self._ctbuf = (lib.Contact * max(1, self.n_contacts))()

    def __repr__(self) -> str:
        return (f"<legsim.Sim {self.model.name!r} {self.variant} {self.precision} "
                f"{self.integrator} h={self.step_size:g} s t={self.time:g} s>")

    # ---- helpers ----
    def _check(self, status: int, function: str):
        if status != 0:
            self.library.check(status, function)

    @staticmethod
    def _apply_options(o, integrator=None, step=None, disable=None, rho_inf=None,
                       max_newton_iter=None, newton_tol=None, statics_rule=None,
                       contact_law=None):
        if integrator is not None:
            if integrator not in INTEGRATORS:
                raise ValueError(f"integrator must be one of {sorted(INTEGRATORS)}, "
                                 f"not {integrator!r}")
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
        if statics_rule is not None:
            if statics_rule not in STATICS_RULES:
                raise ValueError(f"statics_rule must be one of {sorted(STATICS_RULES)}, "
                                 f"not {statics_rule!r}")
            o.statics_rule = STATICS_RULES[statics_rule]
        if contact_law is not None:
            if contact_law not in CONTACT_LAWS:
                raise ValueError(f"contact_law must be one of {sorted(CONTACT_LAWS)}, "
                                 f"not {contact_law!r}")
            o.contact_law = CONTACT_LAWS[contact_law]

    def _arr(self, values, n: int, what: str):
        v = np.asarray(values, dtype=float).reshape(-1)
        if v.size != n:
            raise ValueError(f"{what}: need {n} values, got {v.size}")
        return (self._real * n)(*v.tolist())

    @staticmethod
    def _np(buf, n: int) -> np.ndarray:
        return np.array(buf[:n], dtype=np.float64)

    def _actuator(self, actuator) -> int:
        if isinstance(actuator, str):
            names = self.model.actuator_names
            if actuator not in names:
                raise ValueError(f"no actuator {actuator!r}; the model has {names}")
            return names.index(actuator)
        return int(actuator)

    # ---- options ----
    @property
    def integrator(self) -> str:
        """"rk4" or "galpha"."""
        return {v: k for k, v in INTEGRATORS.items()}[int(self._options.integrator)]

    @property
    def step_size(self) -> float:
        """Fixed step h (s)."""
        return float(self._options.step_s)

    @property
    def disabled(self) -> list[str]:
        """Names of the disable flags set (see DISABLE)."""
        return [k for k, v in DISABLE.items() if self._options.disable & v]

    @property
    def options(self) -> dict:
        """The current options: integrator, step, disable (mask), rho_inf,
        max_newton_iter, newton_tol, statics_rule, contact_law."""
        o = self._options
        return {"integrator": self.integrator, "step": float(o.step_s),
                "disable": int(o.disable), "rho_inf": float(o.rho_inf),
                "max_newton_iter": int(o.max_newton_iter), "newton_tol": float(o.newton_tol),
                "statics_rule": {v: k for k, v in STATICS_RULES.items()}[int(o.statics_rule)],
                "contact_law": {v: k for k, v in CONTACT_LAWS.items()}[int(o.contact_law)]}

    def set_options(self, **options) -> None:
        """Changes options (integrator=, step=, disable=, rho_inf=, max_newton_iter=,
        newton_tol=, statics_rule=, contact_law=); a refused set (BadInputError, DisabledError) changes
        nothing."""
        unknown = set(options) - {"integrator", "step", "disable", "rho_inf",
                                  "max_newton_iter", "newton_tol", "statics_rule",
                                  "contact_law"}
        if unknown:
            raise TypeError(f"unknown option(s) {sorted(unknown)}")
        new = type(self._options).from_buffer_copy(self._options)
        self._apply_options(new, **options)
        self._check(self.library.cdll.legsim_set_options(self.handle, C.byref(new)),
                    "legsim_set_options")
        self._options = new

    # ---- model ----
    def pose_index(self, pose: Union[str, int]) -> int:
        """Index of a pose of the model by name (an int passes through)."""
        if isinstance(pose, (int, np.integer)):
            return int(pose)
        names = self.model.pose_names
        if pose not in names:
            raise ValueError(f"no pose {pose!r}; the model has {names}")
        return names.index(pose)

    # ---- state ----
    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return float(self.library.cdll.legsim_time(self.handle))

    @property
    def step_count(self) -> int:
        """Steps taken since the last assembly or set_state."""
        return int(self.library.cdll.legsim_step_count(self.handle))

    @property
    def q(self) -> np.ndarray:
        """Positions (n_coords,): (x m, y m, phi rad) per body."""
        self._check(self.library.cdll.legsim_get_q(self.handle, self._qbuf), "legsim_get_q")
        return self._np(self._qbuf, self.n_coords)

    @property
    def qd(self) -> np.ndarray:
        """Velocities (n_coords,): m/s, m/s, rad/s per body."""
        self._check(self.library.cdll.legsim_get_qd(self.handle, self._qbuf), "legsim_get_qd")
        return self._np(self._qbuf, self.n_coords)

    @property
    def qdd(self) -> np.ndarray:
        """Accelerations (n_coords,) of the last solve: m/s^2, m/s^2, rad/s^2 per body."""
        self._check(self.library.cdll.legsim_get_qdd(self.handle, self._qbuf), "legsim_get_qdd")
        return self._np(self._qbuf, self.n_coords)

    def state_bytes(self) -> bytes:
        """q then qd as raw bytes in the build's precision (for bit-identity checks)."""
        self._check(self.library.cdll.legsim_get_q(self.handle, self._qbuf), "legsim_get_q")
        b = bytes(self._qbuf)
        self._check(self.library.cdll.legsim_get_qd(self.handle, self._qbuf), "legsim_get_qd")
        return b + bytes(self._qbuf)

    def set_state(self, q, qd=None, t: float = 0.0) -> None:
        """Sets q, qd (None: zero) and the time t (s); does not project onto the constraints."""
        qa = self._arr(q, self.n_coords, "q")
        qda = None if qd is None else self._arr(qd, self.n_coords, "qd")
        self._check(self.library.cdll.legsim_set_state(self.handle, qa, qda, float(t)),
                    "legsim_set_state")

    def report(self) -> Report:
        """Report of the last solve (iterations, residual, condition, events)."""
        r = self.library.Report()
        self._check(self.library.cdll.legsim_get_report(self.handle, C.byref(r)),
                    "legsim_get_report")
        return Report(int(r.iterations), float(r.residual), float(r.condition), int(r.events))

    def events(self) -> list[str]:
        """Names of the events raised since the last :meth:`clear_events`."""
        return self.report().event_names()

    def clear_events(self) -> None:
        self._check(self.library.cdll.legsim_clear_events(self.handle), "legsim_clear_events")

    def contacts_check(self) -> None:
        """Checks the contact modes now, as the next step would at its start (a start that
        cannot hold changes mode at the current time)."""
        self._check(self.library.cdll.legsim_contacts_check(self.handle), "legsim_contacts_check")

    def contact_event_time(self, k: int) -> float:
        """The time (s) of contact k's last contact event, located inside its step."""
        t = C.c_double()
        self._check(self.library.cdll.legsim_contact_event_time(self.handle, int(k), C.byref(t)),
                    "legsim_contact_event_time")
        return float(t.value)

    def stroke_event_time(self, a: int) -> float:
        """The time (s) actuator a last arrived on a stroke stop, located inside its step."""
        t = C.c_double()
        self._check(self.library.cdll.legsim_stroke_event_time(self.handle, int(a), C.byref(t)),
                    "legsim_stroke_event_time")
        return float(t.value)

    def stroke_event_mask(self) -> int:
        """Which actuators raised a stroke event (bit a = actuator a)."""
        return int(self.library.cdll.legsim_stroke_event_mask(self.handle))

    def constraints(self) -> tuple[np.ndarray, float]:
        """(Phi(q) (n_constraints,) in m or rad, max |Phi|)."""
        mx = self._real()
        self._check(self.library.cdll.legsim_constraints(self.handle, self._cbuf, C.byref(mx)),
                    "legsim_constraints")
        return self._np(self._cbuf, self.n_constraints), float(mx.value)

    def constraint_residual(self) -> float:
        """max |Phi(q)| (m or rad)."""
        mx = self._real()
        self._check(self.library.cdll.legsim_constraints(self.handle, None, C.byref(mx)),
                    "legsim_constraints")
        return float(mx.value)

    def jacobian(self) -> np.ndarray:
        """Constraint Jacobian Phi_q (n_constraints, n_coords)."""
        buf = (self._real * (self.n_constraints * self.n_coords))()
        self._check(self.library.cdll.legsim_jacobian(self.handle, buf), "legsim_jacobian")
        return np.array(buf[:], dtype=float).reshape(self.n_constraints, self.n_coords)

    def actuator_lengths(self) -> tuple[np.ndarray, np.ndarray]:
        """(lengths m, rates m/s), each (n_actuators,)."""
        self._check(self.library.cdll.legsim_actuator_lengths(self.handle, self._abuf,
                                                              self._abuf2),
                    "legsim_actuator_lengths")
        return self._np(self._abuf, self.n_actuators), self._np(self._abuf2, self.n_actuators)

    def actuator_forces(self) -> np.ndarray:
        """Axial force of each actuator in the current state (N, > 0 extends)."""
        self._check(self.library.cdll.legsim_actuator_forces(self.handle, self._abuf),
                    "legsim_actuator_forces")
        return self._np(self._abuf, self.n_actuators)

    def foot(self) -> np.ndarray:
        """Foot point position (x, y) in m, world."""
        xy = (self._real * 2)()
        self._check(self.library.cdll.legsim_foot_position(self.handle, xy),
                    "legsim_foot_position")
        return self._np(xy, 2)

    def reactions(self) -> np.ndarray:
        """(n_joints, 3) of the last dynamics, inverse-dynamics or statics solve: Fx, Fy (N,
        world axes) that each joint applies to its first-listed body, and the moment (N m)
        about that body's centre of mass."""
        self._check(self.library.cdll.legsim_reactions(self.handle, self._rbuf),
                    "legsim_reactions")
        return np.array([[r.force_n[0], r.force_n[1], r.moment_nm]
                         for r in self._rbuf[:self.n_joints]], dtype=float).reshape(-1, 3)

    def multipliers(self) -> np.ndarray:
        """Lagrange multipliers (n_constraints,) of the last solve."""
        self._check(self.library.cdll.legsim_multipliers(self.handle, self._cbuf),
                    "legsim_multipliers")
        return self._np(self._cbuf, self.n_constraints)

    # ---- analyses ----
    def assemble_pose(self, pose: Union[str, int] = 0) -> np.ndarray:
        """Assembles a named pose of the model (default: its first, "stand" for the leg)
        from its guess; qd = 0. Returns q."""
        self._check(self.library.cdll.legsim_assemble_pose(self.handle, self.pose_index(pose)),
                    "legsim_assemble_pose")
        return self.q

    def assemble(self, lengths=None) -> np.ndarray:
        """Newton-Raphson from the current q onto Phi(q) = 0 with the actuators at
        ``lengths`` (m, n_actuators; None: keep the current lengths); qd = 0. Raises
        OutOfStrokeError, UnreachableError, SingularError, NotConvergedError; on failure
        q is unchanged. Returns q."""
        arr = None if lengths is None else self._arr(lengths, self.n_actuators, "lengths")
        self._check(self.library.cdll.legsim_assemble(self.handle, arr), "legsim_assemble")
        return self.q

    def assemble_foot(self, foot) -> np.ndarray:
        """The leg's inverse kinematics: Newton-Raphson from the current q (the branch near
        it) onto Phi(q) = 0 with the foot at ``foot`` (m, world (x, y)); qd = 0; the lengths
        that put it there are ``actuator_lengths()[0]``. Raises UnreachableError,
        NotConvergedError, SingularError, OutOfStrokeError (a foot the strokes do not
        reach), BadInputError (a model without a foot, or a robot); on failure q is
        unchanged. Returns q."""
        self._check(self.library.cdll.legsim_assemble_foot(self.handle, self._arr(foot, 2, "foot")),
                    "legsim_assemble_foot")
        return self.q

    def velocity_analysis(self, rates) -> np.ndarray:
        """Sets and returns qd for driven actuator length rates (m/s) in the current q."""
        self._check(self.library.cdll.legsim_velocity_analysis(
            self.handle, self._arr(rates, self.n_actuators, "rates")), "legsim_velocity_analysis")
        return self.qd

    def acceleration_analysis(self, accels) -> np.ndarray:
        """Sets and returns qdd for driven actuator length accelerations (m/s^2), in the
        current q and qd."""
        self._check(self.library.cdll.legsim_acceleration_analysis(
            self.handle, self._arr(accels, self.n_actuators, "accels")),
            "legsim_acceleration_analysis")
        return self.qdd

    def inverse_dynamics(self, lengths, rates, accels) -> np.ndarray:
        """Actuator forces (N, n_actuators) that drive the motion with these lengths (m),
        rates (m/s) and accelerations (m/s^2); assembles from the current q.
        :meth:`reactions` then holds the joints' reactions."""
        na = self.n_actuators
        self._check(self.library.cdll.legsim_inverse_dynamics(
            self.handle, self._arr(lengths, na, "lengths"), self._arr(rates, na, "rates"),
            self._arr(accels, na, "accels"), self._abuf), "legsim_inverse_dynamics")
        return self._np(self._abuf, na)

    def inverse_dynamics_on_ground(self, lengths, rates, accels, follow=()):
        """Inverse dynamics with the stuck feet holding (docs/design/robot-on-ground.md
        section 8): ``follow`` names (or indexes) the actuators that are not driven (on both
        feet of the robot, one of the four); their lengths, rates and accelerations follow
        from the others and the feet (the values given for them are not read). The forces of
        every actuator and each foot's N and T (:meth:`contacts`) are fixed by the
        statics_rule on two stuck feet. Returns (forces, lengths, rates, accels), each
        (n_actuators,)."""
        na = self.n_actuators
        mask = 0
        for a in follow:
            mask |= 1 << self._actuator(a)
        bufs = [self._arr(v, na, w) for v, w in ((lengths, "lengths"), (rates, "rates"),
                                                 (accels, "accels"))]
        self._check(self.library.cdll.legsim_inverse_dynamics_on_ground(
            self.handle, mask, *bufs, self._abuf), "legsim_inverse_dynamics_on_ground")
        return (self._np(self._abuf, na),) + tuple(self._np(b, na) for b in bufs)

    def statics(self) -> np.ndarray:
        """Equilibrium actuator forces (N, n_actuators) in the current q under gravity and
        the force elements; :meth:`reactions` then holds the joints' reactions and
        :meth:`contacts` the ground forces of the feet that are not free (held as stuck;
        two of them by the option ``statics_rule``), with ``holds``."""
        self._check(self.library.cdll.legsim_statics(self.handle, self._abuf), "legsim_statics")
        return self._np(self._abuf, self.n_actuators)

    def statics_sweep(self, n_grid: int) -> WorstCase:
        """Worst-case statics over an n_grid x n_grid grid of the first two actuators'
        strokes; leaves the sim at the last assembled pose."""
        w = self.library.WorstCase()
        self._check(self.library.cdll.legsim_statics_sweep(self.handle, int(n_grid), C.byref(w)),
                    "legsim_statics_sweep")
        nj, na = self.n_joints, self.n_actuators
        return WorstCase(
            max_reaction_n=np.array(w.max_reaction_n[:nj], dtype=float),
            max_actuator_force_n=np.array(w.max_actuator_force_n[:na], dtype=float),
            at_length_m=np.array([row[:na] for row in w.at_length_m[:nj]], dtype=float),
            actuator_at_length_m=np.array([row[:na] for row in w.actuator_at_length_m[:na]],
                                          dtype=float),
            n_poses=int(w.n_poses), n_failed=int(w.n_failed))

    # ---- forward dynamics ----
    def step(self, n: int = 1) -> None:
        """Advances n fixed steps (one ``legsim_step`` call). Raises at the first failing
        step (the state is that of the last good one)."""
        self._check(self.library.cdll.legsim_step(self.handle, int(n)), "legsim_step")

    def run(self, duration: float) -> None:
        """Advances ``duration`` seconds: a whole number of steps, else ValueError."""
        n = duration / self.step_size
        if not math.isfinite(n) or n < 0 or abs(n - round(n)) > 1e-9 * max(1.0, n):
            raise ValueError(f"duration {duration!r} s is not a whole number of steps of "
                             f"{self.step_size!r} s")
        self.step(int(round(n)))

    # ---- foot contact (a robot model) ----
    def _contact(self, contact) -> int:
        if isinstance(contact, str):
            names = self.model.contact_names
            if contact not in names:
                raise ValueError(f"no contact {contact!r}; the model has {names}")
            return names.index(contact)
        return int(contact)

    def contacts(self) -> np.ndarray:
        """Per contact (n_contacts,) a record of CONTACT_DTYPE: ``state`` ("free", "stuck",
        "sliding"), ``normal`` N and ``tangential`` T (N: the ground's force on the foot
        is N n + T t, n the ground line's upward normal, t its tangent), ``friction_use``
        |T|/N, ``position`` (x, y) m, ``slip`` (m/s along t), ``impulse`` (N s)."""
        self._check(self.library.cdll.legsim_contacts(self.handle, self._ctbuf), "legsim_contacts")
        names = {v: k for k, v in CONTACT_STATES.items()}
        out = np.zeros(self.n_contacts, dtype=CONTACT_DTYPE)
        for k, c in enumerate(self._ctbuf[:self.n_contacts]):
            out[k] = (names.get(int(c.state), str(c.state)), c.normal_n, c.tangential_n,
                      c.friction_use, tuple(c.position), c.slip_mps, tuple(c.impulse_ns),
                      bool(c.holds))
        return out

    def set_contact(self, contact: Union[int, str], state: str) -> None:
        """Sets a contact (index or name, e.g. "right.foot") "stuck" at its foot's current
        point (on the ground line, else StateError), "sliding" (on the line and moving along
        it: the sign of its velocity is the sliding direction) or "free"."""
        if state not in CONTACT_STATES:
            raise ValueError(f"state must be one of {sorted(CONTACT_STATES)}, not {state!r}")
        self._check(self.library.cdll.legsim_set_contact_state(
            self.handle, self._contact(contact), CONTACT_STATES[state]), "legsim_set_contact_state")

    def assemble_on_ground(self, lengths=None, feet_mid: float = 0.0,
                           pose: Union[str, int, None] = "stand") -> np.ndarray:
        """The stance of a robot: both feet on the ground line, their midpoint at
        ``feet_mid`` (m along the line), the actuators at ``lengths`` (m; None: the
        lengths of ``pose``), the box pose following; qd = 0 and the contacts stuck.
        Starts from ``pose``'s guess (None: from the current q). Returns q.

        All or nothing: when it raises, the sim is as it was before the call (q, qd,
        time, contact states, commands, report)."""
        arr = None if lengths is None else self._arr(lengths, self.n_actuators, "lengths")
        feet_mid = float(feet_mid)
        index = None if pose is None else self.pose_index(pose)
        # Two C calls (the pose's assembly, then the stance): the sim's storage is copied
        # before and put back if either fails, so a refused call leaves no half-done pose.
        saved = self._save()
        try:
            if index is not None:
                self._check(self.library.cdll.legsim_assemble_pose(self.handle, index),
                            "legsim_assemble_pose")
            st = self.library.cdll.legsim_assemble_on_ground(self.handle, arr, feet_mid)
            if st == Status.ERR_BAD_INPUT:
                self._bad_input("legsim_assemble_on_ground",
                                ("feet_mid", feet_mid, -MAX_COORD, MAX_COORD, "m"))
            self._check(st, "legsim_assemble_on_ground")
        except BaseException:
            self._restore(saved)
            raise
        return self.q

    def _save(self) -> bytes:
        """The whole sim (its storage's bytes: the sim holds no pointer outside its storage
        and the model, which do not move)."""
        return C.string_at(self._addr, self.library.sim_size)

    def _restore(self, saved: bytes) -> None:
        C.memmove(self._addr, saved, len(saved))

    def _bad_input(self, function: str, *args) -> None:
        """Raises BadInputError naming the first argument outside its range: ``args`` are
        (name, value, low, high, unit), checked in order (NaN is outside every range).
        Returns when none is (the caller then raises the generic error)."""
        for name, value, lo, hi, unit in args:
            if not (lo <= value <= hi):
                raise BadInputError(Status.ERR_BAD_INPUT, function,
                                    f"{name} = {value:g} {unit} is outside its range "
                                    f"[{lo:g}, {hi:g}] {unit}")

    def box(self) -> np.ndarray:
        """(x m, y m, phi rad) of body 0 (a robot's box)."""
        return self.q[:3]

    # ---- commands ----
    def command_force(self, actuator: Union[int, str], force_n: float) -> None:
        """Applies an axial force (N, > 0 extends) with an actuator (index or name);
        |force| <= its max force (``model.max_forces``), else BadInputError naming the
        actuator, the force and the range."""
        a, force_n = self._actuator(actuator), float(force_n)
        st = self.library.cdll.legsim_command_force(self.handle, a, force_n)
        if st == Status.ERR_BAD_INPUT and 0 <= a < self.n_actuators:
            fmax = float(self.model.max_forces[a])
            self._bad_input("legsim_command_force",
                            (f"force_n of actuator {self.model.actuator_names[a]!r}", force_n,
                             -fmax, fmax, "N"))
        self._check(st, "legsim_command_force")

    def command_length(self, actuator: Union[int, str], length_m: float) -> None:
        """Makes an actuator's servo hold a length (m) inside its stroke (else
        OutOfStrokeError)."""
        self._check(self.library.cdll.legsim_command_length(
            self.handle, self._actuator(actuator), float(length_m)), "legsim_command_length")

    def set_force(self, force: Union[int, str], value) -> None:
        """Sets a force element's value: a point force (Fx, Fy) in N (world), or a torque
        in N m. ``force`` is its index or name."""
        if isinstance(force, str):
            names = self.model.force_names
            if force not in names:
                raise ValueError(f"no force element {force!r}; the model has {names}")
            force = names.index(force)
        v = np.atleast_1d(np.asarray(value, dtype=float)).reshape(-1)
        if v.size not in (1, 2):
            raise ValueError(f"a force value has 1 (torque) or 2 (point force) entries, "
                             f"not {v.size}")
        arr = (self._real * 2)(*(v.tolist() + [0.0] * (2 - v.size)))
        st = self.library.cdll.legsim_set_force(self.handle, int(force), arr)
        if st == Status.ERR_BAD_INPUT:
            self._bad_input("legsim_set_force",
                            *((f"value[{i}]", float(x), -MAX_FORCE_N, MAX_FORCE_N, "N or N m")
                              for i, x in enumerate(v)))
        self._check(st, "legsim_set_force")
