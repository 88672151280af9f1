"""Independent reference model of the leg: minimal coordinates + Newton-Euler.

The core (firmware_core, legsim.h) works in absolute coordinates with Lagrange
multipliers.  This model is written from the other end:

* Generalized coordinates ``theta`` (minimal):

  - ``variant="revolute"`` (default, 2 dof): ``theta = (phi3, phi6)``, the
    absolute angles of the thigh and the shank (leg.toml's convention,
    u(phi) = (sin phi, -cos phi), n(phi) = (cos phi, sin phi)).
  - ``variant="slot"`` (3 dof): ``theta = (phi3, phi6, s)`` where ``s`` (m) is
    the distance along the shank axis from the shank's proximal end C to the
    point D where the lower rod's distal end rides (D = C + s u(phi6), so
    s = xi + L6/2 in the shank's body coordinates).  Chosen over the lower
    actuator length because it keeps every pose in closed form and is regular
    everywhere (the actuator length would need a circle/line intersection
    with branches).  The stand pose uses s = 0.20, the pin position of the
    revolute variant.

* Closed-form poses.  C = B + L3 u(phi3); shank proximal end at C; D on the
  shank; each actuator is the line from its frame pivot P to its moving end Q
  (A->C, B->D): cylinder centre P + L/2 e, rod centre Q - L/2 e, both with the
  angle of the line, u(phi) = e = (Q-P)/|Q-P|; length |Q-P|.

* Velocities and accelerations are exact hand derivatives ("jets"): every
  point carries its position p, its Jacobian V = dp/dtheta and its bias
  b = (dV/dt) theta_dot, so p_ddot = V theta_ddot + b.  No finite differences.

* Reduced dynamics: M(theta) = sum J_i^T diag(m, m, J) J_i,
  M theta_ddot = Q_gravity + Q_foot + sum_a F_a dl_a/dtheta - sum J_i^T M_i b_i
  (actuator forces by virtual work), integrated with scipy's DOP853.

* Joint reactions by Newton-Euler on the six bodies (18 equations), the joint
  forces as unknowns: revolute -> a 2D force at the joint point; prismatic ->
  a force normal to the cylinder axis plus a couple (the actuator's axial
  force is an external force: -F u on the cylinder, +F u on the rod); slot ->
  a force normal to the shank axis at the rod's end.  The force elements
  (gravity, foot load) are external.  Reported per joint in leg.toml's order:
  (Fx, Fy, M), the force the joint applies to its FIRST-LISTED body in world
  axes and the moment about that body's centre of mass (revolute_to_frame: the
  moving body), i.e. the same quantity as legsim_reactions().  This part is
  generic over the joints of leg.toml and uses only the absolute poses and
  accelerations.

Not modelled: stroke stops (Result.out_of_stroke tells when a run left the
stroke), the sampled nature of a discrete controller (the servo is continuous).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np
from scipy.integrate import solve_ivp

from . import commands as _cmd
from .commands import ForceCommand, LengthCommand
from .model_file import read_model_file

__all__ = ["LegModel", "Result", "InverseDynamics", "WorstCase",
           "ReferenceError", "UnreachableError", "NoEquilibriumError", "u", "n"]


class ReferenceError(RuntimeError):
    """Base class of the reference model's errors."""


class UnreachableError(ReferenceError, ValueError):
    """The actuator lengths cannot be met by any pose."""


class NoEquilibriumError(ReferenceError):
    """Statics: the loads cannot be balanced (the mechanism is free)."""


def u(phi: float) -> np.ndarray:
    """Body axis u(phi) = (sin phi, -cos phi) (phi = 0: hanging down)."""
    return np.array([math.sin(phi), -math.cos(phi)])


def n(phi: float) -> np.ndarray:
    """Body normal n(phi) = (cos phi, sin phi) = du/dphi."""
    return np.array([math.cos(phi), math.sin(phi)])


def _cross(a, b) -> float:
    return a[0] * b[1] - a[1] * b[0]


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


# --------------------------------------------------------------------------
# Newton-Euler columns of the joint reactions (shared by the leg and the robot)
# --------------------------------------------------------------------------
def body_point(length: float, end: str, spec: dict):
    """The body-fixed point (xi, eta) (m) a model file names on a body of this length: its
    proximal or distal end, its centre, `at = [xi, eta]`, or None for its axis (a slot)."""
    if end == "proximal":
        return (-length / 2.0, 0.0)
    if end == "distal":
        return (length / 2.0, 0.0)
    if end == "center":
        return (0.0, 0.0)
    if end == "at":
        return tuple(map(float, spec["at"]))
    if end == "axis":
        return None
    raise ValueError(f"unknown end {end!r}")


def world_point(q, bi, pt) -> np.ndarray:
    """World position (m) of the body-fixed point pt = (xi, eta) of body bi; q (nb, 3)."""
    x, y, ph = q[bi]
    return np.array([x, y]) + pt[0] * u(ph) + pt[1] * n(ph)


def add_force(A, q, bi, col, F, p) -> None:
    """Add to column col of the free-body equations A (3 rows a body) a unit-scaled
    force F (per unknown) on body bi at world point p: force rows and the moment
    about the body's centre of mass."""
    A[3 * bi, col] += F[0]
    A[3 * bi + 1, col] += F[1]
    A[3 * bi + 2, col] += _cross(p - q[bi, :2], F)


def reaction_offsets(joints) -> np.ndarray:
    """Column offsets of each joint's reaction unknowns (len(joints) + 1): two per
    joint (a force, or for a prismatic joint a normal force and a couple), one
    per slot (the normal force); the last entry is the number of columns."""
    ncol = [1 if j.kind == "slot" else 2 for j in joints]
    return np.concatenate([[0], np.cumsum(ncol)]).astype(int)


