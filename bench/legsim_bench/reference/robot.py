"""Independent reference of the two-leg robot (box + two legs) with both feet stuck.

The core will solve the robot in absolute coordinates (13 bodies, 32 joint
equations, contact rows, multipliers).  This model is written from the other end
and uses only numpy/scipy and the bench's leg reference (model.py):

* Composition (models/robot.toml, docs/design/robot-on-ground.md): each leg
  is the leg file's own model (LegModel, minimal coordinates theta = (phi3,
  phi6) in the leg's frame), placed on the box by translation and, for the
  left leg, the reflection x -> -x.  A reflected body is an ordinary body with
  world angle psi - phi and body-fixed points (xi, -eta): the reflection maps
  u(phi) to u(-phi) and n(phi) to -n(-phi).

* Coordinates z = (x, y, psi, thetaR (2), thetaL (2)): box pose and each leg's
  own minimal coordinates (7).  With both feet stuck at fixed ground points
  (4 equations) three are independent: i = (psi, thetaR); (x, y) follow in
  closed form from the right foot, thetaL by Newton on the left foot
  (coordinate partitioning).  Velocities and accelerations are exact: every
  point carries its Jacobian and bias (the leg model's jets, transported by
  the box motion), so qdd = A(i) i_dd + a0(i, i_d) with no finite differences.

* Reduced equations M_r i_dd = A^T (Q - M a0) + (dl/di)^T F, integrated with
  scipy's DOP853 at tight tolerance.

* Newton-Euler on the 13 bodies (39 equations) for the joint reactions and the
  ground forces (and, in statics, the actuator forces).  Statics of a stance on
  two stuck feet has one more unknown than equations: the self-equilibrated
  pair of tangential ground forces along the ground line (the thrust of a
  two-hinged arch).  It is fixed by a stated rule, default "equal_friction":
  both feet use the same fraction of their normal force, T_R/N_R = T_L/N_L
  (so both reach the cone together, and on a slope the robot starts to slide
  exactly at mu = tan(slope)).  "min_tangential" (T_R^2 + T_L^2 least) is the
  alternative.  The normal forces do not depend on the rule: the pair acts
  along one line.  Forward dynamics with force or servo actuators is
  determinate (3 dof, 36 independent constraints): no rule is used there.

* Assembly for given actuator lengths with both feet on the ground line is
  closed form: each leg's shape follows from its lengths (LegModel), the box
  angle puts the feet on a line parallel to the ground, `feet_mid` places
  them along it.

Conventions as leg.toml (u(phi) = (sin, -cos), n(phi) = (cos, sin)); body order
box, then the right leg's bodies, then the left's, each in leg.toml order; joint
and actuator order likewise (right then left).  Reactions (Fx, Fy, M): the force
the joint applies to its first-listed body (for the former frame joints the leg
body; the box is second) and the moment about that body's centre of mass.
Ground forces: the force of the ground on each foot (right, left), world axes,
and its normal N and tangential T components (tangent (cos a, sin a), normal
(-sin a, cos a) of the ground line).  Box load: (Fx, Fy, M) at the box centre.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from .commands import ForceCommand
from .model_file import read_model_file
from .model import (LegModel, NoEquilibriumError, ReferenceError, add_force, add_reaction_columns,
                    command_breakpoints, command_forces, integrate_piecewise, n, reaction_offsets,
                    reactions_from_unknowns, u, world_point)

__all__ = ["RobotModel", "Ground", "Assembly", "RobotStatics", "RobotInverse", "RobotResult", "Modes"]

_IND = np.array([2, 3, 4])      # independent: psi, right phi3, right phi6
_DEP = np.array([0, 1, 5, 6])   # dependent: x, y, left phi3, left phi6


def _rot(psi: float) -> np.ndarray:
    c, s = math.cos(psi), math.sin(psi)
    return np.array([[c, -s], [s, c]])


def _perp(v: np.ndarray) -> np.ndarray:
    """Rotation by +90 degrees (works on (2,) and (2, k))."""
    return np.array([-v[1], v[0]])


@dataclass(frozen=True)
class Ground:
    """The ground line: through ``point`` at angle ``slope`` (rad)."""
    point: np.ndarray
    slope: float
    mu_static: float
    mu_kinetic: float

    @property
    def tangent(self) -> np.ndarray:
        return np.array([math.cos(self.slope), math.sin(self.slope)])

    @property
    def normal(self) -> np.ndarray:
        return np.array([-math.sin(self.slope), math.cos(self.slope)])


@dataclass
class _Leg:
    name: str
    prefix: str
    sign: float               # +1, or -1 when mirrored
    S: np.ndarray             # diag(sign, 1)
    offset: np.ndarray        # box-frame position of the leg frame's origin
    model: LegModel
    body0: int                # global index of its first body
    col: int                  # first column of its theta in z


@dataclass(frozen=True)
class _Joint:
    name: str
    kind: str                 # revolute | prismatic | slot
    bodies: tuple             # global body indices
    points: tuple             # body-fixed (xi, eta) per body (None: axis/prismatic)


class _Kin:
    """World poses, Jacobians d/dz and biases of the bodies, feet and lengths."""
    __slots__ = ("P", "J", "b", "l", "lz", "lb", "ld", "foot", "footJ", "footb")


@dataclass
class Assembly:
    """Both feet on the ground for given lengths: z (7), q (39), feet (2, 2)."""
    z: np.ndarray
    q: np.ndarray
    feet: np.ndarray
    lengths: np.ndarray


@dataclass
class RobotStatics:
    """Statics of a stance on two stuck feet (see RobotModel.statics)."""
    assembly: Assembly
    actuator_forces: np.ndarray   # (4,) N, > 0 extends
    reactions: np.ndarray         # (32, 3) Fx, Fy on the first-listed body, M about its CoM
    ground: np.ndarray            # (2, 2) force of the ground on each foot, world
    normal: np.ndarray            # (2,) N
    tangential: np.ndarray        # (2,) T along the ground tangent
    friction_use: np.ndarray      # (2,) |T| / N
    holds: np.ndarray             # (2,) bool: N > 0 and |T| <= mu_static N
    rule: str
    self_stress: np.ndarray       # (40,) the null vector of the equilibrium equations
    residual: float               # max-abs residual of the 39 equations


@dataclass
class RobotInverse:
    """Inverse dynamics at one instant with both feet stuck (see
    RobotModel.inverse_dynamics): independent coordinates, world q, qd, qdd,
    all four lengths, rates and accelerations, and the forces as RobotStatics."""
    i: np.ndarray
    id: np.ndarray
    idd: np.ndarray
    z: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    lengths: np.ndarray
    rates: np.ndarray
    accels: np.ndarray
    actuator_forces: np.ndarray
    reactions: np.ndarray
    ground: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    friction_use: np.ndarray
    holds: np.ndarray
    rule: str
    residual: float


@dataclass
class Modes:
    """Linearization about an equilibrium: x' = A x, x = (i - i_eq, i_d)."""
    matrix: np.ndarray            # (6, 6)
    eigenvalues: np.ndarray       # (6,) complex, 1/s
    eigenvectors: np.ndarray      # (6, 6) complex, columns
    box_shapes: np.ndarray        # (6, 3) complex: box (x, y, psi) displacement per mode
    equilibrium: np.ndarray       # z at the equilibrium (7,)
    actuator_forces: np.ndarray   # (4,) at the equilibrium

    @property
    def growth_rates(self) -> np.ndarray:
        """Real parts > 0 (1/s), largest first, one per real unstable mode."""
        lam = self.eigenvalues
        g = sorted({round(float(x.real), 12) for x in lam if x.real > 1e-9}, reverse=True)
        return np.array(g)