def add_reaction_columns(A, q, joints, off) -> None:
    """Fill the joint-reaction columns of the free-body equations A (3 nb rows).

    Unknowns per joint (the action on its first-listed body bi; bj gets the
    opposite): revolute (to frame): (Fx, Fy) at the joint point; prismatic:
    f (force f n on bi) and M (couple on bi); slot: f (force f n(bj) at the
    point of bi).  q: absolute poses (nb, 3).
    """
    ex, ey = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    for k, j in enumerate(joints):
        c = off[k]
        bi = j.bodies[0]
        if j.kind in ("revolute_to_frame", "revolute"):
            p = world_point(q, bi, j.points[0])
            add_force(A, q, bi, c, ex, p)
            add_force(A, q, bi, c + 1, ey, p)
            if j.kind == "revolute":
                bj = j.bodies[1]
                add_force(A, q, bj, c, -ex, p)
                add_force(A, q, bj, c + 1, -ey, p)
        elif j.kind == "prismatic":
            bj = j.bodies[1]
            uu, nn = u(q[bi, 2]), n(q[bi, 2])
            A[3 * bi:3 * bi + 2, c] += nn
            A[3 * bi + 2, c + 1] += 1.0
            A[3 * bj:3 * bj + 2, c] -= nn
            A[3 * bj + 2, c] += float(uu @ (q[bj, :2] - q[bi, :2]))
            A[3 * bj + 2, c + 1] -= 1.0
        elif j.kind == "slot":
            bj = j.bodies[1]
            p = world_point(q, bi, j.points[0])
            nn = n(q[bj, 2])
            add_force(A, q, bi, c, nn, p)
            add_force(A, q, bj, c, -nn, p)
        else:
            raise ValueError(f"joint {j.name!r}: unknown kind {j.kind!r}")


def command_breakpoints(cmds) -> set:
    """The times (s) where a command's schedule has a step or a kink."""
    bps = set()
    for c in cmds:
        if isinstance(c, ForceCommand):
            bps.update(_cmd.breakpoints(c.force))
        elif isinstance(c, LengthCommand):
            bps.update(_cmd.breakpoints(c.length))
    return bps


def command_forces(cmds, t, l, ld, kp, kd, fmax):
    """Actuator forces (N) of the commands at time t (s) and which servos saturate.

    Per actuator: None -> 0; ForceCommand -> its force; LengthCommand -> the servo
    kp (l_cmd - l) - kd ld clipped to +-fmax (l, ld: the lengths (m) and rates
    (m/s) now).  Returns (F, saturated) arrays.
    """
    F = np.zeros(len(cmds))
    sat = np.zeros(len(cmds), dtype=bool)
    for i, c in enumerate(cmds):
        if c is None:
            continue
        if isinstance(c, ForceCommand):
            F[i] = _cmd.evaluate(c.force, t)
        elif isinstance(c, LengthCommand):
            raw = kp[i] * (_cmd.evaluate(c.length, t) - l[i]) - kd[i] * ld[i]
            sat[i] = abs(raw) > fmax[i]
            F[i] = min(max(raw, -fmax[i]), fmax[i])
        else:
            raise TypeError("actuator commands are ForceCommand, LengthCommand or None")
    return F, sat


def integrate_piecewise(make_rhs, edges, y0, t_eval=None, **options):
    """Integrate y' = f(t, y) with scipy's solve_ivp one piece [ta, tb] of ``edges``
    (s, increasing) at a time, f = make_rhs(ta, tb), so that no step crosses a
    command's discontinuity.  Returns (T, Y): every step point (``t_eval`` None),
    else the times of ``t_eval`` (the last piece includes its end), taken from the
    dense output except where a step ends on one (more accurate than the
    interpolant).  ``options`` go to solve_ivp (method, rtol, atol, max_step).
    """
    y = np.asarray(y0, float)
    te = None if t_eval is None else np.asarray(t_eval, float)
    T, Y = [], []
    for k in range(len(edges) - 1):
        ta, tb = edges[k], edges[k + 1]
        last = k == len(edges) - 2
        pts = None if te is None else te[(te >= ta) & ((te < tb) | (last & (te <= tb)))]
        sol = solve_ivp(make_rhs(ta, tb), (ta, tb), y,
                        dense_output=pts is not None and len(pts) > 0, **options)
        if sol.status != 0:
            raise ReferenceError(f"integration failed: {sol.message}")
        if pts is None:
            ts = sol.t if k == 0 else sol.t[1:]
            T.extend(ts)
            Y.extend(sol.y.T[-len(ts):])
        elif len(pts):
            ys = sol.sol(pts).T
            for i, tp in enumerate(pts):
                hit = np.nonzero(sol.t == tp)[0]
                if hit.size:
                    ys[i] = sol.y[:, hit[0]]
            T.extend(pts)
            Y.extend(ys)
        y = sol.y[:, -1]
    return np.array(T), np.array(Y)


def reactions_from_unknowns(q, joints, x, off) -> np.ndarray:
    """Joint reactions (n_joints, 3) = (Fx (N), Fy (N), M (N m)) on each joint's
    first-listed body, moment about its centre of mass, from the solved unknowns
    x laid out as :func:`add_reaction_columns`."""
    R = np.zeros((len(joints), 3))
    for k, j in enumerate(joints):
        c = off[k]
        bi = j.bodies[0]
        if j.kind == "prismatic":
            F = x[c] * n(q[bi, 2])
            R[k] = (F[0], F[1], x[c + 1])
            continue
        F = x[c:c + 2] if j.kind != "slot" else x[c] * n(q[j.bodies[1], 2])
        p = world_point(q, bi, j.points[0])
        R[k] = (F[0], F[1], _cross(p - q[bi, :2], F))
    return R


# --------------------------------------------------------------------------
# model description
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class _Body:
    id: int
    name: str
    length: float
    mass: float
    inertia: float


@dataclass(frozen=True)
class _Joint:
    name: str
    kind: str                 # revolute_to_frame | revolute | prismatic | slot
    bodies: tuple             # body indices (0-based); frame joints: (i,)
    points: tuple             # body-fixed (xi, eta) per body (None for prismatic/axis)
    frame_point: Optional[tuple] = None   # world point for revolute_to_frame


@dataclass(frozen=True)
class _Actuator:
    name: str
    joint: str
    cylinder: int
    rod: int
    stroke: tuple
    max_force: float
    kp: float
    kd: float


class _Jets:
    """Poses, Jacobians and bias accelerations of everything at one state."""
    __slots__ = ("P", "J", "b", "l", "lg", "lb", "ld", "foot", "load")


# --------------------------------------------------------------------------
# jet helpers: a point is (p, V, b); an angle is (phi, g, beta, w)
#   p_dot = V theta_dot, p_ddot = V theta_ddot + b
#   phi_dot = w = g . theta_dot, phi_ddot = g . theta_ddot + beta
# --------------------------------------------------------------------------
def _offset(O, ang, a, c):
    """Point O + a u(phi) + c n(phi) of a body with angle jet ``ang``."""
    op, oV, ob = O
    phi, g, beta, w = ang
    sn, cs = math.sin(phi), math.cos(phi)
    s = np.array([a * sn + c * cs, -a * cs + c * sn])      # a u + c n
    t = np.array([a * cs - c * sn, a * sn + c * cs])       # d/dphi = a n - c u
    return (op + s, oV + np.outer(t, g), ob + t * beta - s * (w * w))


def _line(P, Q, thd):
    """Angle and length jets of the line from fixed point P to point jet Q."""
    qp, qV, qb = Q
    d0, d1 = qp[0] - P[0], qp[1] - P[1]
    l = math.hypot(d0, d1)
    e = np.array([d0 / l, d1 / l])
    nv = np.array([-e[1], e[0]])
    Qd = qV @ thd
    ld = float(e @ Qd)
    w = float(nv @ Qd) / l
    phi = math.atan2(e[0], -e[1])
    g = (nv @ qV) / l
    beta = (float(nv @ qb) - 2.0 * ld * w) / l
    lg = e @ qV
    lb = float(e @ qb) + l * w * w
    return (phi, g, beta, w), (l, lg, lb, ld)


class LegModel:
    """Minimal-coordinate reference model of leg.toml (see the module doc).

    Construct with :meth:`from_toml`.  ``theta`` has ``self.ndof`` entries
    (revolute: phi3, phi6; slot: phi3, phi6, s).  Absolute vectors ``q`` are
    (x, y, phi) per body in leg.toml's body order (18 values).  Lengths and
    actuator forces are in leg.toml's actuator order.
    """

    # ---------------------------------------------------------------- build
    @classmethod
    def from_toml(cls, path, variant: str = "revolute") -> "LegModel":
        return cls(read_model_file(path), variant)

    def __init__(self, data: dict, variant: str = "revolute"):
        if variant not in ("revolute", "slot"):
            raise ValueError(f"unknown variant {variant!r}")
        self.variant = variant
        self.name = data.get("name", "")
        self.gravity = np.array(data.get("gravity", [0.0, -9.81]), dtype=float)
        frame = {k: tuple(map(float, v)) for k, v in data.get("frame", {}).items()}

        self.bodies = []
        id2i = {}
        for i, b in enumerate(data["body"]):
            L, m = float(b["length"]), float(b["mass"])
            J = float(b.get("inertia", m * L * L / 12.0))
            self.bodies.append(_Body(int(b["id"]), b.get("name", str(b["id"])), L, m, J))
            id2i[int(b["id"])] = i
        self.nb = len(self.bodies)
        self.body_names = [b.name for b in self.bodies]

        def end_point(bi, end, spec):
            return body_point(self.bodies[bi].length, end, spec)

        variants = data.get("variant", {})
        vspec = variants.get(variant, {}) if variant != "revolute" else {}
        self.joints = []
        self._pin_point_D = None
        for jd in data["joint"]:
            spec = dict(jd)
            if spec["name"] in vspec:
                spec = dict(vspec[spec["name"]], name=spec["name"])
            kind = spec["kind"]
            if kind == "revolute_to_frame":
                bi = id2i[int(spec["body"])]
                pt = end_point(bi, spec["end"], spec)
                fp = spec["point"]
                fp = frame[fp] if isinstance(fp, str) else tuple(map(float, fp))
                self.joints.append(_Joint(spec["name"], kind, (bi,), (pt,), fp))
            elif kind in ("revolute", "slot"):
                bis = tuple(id2i[int(x)] for x in spec["bodies"])
                pts = tuple(end_point(bi, e, spec) for bi, e in zip(bis, spec["ends"]))
                self.joints.append(_Joint(spec["name"], kind, bis, pts))
            elif kind == "prismatic":
                bis = tuple(id2i[int(x)] for x in spec["bodies"])
                self.joints.append(_Joint(spec["name"], kind, bis, (None, None)))
            else:
                raise ValueError(f"joint {spec['name']}: unknown kind {kind!r}")
        self.joint_names = [j.name for j in self.joints]
        self.nj = len(self.joints)
        jbyname = {j.name: j for j in self.joints}

        self.actuators = []
        for a in data.get("actuator", []):
            j = jbyname[a["joint"]]
            if j.kind != "prismatic":
                raise ValueError(f"actuator {a['name']}: joint is not prismatic")
            self.actuators.append(_Actuator(
                a["name"], a["joint"], j.bodies[0], j.bodies[1],
                tuple(map(float, a["stroke"])), float(a["max_force"]),
                float(a["servo_kp"]), float(a["servo_kd"])))
        self.na = len(self.actuators)
        self.actuator_names = [a.name for a in self.actuators]

        self._discover_topology(data, id2i)

        # mass matrix diagonal per body and masses
        self._m = np.array([b.mass for b in self.bodies])
        self._Md = np.array([[b.mass, b.mass, b.inertia] for b in self.bodies])

        # stand pose
        stand = data.get("pose", {}).get("stand", {})
        drv = {}
        for k, v in stand.items():
            if k.startswith("phi") and k[3:].isdigit():
                drv[id2i[int(k[3:])]] = float(v)
        if set(drv) != {self._thigh, self._shank}:
            raise ValueError("pose.stand must drive exactly the thigh and shank angles")
        th = [drv[self._thigh], drv[self._shank]]
        if self.variant == "slot":
            th.append(self._s_stand)
        self._stand = np.array(th)
        self.ndof = len(th)
        # assembly modes (branch signs) of the closed-form position problem
        self._mode = self._modes(self._stand)
        self._foot_mode = None   # theta_from_foot's branch at the stand, on first use

    def _discover_topology(self, data, id2i):
        """Map leg.toml onto the roles the closed-form kinematics needs."""
        frame_of = {}
        for j in self.joints:
            if j.kind == "revolute_to_frame":
                frame_of[j.bodies[0]] = j
        if self.na != 2:
            raise ValueError("the reference model needs exactly two actuators")
        cyls = {a.cylinder for a in self.actuators}
        for a in self.actuators:
            fj = frame_of.get(a.cylinder)
            if fj is None or fj.points[0] != (-self.bodies[a.cylinder].length / 2, 0.0):
                raise ValueError(f"actuator {a.name}: cylinder must be pinned to the frame at its proximal end")
        thighs = [b for b in frame_of if b not in cyls]
        if len(thighs) != 1:
            raise ValueError("expected exactly one non-actuator body pinned to the frame (the thigh)")
        th = thighs[0]
        if frame_of[th].points[0] != (-self.bodies[th].length / 2, 0.0):
            raise ValueError("the thigh must be pinned at its proximal end")
        Lth = self.bodies[th].length

        revs = [j for j in self.joints if j.kind == "revolute"]
        upper = None
        for a in self.actuators:
            for j in revs:
                if set(j.bodies) == {a.rod, th}:
                    upper = a
        if upper is None:
            raise ValueError("no actuator rod is pinned to the thigh")
        lower = [a for a in self.actuators if a is not upper][0]
        # the joints at C join {upper rod distal, thigh distal, shank proximal}
        c_joints = [j for j in revs if upper.rod in j.bodies or th in j.bodies]
        c_joints = [j for j in c_joints if lower.rod not in j.bodies]
        others = {b for j in c_joints for b in j.bodies} - {upper.rod, th}
        if len(others) != 1 or len(c_joints) != 2:
            raise ValueError("expected the rod, thigh and shank to meet at C through two revolute joints")
        sh = others.pop()
        Lsh = self.bodies[sh].length
        Cends = {upper.rod: (self.bodies[upper.rod].length / 2, 0.0),
                 th: (Lth / 2, 0.0), sh: (-Lsh / 2, 0.0)}
        for j in c_joints:
            for bi, pt in zip(j.bodies, j.points):
                if Cends[bi] != pt:
                    raise ValueError(f"joint {j.name}: not at C (rod distal, thigh distal, shank proximal)")
        dj = [j for j in self.joints if j.kind in ("revolute", "slot") and set(j.bodies) == {lower.rod, sh}]
        if len(dj) != 1:
            raise ValueError("expected one joint between the lower rod and the shank")
        dj = dj[0]
        # the pin point of the default (revolute) variant
        base = [jd for jd in data["joint"] if jd["name"] == dj.name][0]
        if base["kind"] != "revolute" or "at" not in base:
            raise ValueError("joint D of the default variant must be a revolute with an 'at' point")
        at = tuple(map(float, base["at"]))
        if self.variant == "revolute":
            if dj.kind != "revolute":
                raise ValueError("revolute variant: joint D must be revolute")
            ri = dj.bodies.index(lower.rod)
            if dj.points[ri] != (self.bodies[lower.rod].length / 2, 0.0):
                raise ValueError("joint D: the lower rod must be pinned at its distal end")
            self._D_at = dj.points[1 - ri]       # (xi, eta) on the shank
        else:
            if dj.kind != "slot" or dj.bodies[0] != lower.rod or dj.points[1] is not None:
                raise ValueError("slot variant: D must be the lower rod's distal end on the shank axis")
            if dj.points[0] != (self.bodies[lower.rod].length / 2, 0.0):
                raise ValueError("slot variant: the lower rod's distal end must ride in the slot")
            self._D_at = None
        if at[1] != 0.0 and self.variant == "slot":
            raise ValueError("slot stand pose needs the pin on the shank axis")
        self._s_stand = at[0] + Lsh / 2.0
        self._thigh, self._shank = th, sh
        self._upper, self._lower = upper, lower
        self._iu = self.actuators.index(upper)
        self._il = self.actuators.index(lower)
        self._A = np.array(frame_of[upper.cylinder].frame_point)
        self._B = np.array(frame_of[th].frame_point)
        self._P_low = np.array(frame_of[lower.cylinder].frame_point)
        # foot and the foot-load force element
        foot = data.get("foot", {})
        if id2i[int(foot["body"])] != sh:
            raise ValueError("the foot must be on the shank")
        self._foot_pt = self._end(sh, foot["end"], foot)
        loads = [f for f in data.get("force", []) if f.get("kind") == "point"]
        others = [f for f in data.get("force", []) if f.get("kind") != "point"]
        if others or len(loads) > 1:
            raise ValueError("the reference model supports one point force element (the foot load)")
        if loads:
            f = loads[0]
            if id2i[int(f["body"])] != sh:
                raise ValueError("the foot load must act on the shank")
            self._load_pt = self._end(sh, f["end"], f)
            self._load_default = np.array(f.get("value", [0.0, 0.0]), dtype=float)
            self.load_name = f.get("name", "foot_load")
        else:
            self._load_pt = self._foot_pt
            self._load_default = np.zeros(2)
            self.load_name = None

    def _end(self, bi, end, spec):
        return body_point(self.bodies[bi].length, end, spec)

    # --------------------------------------------------------- kinematics
    def _jets(self, th, thd) -> _Jets:
        nd = self.ndof
        E = np.eye(nd)
        zero2 = np.zeros(2)
        Bf = (self._B, np.zeros((2, nd)), zero2)
        a3 = (th[0], E[0], 0.0, thd[0])
        a6 = (th[1], E[1], 0.0, thd[1])
        b3, b6 = self.bodies[self._thigh], self.bodies[self._shank]
        C = _offset(Bf, a3, b3.length, 0.0)
        r3 = _offset(Bf, a3, b3.length / 2, 0.0)
        r6 = _offset(C, a6, b6.length / 2, 0.0)
        if self.variant == "revolute":
            xi, eta = self._D_at
            D = _offset(C, a6, b6.length / 2 + xi, eta)
        else:
            s, sd = th[2], thd[2]
            u6, n6 = u(th[1]), n(th[1])
            w6 = thd[1]
            D = (C[0] + s * u6, C[1] + np.outer(s * n6, E[1]) + np.outer(u6, E[2]),
                 C[2] + 2.0 * sd * w6 * n6 - s * w6 * w6 * u6)
        fx, fe = self._foot_pt
        foot = _offset(C, a6, b6.length / 2 + fx, fe)
        if self._load_pt == self._foot_pt:
            load = foot
        else:
            lx, le = self._load_pt
            load = _offset(C, a6, b6.length / 2 + lx, le)

        up, lo = self._upper, self._lower
        aU, lU = _line(self._A, C, thd)
        aL, lL = _line(self._P_low, D, thd)
        Af = (self._A, np.zeros((2, nd)), zero2)
        Pf = (self._P_low, np.zeros((2, nd)), zero2)
        r1 = _offset(Af, aU, self.bodies[up.cylinder].length / 2, 0.0)
        r2 = _offset(C, aU, -self.bodies[up.rod].length / 2, 0.0)
        r4 = _offset(Pf, aL, self.bodies[lo.cylinder].length / 2, 0.0)
        r5 = _offset(D, aL, -self.bodies[lo.rod].length / 2, 0.0)

        K = _Jets()
        P = np.empty((self.nb, 3))
        J = np.empty((self.nb, 3, nd))
        b = np.empty((self.nb, 3))
        for bi, pt, ang in ((up.cylinder, r1, aU), (up.rod, r2, aU), (self._thigh, r3, a3),
                            (lo.cylinder, r4, aL), (lo.rod, r5, aL), (self._shank, r6, a6)):
            P[bi, :2] = pt[0]
            P[bi, 2] = ang[0]
            J[bi, :2] = pt[1]
            J[bi, 2] = ang[1]
            b[bi, :2] = pt[2]
            b[bi, 2] = ang[2]
        K.P, K.J, K.b = P, J, b
        l = np.empty(2)
        lg = np.empty((2, nd))
        lb = np.empty(2)
        ld = np.empty(2)
        for i, lj in ((self._iu, lU), (self._il, lL)):
            l[i], lg[i], lb[i], ld[i] = lj
        K.l, K.lg, K.lb, K.ld = l, lg, lb, ld
        K.foot, K.load = foot, load
        return K

    def stand_theta(self) -> np.ndarray:
        """theta of leg.toml's stand pose (slot variant: s = pin position, 0.20 m)."""
        return self._stand.copy()

    def absolute_q(self, theta) -> np.ndarray:
        """Absolute coordinates (x, y, phi per body, leg.toml order): (18,) or (N, 18)."""
        th = np.asarray(theta, dtype=float)
        if th.ndim == 2:
            return np.array([self.absolute_q(t) for t in th])
        return self._jets(th, np.zeros(self.ndof)).P.reshape(-1)

    def absolute_qd(self, theta, thetad) -> np.ndarray:
        """Absolute velocities q_dot = J(theta) theta_dot (18,)."""
        K = self._jets(np.asarray(theta, float), np.asarray(thetad, float))
        return (K.J @ np.asarray(thetad, float)).reshape(-1)

    def jacobian(self, theta) -> np.ndarray:
        """dq/dtheta, shape (18, ndof)."""
        K = self._jets(np.asarray(theta, float), np.zeros(self.ndof))
        return K.J.reshape(-1, self.ndof)

    def foot(self, theta) -> np.ndarray:
        """Foot point (world, m): (2,) or (N, 2)."""
        th = np.asarray(theta, dtype=float)
        if th.ndim == 2:
            return np.array([self.foot(t) for t in th])
        return self._jets(th, np.zeros(self.ndof)).foot[0].copy()

    def lengths(self, theta) -> np.ndarray:
        """Actuator lengths (cylinder proximal end to rod distal end, m): (2,) or (N, 2)."""
        th = np.asarray(theta, dtype=float)
        if th.ndim == 2:
            return np.array([self.lengths(t) for t in th])
        return self._jets(th, np.zeros(self.ndof)).l

    def length_jacobian(self, theta) -> np.ndarray:
        """dl/dtheta, shape (2, ndof)."""
        return self._jets(np.asarray(theta, float), np.zeros(self.ndof)).lg

    def _phi3_roots(self, l_up):
        """phi3 = psi +- acos(c): |C - A| = l_up with C = B + L3 u(phi3)."""
        L3 = self.bodies[self._thigh].length
        a = self._A - self._B
        ra = math.hypot(*a)
        c = (L3 ** 2 + ra ** 2 - l_up ** 2) / (2.0 * L3 * ra)
        if not abs(c) <= 1.0:
            raise UnreachableError(f"upper length {l_up} cannot be met")
        return math.atan2(a[0], -a[1]), math.acos(c)

    def _phi6_roots(self, phi3, l_lo, s=None):
        b3, b6 = self.bodies[self._thigh], self.bodies[self._shank]
        C = self._B + b3.length * u(phi3)
        if self.variant == "revolute":
            xi, eta = self._D_at
            d, e = b6.length / 2 + xi, eta
        else:
            d, e = float(s), 0.0
        rho = math.hypot(d, e)
        delta = math.atan2(e, d)
        cv = C - self._P_low
        rc = math.hypot(*cv)
        c = (l_lo ** 2 - rc ** 2 - rho ** 2) / (2.0 * rho * rc)
        if not abs(c) <= 1.0:
            raise UnreachableError(f"lower length {l_lo} cannot be met")
        psi_c = math.atan2(cv[0], -cv[1])
        return psi_c - delta, math.acos(c)

    def _modes(self, th):
        l = self.lengths(th)
        psi, _ = self._phi3_roots(l[self._iu])
        base, _ = self._phi6_roots(th[0], l[self._il], th[2] if self.variant == "slot" else None)
        return (1.0 if _wrap(th[0] - psi) >= 0 else -1.0,
                1.0 if _wrap(th[1] - base) >= 0 else -1.0)

    def theta_from_lengths(self, lengths, near=None, s=None) -> np.ndarray:
        """Closed-form position problem: theta from the two actuator lengths.

        Branch: ``near=None`` keeps the assembly mode of the stand pose (the
        sign of each acos root); otherwise the root nearest ``near`` (angles
        unwrapped to lie within pi of ``near``).  Slot variant: ``s`` (m, the
        slot position) is a coordinate of its own; default the stand's.
        Accepts (2,) or (N, 2) (then each row continues from the previous).
        """
        L = np.asarray(lengths, dtype=float)
        if L.ndim == 2:
            out, prev = [], near
            for row in L:
                prev = self.theta_from_lengths(row, near=prev, s=s)
                out.append(prev)
            return np.array(out)
        l_up, l_lo = L[self._iu], L[self._il]
        if self.variant == "slot" and s is None:
            s = float(near[2]) if near is not None else self._s_stand
        psi, ac = self._phi3_roots(l_up)
        if near is None:
            phi3 = psi + self._mode[0] * ac
            phi3 = self._stand[0] + _wrap(phi3 - self._stand[0])
        else:
            c3 = [psi + ac, psi - ac]
            phi3 = min((near[0] + _wrap(x - near[0]) for x in c3), key=lambda x: abs(x - near[0]))
        base, ac6 = self._phi6_roots(phi3, l_lo, s)
        if near is None:
            phi6 = base + self._mode[1] * ac6
            phi6 = self._stand[1] + _wrap(phi6 - self._stand[1])
        else:
            c6 = [base + ac6, base - ac6]
            phi6 = min((near[1] + _wrap(x - near[1]) for x in c6), key=lambda x: abs(x - near[1]))
        th = [phi3, phi6] + ([s] if self.variant == "slot" else [])
        return np.array(th)

    def theta_from_foot(self, foot, near=None) -> np.ndarray:
        """Closed-form inverse kinematics of the foot (revolute variant): theta = (phi3, phi6)
        that put the foot at ``foot`` (m, the leg's frame). The thigh B-C and the line from C
        to the foot make a triangle with |foot - B|: phi3 = angle of (foot - B) +- its angle at B.
        Branch: ``near=None`` the stand pose's, else the root nearest ``near``."""
        if self.variant != "revolute":
            raise ReferenceError("theta_from_foot needs the revolute variant (2 dof)")
        L3 = self.bodies[self._thigh].length
        d = self.bodies[self._shank].length / 2.0 + self._foot_pt[0]
        e = self._foot_pt[1]
        rho, delta = math.hypot(d, e), math.atan2(e, d)   # foot - C = rho u(phi6 + delta)
        r = np.asarray(foot, float) - self._B
        R = math.hypot(*r)
        c = (L3 * L3 + R * R - rho * rho) / (2.0 * L3 * R)
        if not abs(c) <= 1.0:
            raise UnreachableError(f"foot {tuple(foot)} cannot be reached")
        psi, ac = math.atan2(r[0], -r[1]), math.acos(c)
        ref = self._stand if near is None else np.asarray(near, float)
        if near is None:
            if self._foot_mode is None:
                p0 = self.foot(self._stand) - self._B
                psi0 = math.atan2(p0[0], -p0[1])
                self._foot_mode = 1.0 if _wrap(self._stand[0] - psi0) >= 0 else -1.0
            phi3 = psi + self._foot_mode * ac
        else:
            phi3 = min((psi + ac, psi - ac), key=lambda x: abs(_wrap(x - ref[0])))
        phi3 = ref[0] + _wrap(phi3 - ref[0])
        w = np.asarray(foot, float) - (self._B + L3 * u(phi3))
        phi6 = math.atan2(w[0], -w[1]) - delta
        phi6 = ref[1] + _wrap(phi6 - ref[1])
        return np.array([phi3, phi6])

    # ------------------------------------------------------------ dynamics
    def _gravity(self, gravity):
        if gravity is True:
            return self.gravity.copy()
        if gravity is False or gravity is None:
            return np.zeros(2)
        return np.asarray(gravity, dtype=float)

    def mass_matrix(self, theta) -> np.ndarray:
        """Reduced mass matrix M(theta) = sum J_i^T M_i J_i."""
        K = self._jets(np.asarray(theta, float), np.zeros(self.ndof))
        return np.einsum("bki,bk,bkj->ij", K.J, self._Md, K.J)

    def _reduced(self, K, g, load, F):
        """M, and the right-hand side Q - h for known actuator forces F."""
        JM = K.J * self._Md[:, :, None]
        M = np.einsum("bki,bkj->ij", JM, K.J)
        h = np.einsum("bki,bk->i", JM, K.b)
        Q = np.einsum("bki,bk->i", K.J[:, :2, :], self._m[:, None] * g[None, :])
        Q = Q + K.load[1].T @ load + K.lg.T @ F
        return M, Q - h

    def _forces(self, cmds, t, K, clip_t=None):
        a = self.actuators
        return command_forces(cmds, t if clip_t is None else clip_t(t), K.l, K.ld,
                              [x.kp for x in a], [x.kd for x in a], [x.max_force for x in a])

    def _load(self, foot_load, t):
        if foot_load is None:
            return self._load_default.copy()
        return np.array([_cmd.evaluate(foot_load[0], t), _cmd.evaluate(foot_load[1], t)])

    def accelerations(self, theta, thetad, actuator_forces=(0.0, 0.0), foot_load=(0.0, 0.0),
                      gravity=True) -> np.ndarray:
        """theta_ddot for given state and axial actuator forces (forward dynamics)."""
        K = self._jets(np.asarray(theta, float), np.asarray(thetad, float))
        M, r = self._reduced(K, self._gravity(gravity), np.asarray(foot_load, float),
                             np.asarray(actuator_forces, float))
        return np.linalg.solve(M, r)

    def energy(self, theta, thetad, gravity=True, foot_load=(0.0, 0.0), actuator_forces=(0.0, 0.0)):
        """(kinetic, potential): potential of gravity, of a constant foot load
        (-F . foot) and of constant axial actuator forces (-F l)."""
        th, thd = np.asarray(theta, float), np.asarray(thetad, float)
        K = self._jets(th, thd)
        v = K.J @ thd
        T = 0.5 * float(np.sum(self._Md * v * v))
        g = self._gravity(gravity)
        V = -float(np.sum(self._m * (K.P[:, :2] @ g)))
        V -= float(np.asarray(foot_load, float) @ K.load[0])
        V -= float(np.asarray(actuator_forces, float) @ K.l)
        return T, V

    # -------------------------------------------------------- Newton-Euler
    def newton_euler(self, q, qdd, actuator_forces=None, foot_load=(0.0, 0.0), gravity=True):
        """Joint reactions from the free-body equations of the six bodies.

        ``q``, ``qdd``: absolute poses and accelerations (18,).  If
        ``actuator_forces`` is None they are unknowns too (statics, inverse
        dynamics), else they are known external forces (forward dynamics).
        Returns (actuator_forces (2,), reactions (n_joints, 3), residual) where
        residual is the max-abs residual of the 18 equations (N or N m): ~0
        when the motion is consistent with the loads.
        """
        q = np.asarray(q, float).reshape(self.nb, 3)
        qdd = np.asarray(qdd, float).reshape(self.nb, 3)
        g = self._gravity(gravity)
        load = np.asarray(foot_load, float)
        off = reaction_offsets(self.joints)
        unknown_F = actuator_forces is None
        nx = off[-1] + (self.na if unknown_F else 0)
        A = np.zeros((3 * self.nb, nx))
        rhs = (self._Md * qdd).reshape(-1).copy()
        for i in range(self.nb):
            rhs[3 * i:3 * i + 2] -= self._m[i] * g

        add_reaction_columns(A, q, self.joints, off)
        # foot load (external, known)
        sh = self._shank
        pl = world_point(q, sh, self._load_pt)
        rhs[3 * sh:3 * sh + 2] -= load
        rhs[3 * sh + 2] -= _cross(pl - q[sh, :2], load)
        # actuator axial forces: -F u on the cylinder, +F u on the rod
        for ai, a in enumerate(self.actuators):
            uu = u(q[a.cylinder, 2])
            if unknown_F:
                col = off[-1] + ai
                A[3 * a.cylinder:3 * a.cylinder + 2, col] -= uu
                A[3 * a.rod:3 * a.rod + 2, col] += uu
            else:
                F = float(actuator_forces[ai])
                rhs[3 * a.cylinder:3 * a.cylinder + 2] += F * uu
                rhs[3 * a.rod:3 * a.rod + 2] -= F * uu
        if A.shape[0] == A.shape[1]:
            x = np.linalg.solve(A, rhs)
        else:
            x = np.linalg.lstsq(A, rhs, rcond=None)[0]
        res = float(np.max(np.abs(A @ x - rhs)))

        R = reactions_from_unknowns(q, self.joints, x, off)
        Fa = x[off[-1]:] if unknown_F else np.asarray(actuator_forces, float).copy()
        return Fa, R, res

    # ----------------------------------------------------------- statics
    def statics(self, lengths=None, foot_load=(0.0, 0.0), gravity=True, theta=None, near=None,
                s=None, tol=1e-9):
        """Equilibrium actuator forces (2,) and joint reactions (n_joints, 3).

        Pose from ``lengths`` (closed form, see theta_from_lengths) or given as
        ``theta``.  ``foot_load`` = (Fx, Fy) N on the foot, e.g. (0, 300) for
        the ground pushing the foot up.  The slot variant is a free mechanism
        with both lengths held: raises NoEquilibriumError unless the loads
        happen to balance (Newton-Euler residual below ``tol`` N).
        """
        if theta is None:
            theta = self.theta_from_lengths(lengths, near=near, s=s)
        q = self.absolute_q(theta)
        Fa, R, res = self.newton_euler(q, np.zeros(3 * self.nb), None, foot_load, gravity)
        if res > tol:
            raise NoEquilibriumError(f"loads cannot be balanced (residual {res:.3g})")
        return Fa, R

    def statics_reduced(self, theta, foot_load=(0.0, 0.0), gravity=True) -> np.ndarray:
        """Equilibrium actuator forces by virtual work: (dl/dtheta)^T F = -Q
        (revolute variant; an independent check of :meth:`statics`)."""
        K = self._jets(np.asarray(theta, float), np.zeros(self.ndof))
        _, r = self._reduced(K, self._gravity(gravity), np.asarray(foot_load, float), np.zeros(self.na))
        return np.linalg.solve(K.lg.T, -r)

    def statics_sweep(self, n_grid: int, foot_load=(0.0, 0.0), gravity=True) -> "WorstCase":
        """Worst-case statics over an n x n grid of the two strokes (linspace of
        each stroke, ends included), as legsim_statics_sweep.  Unreachable
        poses are skipped and counted; every pose is taken in the stand pose's
        assembly mode (the core's Newton continuation could flip branch only
        across a dead centre)."""
        grids = [np.linspace(a.stroke[0], a.stroke[1], n_grid) for a in self.actuators]
        maxR = np.zeros(self.nj)
        atR = np.full((self.nj, self.na), np.nan)
        maxF = np.zeros(self.na)
        atF = np.full((self.na, self.na), np.nan)
        npose = nfail = 0
        for l0 in grids[0]:
            for l1 in grids[1]:
                L = np.array([l0, l1])
                try:
                    Fa, R = self.statics(L, foot_load, gravity)
                except (UnreachableError, NoEquilibriumError, np.linalg.LinAlgError):
                    nfail += 1
                    continue
                npose += 1
                mag = np.hypot(R[:, 0], R[:, 1])
                for k in range(self.nj):
                    if mag[k] > maxR[k]:
                        maxR[k], atR[k] = mag[k], L
                for a in range(self.na):
                    if abs(Fa[a]) > maxF[a]:
                        maxF[a], atF[a] = abs(Fa[a]), L
        return WorstCase(maxR, atR, maxF, atF, npose, nfail)

    # -------------------------------------------------- inverse dynamics
    def inverse_dynamics(self, lengths, rates, accels, foot_load=(0.0, 0.0), gravity=True,
                         near=None) -> "InverseDynamics":
        """Actuator forces and reactions along driven lengths (revolute variant).

        ``lengths``, ``rates``, ``accels``: (2,) or (N, 2) (rows continue the
        branch from the previous one).  theta from the closed form, theta_dot
        = G^-1 l_dot, theta_ddot = G^-1 (l_ddot - G_dot theta_dot) with
        G = dl/dtheta; then Newton-Euler with the actuator forces unknown.
        For a schedule s use s(t), s.rate(t), s.accel(t) (see commands).
        """
        if self.variant != "revolute":
            raise ReferenceError("inverse dynamics needs the revolute variant (2 lengths, 2 dof)")
        L = np.atleast_2d(np.asarray(lengths, float))
        Ld = np.atleast_2d(np.asarray(rates, float))
        Ldd = np.atleast_2d(np.asarray(accels, float))
        out = {k: [] for k in ("theta", "thetad", "thetadd", "q", "qd", "qdd", "F", "R", "res", "Fred")}
        prev = near
        load = np.asarray(foot_load, float)
        g = self._gravity(gravity)
        for l, ld, ldd in zip(L, Ld, Ldd):
            th = self.theta_from_lengths(l, near=prev)
            prev = th
            K0 = self._jets(th, np.zeros(self.ndof))
            thd = np.linalg.solve(K0.lg, ld)
            K = self._jets(th, thd)
            thdd = np.linalg.solve(K.lg, ldd - K.lb)
            qdd = (K.J @ thdd + K.b).reshape(-1)
            Fa, R, res = self.newton_euler(K.P.reshape(-1), qdd, None, load, g)
            M, r = self._reduced(K, g, load, np.zeros(self.na))
            Fred = np.linalg.solve(K.lg.T, M @ thdd - r)
            for k, v in (("theta", th), ("thetad", thd), ("thetadd", thdd), ("q", K.P.reshape(-1)),
                         ("qd", (K.J @ thd).reshape(-1)), ("qdd", qdd), ("F", Fa), ("R", R),
                         ("res", res), ("Fred", Fred)):
                out[k].append(v)
        a = {k: np.array(v) for k, v in out.items()}
        single = np.asarray(lengths).ndim == 1
        if single:
            a = {k: v[0] for k, v in a.items()}
        return InverseDynamics(a["theta"], a["thetad"], a["thetadd"], a["q"], a["qd"], a["qdd"],
                               a["F"], a["R"], a["Fred"], a["res"])

    # --------------------------------------------------- forward dynamics
    def simulate(self, t_end: float, t_eval=None, actuators: Optional[Sequence] = None,
                 foot_load=(0.0, 0.0), gravity=True, theta0=None, thetad0=None,
                 rtol: float = 1e-12, atol: float = 1e-12, method: str = "DOP853",
                 max_step: float = np.inf) -> "Result":
        """Integrate the reduced equations from t = 0 to ``t_end``.

        actuators: one command per actuator (ForceCommand, LengthCommand or
        None = zero force); default all zero.  foot_load: (Fx, Fy), each a
        float or a schedule of t.  theta0 defaults to the stand pose, thetad0
        to rest.  t_eval: output times (default: the integrator's own steps);
        the integration restarts exactly at schedule breakpoints (force
        steps) so that they cost no accuracy.
        """
        cmds = list(actuators) if actuators is not None else [None] * self.na
        if len(cmds) != self.na:
            raise ValueError(f"need {self.na} actuator commands")
        for i, c in enumerate(cmds):
            if isinstance(c, ForceCommand) and not callable(c.force) and \
                    abs(float(c.force)) > self.actuators[i].max_force:
                raise ValueError(f"actuator {self.actuators[i].name}: |force| > max_force")
        g = self._gravity(gravity)
        th0 = self.stand_theta() if theta0 is None else np.asarray(theta0, float)
        thd0 = np.zeros(self.ndof) if thetad0 is None else np.asarray(thetad0, float)
        nd = self.ndof

        bps = command_breakpoints(cmds)
        if foot_load is not None:
            for f in foot_load:
                bps.update(_cmd.breakpoints(f))
        edges = [0.0] + sorted(b for b in bps if 0.0 < b < t_end) + [float(t_end)]

        nfev = [0]

        def make_rhs(ta, tb):
            lo, hi = np.nextafter(ta, np.inf), np.nextafter(tb, -np.inf)

            def clip(t):
                return min(max(t, lo), hi)

            def rhs(t, y):
                nfev[0] += 1
                th, thd = y[:nd], y[nd:]
                K = self._jets(th, thd)
                F, _ = self._forces(cmds, t, K, clip)
                load = self._load(foot_load, clip(t))
                M, r = self._reduced(K, g, load, F)
                return np.concatenate([thd, np.linalg.solve(M, r)])
            return rhs

        T, Y = integrate_piecewise(make_rhs, edges, np.concatenate([th0, thd0]), t_eval,
                                   method=method, rtol=rtol, atol=atol, max_step=max_step)
        return self._result(T, Y, cmds, foot_load, g, nfev[0])

    def _result(self, T, Y, cmds, foot_load, g, nfev):
        nd, N = self.ndof, len(T)
        R = Result.empty(N, nd, self.nb, self.nj, self.na)
        R.t, R.nfev = T, nfev
        for k, (t, y) in enumerate(zip(T, Y)):
            th, thd = y[:nd], y[nd:]
            K = self._jets(th, thd)
            F, sat = self._forces(cmds, t, K)
            load = self._load(foot_load, t)
            M, r = self._reduced(K, g, load, F)
            thdd = np.linalg.solve(M, r)
            qdd = (K.J @ thdd + K.b).reshape(-1)
            _, Rj, res = self.newton_euler(K.P.reshape(-1), qdd, F, load, g)
            Fpot = np.array([F[i] if isinstance(c, ForceCommand) else 0.0 for i, c in enumerate(cmds)])
            Tk, Vk = self.energy(th, thd, g, load, Fpot)
            R.theta[k], R.thetad[k], R.thetadd[k] = th, thd, thdd
            R.q[k], R.qd[k], R.qdd[k] = K.P.reshape(-1), (K.J @ thd).reshape(-1), qdd
            R.lengths[k], R.length_rates[k] = K.l, K.ld
            R.length_accels[k] = K.lg @ thdd + K.lb
            R.actuator_forces[k], R.saturated[k] = F, sat
            R.reactions[k], R.ne_residual[k] = Rj, res
            R.foot[k] = K.foot[0]
            R.kinetic[k], R.potential[k] = Tk, Vk
        # continuous angles in q
        for bi in range(self.nb):
            R.q[:, 3 * bi + 2] = np.unwrap(R.q[:, 3 * bi + 2])
        R.energy = R.kinetic + R.potential
        lo = np.array([a.stroke[0] for a in self.actuators])
        hi = np.array([a.stroke[1] for a in self.actuators])
        R.out_of_stroke = bool(np.any((R.lengths < lo) | (R.lengths > hi)))
        return R