class RobotModel:
    """The two-leg robot of robot.toml (see the module doc)."""

    # ---------------------------------------------------------------- build
    @classmethod
    def from_toml(cls, path) -> "RobotModel":
        path = Path(path)
        return cls(read_model_file(path), path.parent)

    def __init__(self, data: dict, base_dir: Path = Path(".")):
        self.name = data.get("name", "")
        self.gravity = np.array(data.get("gravity", [0.0, -9.81]), float)
        box = data["box"]
        self.box_name = box.get("name", "box")
        self.box_mass = float(box["mass"])
        self.box_size = tuple(map(float, box.get("size", (0.0, 0.0))))
        self.box_inertia = float(box["inertia"])
        if not (self.box_mass > 0 and self.box_inertia > 0):
            raise ValueError("box: mass and inertia must be positive")
        g = data["ground"]
        self.ground = Ground(np.array(g.get("point", [0.0, 0.0]), float), float(g.get("slope", 0.0)),
                             float(g["mu_static"]), float(g["mu_kinetic"]))
        if not 0.0 <= self.ground.mu_kinetic <= self.ground.mu_static:
            raise ValueError("ground: need 0 <= mu_kinetic <= mu_static")
        if len(data.get("leg", [])) != 2:
            raise ValueError("the robot reference needs exactly two legs")

        self.legs: list[_Leg] = []
        self.body_names = [self.box_name]
        mass = [(self.box_mass, self.box_mass, self.box_inertia)]
        self.joints: list[_Joint] = []
        self.actuator_names: list[str] = []
        self._kp, self._kd, self._fmax, self._stroke = [], [], [], []
        self._leg_stand: list[str] = []
        for k, ld in enumerate(data["leg"]):
            lpath = base_dir / ld["file"]
            ldata = read_model_file(lpath)
            variant = ld.get("variant", "revolute")
            if variant != "revolute":
                raise ReferenceError("the robot reference supports the revolute (pinned-knee) leg only")
            lm = LegModel(ldata, variant)
            if not np.allclose(lm.gravity, self.gravity, rtol=0, atol=1e-12):
                raise ValueError(f"leg {ld['name']}: its gravity differs from the robot's")
            sign = -1.0 if ld.get("mirror", False) else 1.0
            S = np.diag([sign, 1.0])
            frame = {kk: np.array(v, float) for kk, v in ldata.get("frame", {}).items()}
            attach = {kk: np.array(v, float) for kk, v in ld["attach"].items()}
            if set(frame) != set(attach):
                raise ValueError(f"leg {ld['name']}: attach must name the leg file's frame points "
                                 f"{sorted(frame)}")
            offs = [attach[kk] - S @ frame[kk] for kk in sorted(frame)]
            if any(np.max(np.abs(o - offs[0])) > 1e-12 for o in offs):
                raise ValueError(f"leg {ld['name']}: the box points are not congruent with the leg's frame")
            leg = _Leg(ld["name"], ld.get("prefix", ld["name"] + "."), sign, S, offs[0], lm,
                       len(self.body_names), 3 + 2 * k)
            self.legs.append(leg)
            for b in lm.bodies:
                self.body_names.append(leg.prefix + b.name)
                mass.append((b.mass, b.mass, b.inertia))
            for j in lm.joints:
                self.joints.append(self._compose_joint(leg, j))
            for a in lm.actuators:
                self.actuator_names.append(leg.prefix + a.name)
                self._kp.append(a.kp)
                self._kd.append(a.kd)
                self._fmax.append(a.max_force)
                self._stroke.append(a.stroke)
        self.nb = len(self.body_names)
        self.nj = len(self.joints)
        self.na = len(self.actuator_names)
        self.joint_names = [j.name for j in self.joints]
        self.foot_names = [leg.prefix + "foot" for leg in self.legs]
        self._Md = np.array(mass, float)
        self._m = self._Md[:, 0].copy()
        self._Mflat = self._Md.reshape(-1)
        self._kp, self._kd, self._fmax = map(np.array, (self._kp, self._kd, self._fmax))
        # the global body index of each leg's shank (its foot) and the foot point
        self._foot_body = [leg.body0 + leg.model._shank for leg in self.legs]
        self._foot_pt = [np.array([leg.model._foot_pt[0], leg.sign * leg.model._foot_pt[1]])
                         for leg in self.legs]
        stand = data.get("pose", {}).get("stand", {})
        self._stand_pose = stand.get("legs", "stand")
        self._feet_mid = float(stand.get("feet_mid", 0.0))
        if self._stand_pose != "stand":
            raise ValueError("pose.stand.legs: only the legs' own 'stand' pose is supported")
        self._thL_guess = None

    @staticmethod
    def _compose_joint(leg: _Leg, j) -> _Joint:
        def mir(pt):
            return None if pt is None else (pt[0], leg.sign * pt[1])
        name = leg.prefix + j.name
        if j.kind == "revolute_to_frame":
            # the frame point on the box, in box body coordinates (xi, eta) = (-y, x)
            xy = leg.offset + leg.S @ np.array(j.frame_point)
            return _Joint(name, "revolute", (leg.body0 + j.bodies[0], 0),
                          (mir(j.points[0]), (-float(xy[1]), float(xy[0]))))
        return _Joint(name, j.kind, tuple(leg.body0 + b for b in j.bodies),
                      tuple(mir(p) for p in j.points))

    # --------------------------------------------------------- kinematics
    def _place(self, leg: _Leg, R, psi_d, thd, p, Jp, bp, J, b, row):
        """Transport a leg-frame point jet to world: writes J[row] (2, 7), b[row]."""
        RS = R @ leg.S
        rho = R @ (leg.offset + leg.S @ p)
        c = leg.col
        J[row, :, 0] = (1.0, 0.0)
        J[row, :, 1] = (0.0, 1.0)
        J[row, :, 2] = _perp(rho)
        J[row, :, c:c + 2] = RS @ Jp
        vrel = RS @ (Jp @ thd)
        b[row] = -psi_d * psi_d * rho + 2.0 * psi_d * _perp(vrel) + RS @ bp
        return rho

    def kinematics(self, z, zd) -> _Kin:
        """Poses (13, 3), d/dz (13, 3, 7), biases (13, 3); lengths; feet."""
        z = np.asarray(z, float)
        zd = np.asarray(zd, float)
        r, psi, psi_d = z[:2], z[2], zd[2]
        R = _rot(psi)
        K = _Kin()
        P = np.zeros((self.nb, 3))
        J = np.zeros((self.nb, 3, 7))
        b = np.zeros((self.nb, 3))
        P[0] = z[:3]
        J[0, :, :3] = np.eye(3)
        foot = np.zeros((2, 2))
        fJ = np.zeros((2, 2, 7))
        fb = np.zeros((2, 2))
        l = np.zeros(self.na)
        lz = np.zeros((self.na, 7))
        lb = np.zeros(self.na)
        ld = np.zeros(self.na)
        Jp2 = np.zeros((1, 2, 7))
        bp2 = np.zeros((1, 2))
        for k, leg in enumerate(self.legs):
            c = leg.col
            th, thd = z[c:c + 2], zd[c:c + 2]
            L = leg.model._jets(th, thd)
            for i in range(leg.model.nb):
                g = leg.body0 + i
                Jp2[:] = 0.0
                rho = self._place(leg, R, psi_d, thd, L.P[i, :2], L.J[i, :2], L.b[i, :2], Jp2, bp2, 0)
                P[g, :2] = r + rho
                J[g, :2] = Jp2[0]
                b[g, :2] = bp2[0]
                P[g, 2] = psi + leg.sign * L.P[i, 2]
                J[g, 2, 2] = 1.0
                J[g, 2, c:c + 2] = leg.sign * L.J[i, 2]
                b[g, 2] = leg.sign * L.b[i, 2]
            fp, fV, fbb = L.foot
            Jp2[:] = 0.0
            rho = self._place(leg, R, psi_d, thd, fp, fV, fbb, Jp2, bp2, 0)
            foot[k] = r + rho
            fJ[k] = Jp2[0]
            fb[k] = bp2[0]
            a0 = 2 * k
            l[a0:a0 + 2] = L.l
            lz[a0:a0 + 2, c:c + 2] = L.lg
            lb[a0:a0 + 2] = L.lb
            ld[a0:a0 + 2] = L.ld
        K.P, K.J, K.b = P, J, b
        K.l, K.lz, K.lb, K.ld = l, lz, lb, ld
        K.foot, K.footJ, K.footb = foot, fJ, fb
        return K

    def absolute_q(self, z) -> np.ndarray:
        """World (x, y, phi) of the 13 bodies (39,)."""
        return self.kinematics(z, np.zeros(7)).P.reshape(-1)

    def feet(self, z) -> np.ndarray:
        """World foot points (2, 2): right, left."""
        return self.kinematics(z, np.zeros(7)).foot

    def lengths(self, z) -> np.ndarray:
        return self.kinematics(z, np.zeros(7)).l

    def stand_lengths(self) -> np.ndarray:
        return np.concatenate([leg.model.lengths(leg.model.stand_theta()) for leg in self.legs])

    # ----------------------------------------------------------- assembly
    def assemble(self, lengths=None, feet_mid: Optional[float] = None) -> Assembly:
        """Both feet on the ground line for the given lengths (4,) (default:
        each leg's stand lengths); the feet's midpoint at ``feet_mid`` along the
        line (default the model's).  Closed form; raises UnreachableError."""
        L = self.stand_lengths() if lengths is None else np.asarray(lengths, float)
        if L.shape != (self.na,) or not np.all(np.isfinite(L)):
            raise ValueError("need 4 finite lengths")
        mid = self._feet_mid if feet_mid is None else float(feet_mid)
        z = np.zeros(7)
        fb = []
        for k, leg in enumerate(self.legs):
            th = leg.model.theta_from_lengths(L[2 * k:2 * k + 2])
            z[leg.col:leg.col + 2] = th
            fb.append(leg.offset + leg.S @ leg.model.foot(th))
        d = fb[0] - fb[1]                  # right foot minus left foot, box frame
        psi = self.ground.slope - math.atan2(d[1], d[0])
        R = _rot(psi)
        centre = 0.5 * (fb[0] + fb[1])
        r = self.ground.point + mid * self.ground.tangent - R @ centre
        z[:2], z[2] = r, psi
        K = self.kinematics(z, np.zeros(7))
        return Assembly(z, K.P.reshape(-1), K.foot.copy(), L.copy())

    def _solve_dependent(self, ind, feet, guess=None) -> np.ndarray:
        """z from the independent (psi, thetaR) with both feet at ``feet``."""
        psi = float(ind[0])
        R = _rot(psi)
        legR, legL = self.legs
        thR = np.asarray(ind[1:3], float)
        fR = legR.model.foot(thR)
        r = feet[0] - R @ (legR.offset + legR.S @ fR)
        target = legL.S @ (R.T @ (feet[1] - r) - legL.offset)
        th = np.array(guess if guess is not None else self._thL_guess, float)
        for it in range(40):
            K = legL.model._jets(th, np.zeros(2))
            res = K.foot[0] - target
            if np.max(np.abs(res)) < 1e-14:
                break
            dth = np.linalg.solve(K.foot[1], res)
            th = th - dth
            if np.max(np.abs(dth)) < 1e-15:
                break
        else:
            raise ReferenceError("left foot: Newton did not converge")
        if np.max(np.abs(K.foot[0] - target)) > 1e-11:
            raise ReferenceError("left foot cannot reach its ground point")
        self._thL_guess = th.copy()
        z = np.empty(7)
        z[:2], z[2], z[3:5], z[5:7] = r, psi, thR, th
        return z

    def _partition(self, K):
        """T (7, 3) with z_d = T i_d, and c (7,) with z_dd = T i_dd + c."""
        G = K.footJ.reshape(4, 7)
        gb = K.footb.reshape(4)
        Gd = G[:, _DEP]
        T = np.zeros((7, 3))
        T[_IND] = np.eye(3)
        T[_DEP] = -np.linalg.solve(Gd, G[:, _IND])
        c = np.zeros(7)
        c[_DEP] = -np.linalg.solve(Gd, gb)
        return T, c

    # ------------------------------------------------------------ loads
    def _gravity(self, gravity):
        if gravity is True:
            return self.gravity.copy()
        if gravity is False or gravity is None:
            return np.zeros(2)
        return np.asarray(gravity, float)

    def _applied(self, g, box_load) -> np.ndarray:
        Q = np.zeros((self.nb, 3))
        Q[:, :2] = self._m[:, None] * g[None, :]
        Q[0] += np.asarray(box_load, float)
        return Q.reshape(-1)

    def _forces(self, cmds, t, K):
        return command_forces(cmds, t, K.l, K.ld, self._kp, self._kd, self._fmax)[0]

    # ----------------------------------------------------------- dynamics
    def _state(self, i, id_, feet, cmds, t, g, box_load):
        """Everything at one state of the stuck-feet robot."""
        z = self._solve_dependent(i, feet)
        K0 = self.kinematics(z, np.zeros(7))
        T, _ = self._partition(K0)
        zd = T @ id_
        K = self.kinematics(z, zd)
        _, c = self._partition(K)
        Jq = K.J.reshape(-1, 7)
        A = Jq @ T
        a0 = Jq @ c + K.b.reshape(-1)
        F = self._forces(cmds, t, K)
        Q = self._applied(g, box_load)
        Mr = A.T @ (self._Mflat[:, None] * A)
        rhs = A.T @ (Q - self._Mflat * a0) + T.T @ (K.lz.T @ F)
        idd = np.linalg.solve(Mr, rhs)
        return z, zd, K, T, c, idd, A @ idd + a0, F

    def accelerations(self, i, id_, feet, actuators, t=0.0, box_load=(0.0, 0.0, 0.0), gravity=True):
        """i_dd (3,) of the independent coordinates (psi, thetaR)."""
        return self._state(np.asarray(i, float), np.asarray(id_, float), np.asarray(feet, float),
                           list(actuators), t, self._gravity(gravity), box_load)[5]

    def energy(self, z, zd, box_load=(0.0, 0.0, 0.0), actuator_forces=None, gravity=True):
        """(kinetic, potential): gravity, the constant box load and constant
        axial actuator forces (-F l)."""
        K = self.kinematics(z, zd)
        v = K.J.reshape(-1, 7) @ np.asarray(zd, float)
        T = 0.5 * float(np.sum(self._Mflat * v * v))
        g = self._gravity(gravity)
        V = -float(np.sum(self._m * (K.P[:, :2] @ g)))
        V -= float(np.asarray(box_load, float) @ K.P[0])
        if actuator_forces is not None:
            V -= float(np.asarray(actuator_forces, float) @ K.l)
        return T, V

    def simulate(self, t_end: float, t_eval=None, actuators: Optional[Sequence] = None,
                 box_load=(0.0, 0.0, 0.0), gravity=True, start: Optional[Assembly] = None,
                 i0=None, id0=None, rtol=1e-11, atol=1e-12) -> "RobotResult":
        """Both feet stuck at the feet of ``start`` (default: the stand
        assembly).  actuators: 4 commands (ForceCommand, LengthCommand, None).
        i0, id0: independent coordinates (psi, thetaR) and their rates
        (default: the start pose, at rest).  box_load: (Fx, Fy, M) constant."""
        cmds = list(actuators) if actuators is not None else [None] * self.na
        if len(cmds) != self.na:
            raise ValueError(f"need {self.na} actuator commands")
        start = self.assemble() if start is None else start
        feet = start.feet.copy()
        g = self._gravity(gravity)
        i0 = start.z[_IND].copy() if i0 is None else np.asarray(i0, float)
        id0 = np.zeros(3) if id0 is None else np.asarray(id0, float)
        self._thL_guess = start.z[5:7].copy()
        bps = command_breakpoints(cmds)
        edges = [0.0] + sorted(b for b in bps if 0.0 < b < t_end) + [float(t_end)]
        nfev = [0]

        def make_rhs(ta, tb):
            lo, hi = np.nextafter(ta, np.inf), np.nextafter(tb, -np.inf)

            def rhs(t, y):
                nfev[0] += 1
                tt = min(max(t, lo), hi)
                idd = self._state(y[:3], y[3:], feet, cmds, tt, g, box_load)[5]
                return np.concatenate([y[3:], idd])
            return rhs

        T, Y = integrate_piecewise(make_rhs, edges, np.concatenate([i0, id0]), t_eval,
                                   method="DOP853", rtol=rtol, atol=atol)
        return self._result(T, Y, feet, cmds, g, box_load, nfev[0])

    def _result(self, T, Y, feet, cmds, g, box_load, nfev) -> "RobotResult":
        N = len(T)
        out = RobotResult.empty(N, self.nb, self.nj, self.na)
        out.t, out.nfev, out.feet = T, nfev, feet
        Fpot = [isinstance(c, ForceCommand) for c in cmds]
        for k, (t, y) in enumerate(zip(T, Y)):
            z, zd, K, Tm, c, idd, qdd, F = self._state(y[:3], y[3:], feet, cmds, t, g, box_load)
            _, R, G, res = self.newton_euler(K.P.reshape(-1), qdd, F, box_load, g)
            Fp = np.where(Fpot, F, 0.0)
            kin, pot = self.energy(z, zd, box_load, Fp, g)
            out.i[k], out.id[k], out.idd[k] = y[:3], y[3:], idd
            out.z[k], out.zd[k] = z, zd
            out.q[k], out.qd[k], out.qdd[k] = K.P.reshape(-1), K.J.reshape(-1, 7) @ zd, qdd
            out.lengths[k], out.length_rates[k] = K.l, K.ld
            out.actuator_forces[k] = F
            out.reactions[k], out.ground[k], out.ne_residual[k] = R, G, res
            out.kinetic[k], out.potential[k] = kin, pot
        out.energy = out.kinetic + out.potential
        out.normal = out.ground @ self.ground.normal
        out.tangential = out.ground @ self.ground.tangent
        return out

    # -------------------------------------------------------- Newton-Euler
    def newton_euler(self, q, qdd, actuator_forces=None, box_load=(0.0, 0.0, 0.0), gravity=True):
        """Joint reactions and ground forces from the 39 free-body equations.

        Known ``actuator_forces``: 36 unknowns (32 joint, 4 ground), solved in
        least squares; returns (F, reactions (32, 3), ground (2, 2), residual).
        ``actuator_forces=None`` (statics, inverse dynamics): 40 unknowns, one
        more than equations; returns the matrix and right-hand side instead,
        see :meth:`statics`.
        """
        A, rhs, off, gcol = self._ne_system(q, qdd, actuator_forces, box_load, self._gravity(gravity))
        if actuator_forces is None:
            return A, rhs, off, gcol
        x = np.linalg.lstsq(A, rhs, rcond=None)[0]
        res = float(np.max(np.abs(A @ x - rhs)))
        R, G = self._unpack(np.asarray(q, float).reshape(self.nb, 3), x, off, gcol)
        return np.asarray(actuator_forces, float).copy(), R, G, res

    def _ne_system(self, q, qdd, actuator_forces, box_load, g):
        q = np.asarray(q, float).reshape(self.nb, 3)
        qdd = np.asarray(qdd, float).reshape(self.nb, 3)
        off = reaction_offsets(self.joints)
        gcol = int(off[-1])
        unknown_F = actuator_forces is None
        nx = gcol + 4 + (self.na if unknown_F else 0)
        A = np.zeros((3 * self.nb, nx))
        rhs = (self._Md * qdd).reshape(-1).copy()
        for i in range(self.nb):
            rhs[3 * i:3 * i + 2] -= self._m[i] * g
        rhs[0:3] -= np.asarray(box_load, float)

        add_reaction_columns(A, q, self.joints, off)
        ex, ey = np.array([1.0, 0.0]), np.array([0.0, 1.0])
        for k in range(2):
            bi = self._foot_body[k]
            p = world_point(q, bi, self._foot_pt[k])
            add_force(A, q, bi, gcol + 2 * k, ex, p)
            add_force(A, q, bi, gcol + 2 * k + 1, ey, p)
        for a, (cyl, rod) in enumerate(self._actuator_bodies()):
            uu = u(q[cyl, 2])
            if unknown_F:
                col = gcol + 4 + a
                A[3 * cyl:3 * cyl + 2, col] -= uu
                A[3 * rod:3 * rod + 2, col] += uu
            else:
                F = float(actuator_forces[a])
                rhs[3 * cyl:3 * cyl + 2] += F * uu
                rhs[3 * rod:3 * rod + 2] -= F * uu
        return A, rhs, off, gcol

    def _actuator_bodies(self):
        out = []
        for leg in self.legs:
            for a in leg.model.actuators:
                out.append((leg.body0 + a.cylinder, leg.body0 + a.rod))
        return out

    def _unpack(self, q, x, off, gcol):
        R = reactions_from_unknowns(q, self.joints, x, off)
        G = x[gcol:gcol + 4].reshape(2, 2).copy()
        return R, G

    # ------------------------------------------------------------ statics
    def statics(self, lengths=None, box_load=(0.0, 0.0, 0.0), gravity=True, rule="equal_friction",
                feet_mid: Optional[float] = None, assembly: Optional[Assembly] = None,
                tol: float = 1e-8) -> RobotStatics:
        """Actuator forces, joint reactions and ground forces of the stance on
        both stuck feet at the given lengths (closed-form assembly).

        The 39 equilibrium equations have 40 unknowns: the solutions differ by
        the self-stress (a pair of equal and opposite tangential ground forces
        along the ground line with the internal forces it causes).  ``rule``
        picks one: "equal_friction" (T_R/N_R = T_L/N_L, default) or
        "min_tangential" (T_R^2 + T_L^2 least).
        """
        asm = self.assemble(lengths, feet_mid) if assembly is None else assembly
        F, R, G, N, Tt, use, holds, null, res = self._forces_by_rule(
            asm.q, np.zeros(3 * self.nb), box_load, gravity, rule, tol)
        return RobotStatics(asm, F, R, G, N, Tt, use, holds, rule, null, res)

    def _forces_by_rule(self, q, qdd, box_load, gravity, rule, tol):
        """The 39 Newton-Euler equations at (q, qdd) with the 4 actuator forces
        unknown (40 unknowns): the particular solution plus s times the
        self-stress, s by ``rule``."""
        A, rhs, off, gcol = self.newton_euler(q, qdd, None, box_load, gravity)
        Uu, s, Vt = np.linalg.svd(A)
        if s[-1] < 1e-9 * s[0]:
            raise NoEquilibriumError("the stance is singular: its equilibrium equations lose rank")
        x0 = Vt[:-1].T @ ((Uu.T @ rhs)[:len(s)] / s)
        null = Vt[-1].copy()
        res0 = float(np.max(np.abs(A @ x0 - rhs)))
        if res0 > tol:
            raise NoEquilibriumError(f"loads cannot be balanced (residual {res0:.3g})")
        tg, nm = self.ground.tangent, self.ground.normal
        G0 = x0[gcol:gcol + 4].reshape(2, 2)
        Gn = null[gcol:gcol + 4].reshape(2, 2)
        N0, T0 = G0 @ nm, G0 @ tg
        Nn, Tn = Gn @ nm, Gn @ tg
        if np.max(np.abs(Nn)) > 1e-9 * np.max(np.abs(Tn)):
            raise ReferenceError("the self-stress changes the normal forces: feet not on one line?")
        if rule == "equal_friction":
            den = Tn[0] * N0[1] - Tn[1] * N0[0]
            s_ = (T0[1] * N0[0] - T0[0] * N0[1]) / den
        elif rule == "min_tangential":
            s_ = -float(T0 @ Tn) / float(Tn @ Tn)
        else:
            raise ValueError(f"unknown rule {rule!r}")
        x = x0 + s_ * null
        res = float(np.max(np.abs(A @ x - rhs)))
        qb = np.asarray(q, float).reshape(self.nb, 3)
        R, G = self._unpack(qb, x, off, gcol)
        F = x[gcol + 4:].copy()
        N, Tt = G @ nm, G @ tg
        with np.errstate(divide="ignore", invalid="ignore"):
            use = np.where(N > 0, np.abs(Tt) / N, np.inf)
        holds = (N > 0) & (np.abs(Tt) <= self.ground.mu_static * N)
        return F, R, G, N, Tt, use, holds, null, res

    # -------------------------------------------------- inverse dynamics
    def inverse_dynamics(self, lengths, rates, accels, follow: int = 3,
                         start: Optional[Assembly] = None, box_load=(0.0, 0.0, 0.0), gravity=True,
                         rule="equal_friction", guess=None, tol: float = 1e-8) -> "RobotInverse":
        """Inverse dynamics along driven lengths with both feet stuck at
        ``start``'s feet (default: the stand assembly).  The three actuators
        other than ``follow`` drive the three independent coordinates
        i = (psi, thetaR): i by Newton on their lengths, i_d and i_dd from
        dl/di (exact jets, no differences); the follower's length, rate and
        acceleration follow.  The 4 actuator forces, the reactions and the
        ground forces from the 39 Newton-Euler equations, the self-stress
        fixed by ``rule`` as in :meth:`statics`."""
        start = self.assemble() if start is None else start
        feet, g = start.feet, self._gravity(gravity)
        D = [a for a in range(self.na) if a != int(follow)]
        L, Ld, Ldd = (np.asarray(v, float)[D] for v in (lengths, rates, accels))
        i = np.array(start.z[_IND] if guess is None else guess, float)
        self._thL_guess = start.z[5:7].copy()
        for _ in range(50):
            z = self._solve_dependent(i, feet)
            K = self.kinematics(z, np.zeros(7))
            T, _ = self._partition(K)
            Gl = K.lz[D] @ T
            res = K.l[D] - L
            if np.max(np.abs(res)) < 1e-14:
                break
            i = i - np.linalg.solve(Gl, res)
        else:
            raise NoEquilibriumError("the driven lengths cannot be reached with both feet stuck")
        id_ = np.linalg.solve(Gl, Ld)
        zd = T @ id_
        K = self.kinematics(z, zd)
        _, c = self._partition(K)
        idd = np.linalg.solve(Gl, Ldd - K.lz[D] @ c - K.lb[D])
        zdd = T @ idd + c
        Jq = K.J.reshape(-1, 7)
        q, qd, qdd = K.P.reshape(-1), Jq @ zd, Jq @ zdd + K.b.reshape(-1)
        F, R, G, N, Tt, use, holds, null, r = self._forces_by_rule(q, qdd, box_load, g, rule, tol)
        return RobotInverse(i, id_, idd, z, q, qd, qdd, K.l.copy(), K.ld.copy(), K.lz @ zdd + K.lb,
                            F, R, G, N, Tt, use, holds, rule, r)

    # ------------------------------------------------------ equilibria, modes
    def equilibrium(self, actuators, start: Optional[Assembly] = None, box_load=(0.0, 0.0, 0.0),
                    gravity=True, tol=1e-12, h=1e-7) -> np.ndarray:
        """z at rest in equilibrium with the feet at ``start``'s feet (Newton
        on the reduced accelerations, from ``start``): e.g. the servo stand,
        which sags until the servo forces carry the weight."""
        start = self.assemble() if start is None else start
        feet, g = start.feet, self._gravity(gravity)
        self._thL_guess = start.z[5:7].copy()
        cmds = list(actuators)
        i = start.z[_IND].copy()
        zero = np.zeros(3)

        def f(ii):
            return self._state(ii, zero, feet, cmds, 0.0, g, box_load)[5]
        for _ in range(50):
            r = f(i)
            if np.max(np.abs(r)) < tol:
                break
            Jm = np.column_stack([(f(i + h * e) - f(i - h * e)) / (2 * h) for e in np.eye(3)])
            i = i - np.linalg.solve(Jm, r)
        else:
            raise NoEquilibriumError("no equilibrium found near the start pose")
        return self._solve_dependent(i, feet)

    def linearize(self, actuators, z_eq=None, start: Optional[Assembly] = None,
                  box_load=(0.0, 0.0, 0.0), gravity=True, h=1e-6) -> Modes:
        """Linearization of the stuck-feet dynamics about the rest state at
        ``z_eq`` (default: start's pose), by central differences of the exact
        reduced accelerations; its eigenvalues (1/s) and the box motion of
        each mode."""
        start = self.assemble() if start is None else start
        feet, g = start.feet, self._gravity(gravity)
        cmds = list(actuators)
        z_eq = start.z if z_eq is None else np.asarray(z_eq, float)
        self._thL_guess = z_eq[5:7].copy()
        i0 = z_eq[_IND].copy()

        def f(x):
            return self._state(i0 + x[:3], x[3:], feet, cmds, 0.0, g, box_load)[5]
        base = f(np.zeros(6))
        if np.max(np.abs(base)) > 1e-6:
            raise NoEquilibriumError(f"not an equilibrium (accelerations {np.max(np.abs(base)):.3g})")
        Amat = np.zeros((6, 6))
        Amat[:3, 3:] = np.eye(3)
        for k in range(6):
            e = np.zeros(6)
            e[k] = h
            Amat[3:, k] = (f(e) - f(-e)) / (2 * h)
        lam, V = np.linalg.eig(Amat)
        order = np.argsort(-lam.real)
        lam, V = lam[order], V[:, order]
        K0 = self.kinematics(z_eq, np.zeros(7))
        T, _ = self._partition(K0)
        shapes = (T[:3] @ V[:3]).T
        F = self._forces(cmds, 0.0, K0)
        return Modes(Amat, lam, V, shapes, z_eq.copy(), F)