@dataclass
class Result:
    """Output of :meth:`LegModel.simulate` (N samples).

    t (N,); theta, thetad, thetadd (N, ndof); q, qd, qdd (N, 18) absolute
    (x, y, phi per body, leg.toml order; angles unwrapped in time); lengths,
    length_rates, length_accels, actuator_forces (N, 2) (axial, > 0 extends; servo forces
    after saturation); saturated (N, 2) bool; reactions (N, n_joints, 3)
    (Fx, Fy on the first-listed body, moment about its CoM); foot (N, 2);
    kinetic, potential, energy (N,) (potential: gravity, foot load and
    force-mode actuator forces as if constant: conserved for constant loads,
    no servo); ne_residual (N,) Newton-Euler consistency (N); out_of_stroke
    (a length left its stroke: the core would have stopped it); nfev.
    """
    t: np.ndarray
    theta: np.ndarray
    thetad: np.ndarray
    thetadd: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    lengths: np.ndarray
    length_rates: np.ndarray
    length_accels: np.ndarray
    actuator_forces: np.ndarray
    saturated: np.ndarray
    reactions: np.ndarray
    foot: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    energy: np.ndarray
    ne_residual: np.ndarray
    out_of_stroke: bool = False
    nfev: int = 0

    @classmethod
    def empty(cls, N, nd, nb, nj, na):
        z = np.zeros
        return cls(z(N), z((N, nd)), z((N, nd)), z((N, nd)), z((N, 3 * nb)), z((N, 3 * nb)),
                   z((N, 3 * nb)), z((N, na)), z((N, na)), z((N, na)), z((N, na)), z((N, na), bool),
                   z((N, nj, 3)), z((N, 2)), z(N), z(N), z(N), z(N))


@dataclass
class InverseDynamics:
    """Output of :meth:`LegModel.inverse_dynamics` ((N, ...) or single rows).

    actuator_forces: from Newton-Euler; actuator_forces_reduced: the same by
    virtual work on the reduced equations (an internal cross-check);
    ne_residual: Newton-Euler residual (N)."""
    theta: np.ndarray
    thetad: np.ndarray
    thetadd: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    actuator_forces: np.ndarray
    reactions: np.ndarray
    actuator_forces_reduced: np.ndarray
    ne_residual: np.ndarray


@dataclass
class WorstCase:
    """Output of :meth:`LegModel.statics_sweep` (cf. legsim_worst_case)."""
    max_reaction: np.ndarray          # (n_joints,) max |(Fx, Fy)| over the grid, N
    reaction_at_lengths: np.ndarray   # (n_joints, 2) lengths where it occurs
    max_actuator_force: np.ndarray    # (2,) max |F|, N
    actuator_at_lengths: np.ndarray   # (2, 2)
    n_poses: int
    n_failed: int