@dataclass
class RobotResult:
    """Output of RobotModel.simulate (N samples).  i, id, idd (N, 3): psi and
    the right leg's (phi3, phi6); z, zd (N, 7); q, qd, qdd (N, 39) world;
    lengths, length_rates, actuator_forces (N, 4); reactions (N, 32, 3);
    ground (N, 2, 2) force of the ground on each foot; normal, tangential
    (N, 2); kinetic, potential, energy (N,) (potential: gravity, box load,
    force-mode actuators as constants); ne_residual (N,); feet (2, 2)."""
    t: np.ndarray
    i: np.ndarray
    id: np.ndarray
    idd: np.ndarray
    z: np.ndarray
    zd: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    lengths: np.ndarray
    length_rates: np.ndarray
    actuator_forces: np.ndarray
    reactions: np.ndarray
    ground: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    energy: np.ndarray
    ne_residual: np.ndarray
    feet: np.ndarray
    nfev: int = 0

    @classmethod
    def empty(cls, N, nb, nj, na):
        z = np.zeros
        return cls(z(N), z((N, 3)), z((N, 3)), z((N, 3)), z((N, 7)), z((N, 7)), z((N, 3 * nb)),
                   z((N, 3 * nb)), z((N, 3 * nb)), z((N, na)), z((N, na)), z((N, na)),
                   z((N, nj, 3)), z((N, 2, 2)), z((N, 2)), z((N, 2)), z(N), z(N), z(N), z(N),
                   z((2, 2)))
