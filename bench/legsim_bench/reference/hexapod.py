"""Independent reference of the hexapod in space (models/hexapod.toml), in minimal coordinates.

The core lifts every bar of the six legs into space as a free body and closes the joints with
rows and multipliers (firmware_core/src/spatial/). This model is written from the other end,
on the bench's planar leg (LegModel: closed-form poses and exact jets in the leg's own two
coordinates theta = (phi3, phi6)):

* A leg's place: its yoke turns about the box's z through the hip point h (box frame) by
  alpha = heading + psi (psi the rowing angle). Yoke frame R_y = R_box Rz(alpha): x out from the
  axis, z up. The leg's planar point (x, y) (its file's frame) is at (hip_offset + x, 0, y) in
  the yoke frame; a planar angle turns about -y_yoke, so a bar's axes (u, n, k) are
  R_y (u_x, 0, u_y), R_y (n_x, 0, n_y), -R_y e_y. A left leg is the same leg at heading +pi/2.
  Inertias: the box and the yoke principal in their frames; a bar's (m r^2 / 2, J, J) about
  (u, n, k), J the leg file's in-plane inertia (the file's yoke and bar radius).

* Velocities are linear in u = (v, omega) of the box (world: its centre's velocity, its angular
  velocity) and each free leg's (psi_dot, theta_dot); every body's acceleration is A u_dot + c
  with c from the leg's planar jets carried by the rotating yoke (no differences):
  x = r + a + b (a = R h, b = R_y rho), x_ddot = v_dot + omega_dot x a + omega_y_dot x b
  + omega x (omega x a) + omega_y x (omega_y x b) + 2 omega_y x R_y rho_dot + R_y rho_ddot,
  omega_y = omega + psi_dot z_box. The box's orientation is a unit quaternion integrated from
  omega (normalised where it is read).

* A stuck foot fixes its leg's three coordinates from the box pose: psi in closed form (the
  plane through the hip axis and the foot), theta by the leg's planar inverse kinematics
  (LegModel.theta_from_foot); their rates and accelerations from the foot's velocity and
  acceleration being zero: G (alpha, theta)_dot = -(v + omega x (a + b_f)), G = [z x b_f, R_y V_f].

* Reduced equations (Kane's: the bodies' Newton-Euler projected on the partial velocities)
  M u_dot = sum A^T (applied - inertial bias) + actuators by virtual work (F dl, l the planar
  length, its jacobian through E for a stuck leg) + rowing torques (tau dpsi), integrated with
  DOP853. A stuck foot's ground force from its leg's own three equations (the box's motion
  given): G^T f = sum_leg A_leg^T (M a - applied) - (tau, lg^T F).

* Statics on a stance: the stance forces with the least sum of squares that balance the whole
  robot (Lagrange: f_k = lambda + mu x e_k, e_k the foot from the feet's centroid; then
  lambda = -W / n and J mu = -(the loads' moment about the centroid), J = sum |e|^2 I - e e^T),
  then each leg by virtual work in its own coordinates (psi, theta) at a held box.

Units SI, world z up; pose dicts as legsim.Hexapod's (box_m, box_quat (w, x, y, z), rowing_rad,
length_m (6 x 2): each leg's actuators in its file's order).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from .model import LegModel, NoEquilibriumError, ReferenceError, n, u
from .model_file import read_model_file

__all__ = ["HexapodModel", "HexapodResult", "quat_matrix"]

LEGS = 6
_E3 = np.array([0.0, 0.0, 1.0])


def quat_matrix(q) -> np.ndarray:
    """Rotation matrix of the quaternion q = (w, x, y, z) (normalised here)."""
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _skew(a) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def _cx(a, b) -> np.ndarray:
    """a x b for 3-vectors (a or b may be (k, 3))."""
    return np.cross(a, b)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class _Leg:
    name: str
    model: LegModel
    hip: np.ndarray       # box frame (m)
    heading: float        # rad


class _LegJets:
    """One leg's bodies (yoke, then its bars in the file's order) at one state: positions X,
    velocities xd, masses m, world inertias Iw, angular velocities w; partial velocities on the
    box's (v, omega) (Lb: 3 x 6; the angular one is [0, I] for every body) and on the leg's
    (psi_dot, theta_dot) (Ll, Wl: 3 x 3), the bias accelerations (cl, ca); the hip a = R h, the
    box's z; the foot's b_f (from the hip), G, bias cf; the lengths l, their jacobian lg."""
    __slots__ = ("X", "m", "Iw", "w", "Lb", "Ll", "cl", "Wl", "ca", "a", "z", "bf", "G", "cf",
                 "l", "lg", "theta", "psi", "xd")


@dataclass
class HexapodResult:
    """Output of :meth:`HexapodModel.simulate` (N samples).

    t (N,); box_q (N, 7): centre (m, world) and unit quaternion (w, x, y, z); box_v (N, 6):
    velocity and angular velocity (world); rowing (N, 6) rad; theta (N, 6, 2) each leg's
    (phi3, phi6); lengths (N, 6, 2) m; feet (N, 6, 3) m world; foot_force (N, 6, 3): the
    ground's force on each stuck foot (N, world; 0 for a free leg); com (N, 3);
    kinetic, potential, energy (N,) J (potential: gravity, -F l, -tau psi, -F_box . r);
    stance (the stuck legs); com_accel (N, 3) m/s^2 (sum m a / M over the bodies: Newton's
    check of the ground forces); angular_momentum (N, 3) about the centre of mass (world,
    kg m^2/s); nfev."""
    t: np.ndarray
    box_q: np.ndarray
    box_v: np.ndarray
    rowing: np.ndarray
    theta: np.ndarray
    lengths: np.ndarray
    feet: np.ndarray
    foot_force: np.ndarray
    com: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    energy: np.ndarray
    stance: tuple
    com_accel: np.ndarray = None
    angular_momentum: np.ndarray = None
    nfev: int = 0


class HexapodModel:
    """The hexapod of a hexapod file (see the module doc). Build with :meth:`from_toml`."""

    @classmethod
    def from_toml(cls, path) -> "HexapodModel":
        path = Path(path)
        return cls(read_model_file(path), path.parent)

    def __init__(self, data: dict, base_dir: Path = Path(".")):
        self.name = data.get("name", "")
        self.gravity = np.array(data["gravity"], float)
        if self.gravity[0] != 0.0 or self.gravity[1] != 0.0:
            raise ValueError("gravity must be along z")
        box, yoke = data["box"], data["yoke"]
        self.box_mass = float(box["mass"])
        self.box_inertia = np.array(box["inertia"], float)
        self.yoke_mass = float(yoke["mass"])
        self.yoke_com = np.array(yoke["com"], float)
        self.yoke_inertia = np.array(yoke["inertia"], float)
        # the rowing motor's rotor reflected to the yoke (rotor ratio^2), added to the yoke's
        # inertia about the hip axis in the dynamics (not a rigid body's: the yoke's own is apart)
        rowing = data.get("rowing", {})
        self.rotor_reflected = float(rowing.get("rotor_inertia_kg_m2", 0.0)) * float(rowing.get("gear_ratio", 1.0)) ** 2
        self.hip_offset = float(yoke["hip_offset"])
        self.bar_radius = float(yoke["bar_radius"])
        models = {}
        self.legs = []
        for ld in data["leg"]:
            key = (str(ld["file"]), ld.get("variant", "revolute"))
            if key not in models:
                models[key] = LegModel.from_toml(base_dir / key[0], variant=key[1])
                if models[key].variant != "revolute" or models[key].gravity[1] != self.gravity[2]:
                    raise ValueError(f"{key[0]}: the hexapod needs the revolute leg with its gravity")
            self.legs.append(_Leg(ld["name"], models[key], np.array(ld["hip"], float), float(ld["heading"])))
        if len(self.legs) != LEGS:
            raise ValueError(f"a hexapod has {LEGS} legs")
        self.leg_names = [leg.name for leg in self.legs]
        # per leg: the masses and principal inertias of its yoke and bars
        self._leg_m, self._leg_I = [], []
        for leg in self.legs:
            mm = [self.yoke_mass] + [b.mass for b in leg.model.bodies]
            II = [self.yoke_inertia + np.array([0.0, 0.0, self.rotor_reflected])] + [np.array([0.5 * b.mass * self.bar_radius ** 2, b.inertia, b.inertia])
                                        for b in leg.model.bodies]
            self._leg_m.append(np.array(mm))
            self._leg_I.append(np.array(II))
        self.mass = self.box_mass + sum(float(m.sum()) for m in self._leg_m)

    # ------------------------------------------------------------ poses
    def stand_lengths(self) -> np.ndarray:
        """Each leg's stand lengths (6, 2) m (its file's stand pose)."""
        return np.array([leg.model.lengths(leg.model.stand_theta()) for leg in self.legs])

    def stand_pose(self, box_height: float, rowing=(0.0,) * LEGS) -> dict:
        """The box level at (0, 0, box_height), every leg at its stand lengths (legsim's too)."""
        return {"box_m": [0.0, 0.0, float(box_height)], "box_quat": [1.0, 0.0, 0.0, 0.0],
                "rowing_rad": [float(x) for x in rowing], "length_m": self.stand_lengths().tolist()}

    def _thetas(self, pose) -> np.ndarray:
        L = np.asarray(pose["length_m"], float)
        return np.array([leg.model.theta_from_lengths(L[k]) for k, leg in enumerate(self.legs)])

    def _leg(self, k, r, R, v, w, psi, psid, th, thd) -> _LegJets:
        """Leg k's bodies at the box (r, R, v, w) and its coordinates (psi, theta) and rates."""
        leg = self.legs[k]
        K = leg.model._jets(th, thd)
        J = _LegJets()
        z = R[:, 2]
        a = R @ leg.hip
        Ry = R @ _rz(leg.heading + psi)
        Ryp = Ry[:, [0, 2]]                        # planar (x, y) -> world
        kw = -Ry[:, 1]                             # the plane's normal: planar angles turn about it
        wy = w + psid * z
        wz = psid * _cx(w, z)                      # d/dt of z psi_dot, apart from psi_ddot
        ox = self.hip_offset * Ry[:, 0]
        nb = leg.model.nb
        # positions from the hip point
        bb = np.empty((nb + 1, 3))
        bb[0] = Ry @ self.yoke_com
        bb[1:] = ox + K.P[:, :2] @ Ryp.T
        RV = np.einsum("ij,bjk->bik", Ryp, K.J[:, :2, :])       # (nb, 3, 2)
        g = K.J[:, 2, :]                                       # angle jacobians (nb, 2)
        phid = g @ thd
        rhod = np.einsum("bij,j->bi", RV, thd)                 # R_y rho_dot
        J.a, J.z = a, z
        J.X = (r + a) + bb
        J.xd = v + _cx(w, a + bb) + psid * _cx(z, bb)
        J.xd[1:] += rhod
        J.m = self._leg_m[k]
        # linear partials and bias
        J.Lb = np.zeros((nb + 1, 3, 6))
        J.Lb[:, :, :3] = np.eye(3)
        for i in range(nb + 1):
            J.Lb[i, :, 3:] = -_skew(a + bb[i])
        J.Ll = np.zeros((nb + 1, 3, 3))
        J.Ll[:, :, 0] = _cx(z, bb)
        J.Ll[1:, :, 1:] = RV
        J.cl = _cx(w, _cx(w, a)) + _cx(wz, bb) + _cx(wy, _cx(wy, bb))
        J.cl[1:] += 2.0 * _cx(wy, rhod) + K.b[:, :2] @ Ryp.T
        # angular velocities, partials and bias
        J.w = np.tile(wy, (nb + 1, 1))
        J.w[1:] += phid[:, None] * kw
        J.Wl = np.zeros((nb + 1, 3, 3))
        J.Wl[:, :, 0] = z
        J.Wl[1:, :, 1:] = kw[None, :, None] * g[:, None, :]
        J.ca = np.tile(wz, (nb + 1, 1))
        J.ca[1:] += K.b[:, 2][:, None] * kw + phid[:, None] * _cx(wy, kw)
        # world inertias: the yoke in its frame, a bar in (u, n, k)
        J.Iw = np.empty((nb + 1, 3, 3))
        I = self._leg_I[k]
        J.Iw[0] = Ry @ np.diag(I[0]) @ Ry.T
        for i in range(nb):
            ph = K.P[i, 2]
            Q = np.column_stack([Ryp @ u(ph), Ryp @ n(ph), kw])
            J.Iw[i + 1] = (Q * I[i + 1]) @ Q.T
        # the foot
        fp, fV, fb = K.foot
        J.bf = ox + Ryp @ fp
        RVf = Ryp @ fV
        J.G = np.column_stack([_cx(z, J.bf), RVf])
        J.cf = (_cx(w, _cx(w, a)) + _cx(wz, J.bf) + _cx(wy, _cx(wy, J.bf)) + 2.0 * _cx(wy, RVf @ thd)
                + Ryp @ fb)
        J.l, J.lg = K.l, K.lg
        J.theta, J.psi = np.asarray(th, float), psi
        return J

    def _at_rest(self, k, r, R, psi, th) -> _LegJets:
        return self._leg(k, r, R, np.zeros(3), np.zeros(3), psi, 0.0, th, np.zeros(2))

    def leg_coordinates(self, k, r, R, foot) -> tuple:
        """Leg k's (psi, theta) that put its foot at ``foot`` (world) on the box (r, R): psi in
        closed form (the plane through the hip axis and the foot), theta by the leg's planar
        inverse kinematics (the stand's branch)."""
        leg = self.legs[k]
        d = R.T @ (np.asarray(foot, float) - r) - leg.hip
        psi = _wrap(math.atan2(d[1], d[0]) - leg.heading)
        if abs(psi) > math.pi / 2:
            raise ReferenceError(f"leg {leg.name}: its foot behind the hip axis")
        target = np.array([math.hypot(d[0], d[1]) - self.hip_offset, d[2]])
        return psi, leg.model.theta_from_foot(target)

    def _stuck_leg(self, k, r, R, v, w, foot):
        """Leg k with its foot stuck at ``foot``: its jets and E, e with
        (psi, theta)_dot = E u_box, (psi, theta)_ddot = E u_box_dot + e."""
        psi, th = self.leg_coordinates(k, r, R, foot)
        J0 = self._leg(k, r, R, np.zeros(3), np.zeros(3), psi, 0.0, th, np.zeros(2))
        Lbf = np.hstack([np.eye(3), -_skew(J0.a + J0.bf)])
        Ginv = np.linalg.inv(J0.G)
        E = -Ginv @ Lbf
        rates = E @ np.concatenate([v, w])
        J = self._leg(k, r, R, v, w, psi, rates[0], th, rates[1:])
        e = -Ginv @ J.cf
        return J, E, e, rates

    # ------------------------------------------------------ kinematics
    def kinematics(self, pose) -> dict:
        """At a pose (legsim.Hexapod's keys): feet (6, 3) and the centre of mass (3) (world),
        each leg's theta (6, 2) and its lengths (6, 2)."""
        r = np.asarray(pose["box_m"], float)
        R = quat_matrix(pose["box_quat"])
        th = self._thetas(pose)
        feet, mx = np.empty((LEGS, 3)), self.box_mass * r
        for k in range(LEGS):
            J = self._at_rest(k, r, R, float(pose["rowing_rad"][k]), th[k])
            feet[k] = r + J.a + J.bf
            mx = mx + J.m @ J.X
        return {"foot_m": feet, "com_m": mx / self.mass, "theta": th,
                "length_m": np.array([self.legs[k].model.lengths(th[k]) for k in range(LEGS)])}

    # ---------------------------------------------------------- statics
    def stance_forces(self, feet, com, box_point, box_force=None) -> np.ndarray:
        """The least sum of squares of the feet's forces (n, 3) balancing the weight at ``com``
        and ``box_force`` at ``box_point``: f_k = lambda + mu x e_k about the feet's centroid."""
        p = np.asarray(feet, float).reshape(-1, 3)
        if len(p) < 3:
            raise NoEquilibriumError("fewer than three feet")
        W = self.mass * self.gravity
        Fb = np.zeros(3) if box_force is None else np.asarray(box_force, float)
        pc = p.mean(axis=0)
        e = p - pc
        lam = -(W + Fb) / len(p)
        Jf = np.sum(np.einsum("ki,ki->k", e, e)) * np.eye(3) - e.T @ e
        moment = _cx(np.asarray(com, float) - pc, W) + _cx(np.asarray(box_point, float) - pc, Fb)
        s = np.linalg.svd(Jf, compute_uv=False)
        if s[-1] <= 1e-12 * s[0]:
            raise NoEquilibriumError("the feet on one line")
        mu = np.linalg.solve(Jf, -moment)
        return lam + _cx(mu, e)

    def statics(self, pose, stance=range(LEGS), box_force_n=None) -> dict:
        """The robot standing at ``pose`` on the feet of ``stance`` (leg indices), ``box_force_n``
        (N, world) at the box's centre: the stance forces by the least sum of squares, then each
        leg's actuator forces and rowing torque by virtual work in its coordinates (psi, theta)
        with the box held. Returns legsim.Hexapod.statics' keys (not the margin)."""
        stance = sorted(int(k) for k in stance)
        r = np.asarray(pose["box_m"], float)
        R = quat_matrix(pose["box_quat"])
        th = self._thetas(pose)
        jets = [self._at_rest(k, r, R, float(pose["rowing_rad"][k]), th[k]) for k in range(LEGS)]
        feet = np.array([r + J.a + J.bf for J in jets])
        com = (self.box_mass * r + sum(J.m @ J.X for J in jets)) / self.mass
        f = np.zeros((LEGS, 3))
        f[stance] = self.stance_forces(feet[stance], com, r, box_force_n)
        if np.any(f[stance] @ -self.gravity <= 0):
            raise NoEquilibriumError("a stance foot would pull")
        Fa, tau = np.zeros((LEGS, 2)), np.zeros(LEGS)
        for k, J in enumerate(jets):
            # generalised forces on (psi, theta) of the weights and the foot's force
            Qg = np.einsum("b,bji,j->i", J.m, J.Ll, self.gravity) + J.G.T @ f[k]
            tau[k] = -Qg[0]
            Fa[k] = np.linalg.solve(J.lg.T, -Qg[1:])
        return {"com_m": com, "foot_m": feet, "foot_force_n": f, "actuator_force_n": Fa, "rowing_torque_nm": tau}

    # --------------------------------------------------------- dynamics
    def _system(self, r, R, v, w, swing_q, swing_qd, stance, feet, Fa, tau, Fbox):
        """All the bodies at one state: (M, rhs, pieces) of M u_dot = rhs, u = (v, omega, each free
        leg's (psi_dot, theta_dot) in leg order)."""
        free = [k for k in range(LEGS) if k not in stance]
        nu = 6 + 3 * len(free)
        M = np.zeros((nu, nu))
        rhs = np.zeros(nu)
        # the box
        Ib = (R * self.box_inertia) @ R.T
        M[:3, :3] += self.box_mass * np.eye(3)
        M[3:6, 3:6] += Ib
        rhs[:3] += self.box_mass * self.gravity + Fbox
        rhs[3:6] -= _cx(w, Ib @ w)
        legs = {}
        for k in range(LEGS):
            if k in stance:
                J, E, e, rates = self._stuck_leg(k, r, R, v, w, feet[k])
                # as functions of u: (Lb + Ll E) u_dot + (cl + Ll e)
                Al = J.Lb + np.einsum("bij,jk->bik", J.Ll, E)
                cl = J.cl + np.einsum("bij,j->bi", J.Ll, e)
                Aw = np.einsum("bij,jk->bik", J.Wl, E)
                Aw[:, :, 3:] += np.eye(3)
                ca = J.ca + np.einsum("bij,j->bi", J.Wl, e)
                cols = slice(0, 6)
                dq = E                      # d(psi, theta)/du on the box's columns
                legs[k] = (J, E, e, rates)
            else:
                i = free.index(k)
                s = 6 + 3 * i
                J = self._leg(k, r, R, v, w, swing_q[i, 0], swing_qd[i, 0], swing_q[i, 1:], swing_qd[i, 1:])
                Al = np.concatenate([J.Lb, J.Ll], axis=2)
                Aw = np.concatenate([np.zeros_like(J.Lb), J.Wl], axis=2)
                Aw[:, :, 3:6] += np.eye(3)
                cl, ca = J.cl, J.ca
                cols = np.r_[0:6, s:s + 3]
                dq = np.zeros((3, 9))
                dq[:, 6:] = np.eye(3)
                legs[k] = (J, None, None, None)
            Mk = (np.einsum("b,bik,bil->kl", J.m, Al, Al) + np.einsum("bik,bij,bjl->kl", Aw, J.Iw, Aw))
            fl = J.m[:, None] * (self.gravity[None, :] - cl)
            fw = -np.einsum("bij,bj->bi", J.Iw, ca) - _cx(J.w, np.einsum("bij,bj->bi", J.Iw, J.w))
            rk = np.einsum("bik,bi->k", Al, fl) + np.einsum("bik,bi->k", Aw, fw)
            # the actuators (F dl, l = l(theta)) and the rowing torque (tau dpsi)
            rk += dq[1:].T @ (J.lg.T @ Fa[k]) + dq[0] * tau[k]
            if isinstance(cols, slice):
                M[cols, cols] += Mk
                rhs[cols] += rk
            else:
                M[np.ix_(cols, cols)] += Mk
                rhs[cols] += rk
        return M, rhs, legs, free

    def _unpack(self, y, nfree):
        r = y[0:3]
        qb = y[3:7]
        nq = 7 + 3 * nfree
        sq = y[7:nq].reshape(nfree, 3)
        v, w = y[nq:nq + 3], y[nq + 3:nq + 6]
        sqd = y[nq + 6:].reshape(nfree, 3)
        return r, qb, sq, v, w, sqd

    def accelerations(self, y, stance, feet, Fa, tau, Fbox=None):
        """u_dot at the state y (simulate's layout, see initial_state) with the feet of stance
        stuck at feet (6, 3), and the pieces for the outputs."""
        Fbox = np.zeros(3) if Fbox is None else np.asarray(Fbox, float)
        nfree = LEGS - len(stance)
        r, qb, sq, v, w, sqd = self._unpack(y, nfree)
        R = quat_matrix(qb)
        M, rhs, legs, free = self._system(r, R, v, w, sq, sqd, stance, feet, Fa, tau, Fbox)
        return np.linalg.solve(M, rhs), legs, free

    def multiplier_accelerations(self, y, stance, feet, Fa, tau, Fbox=None):
        """The same state's accelerations the other way: every leg free (24 coordinates), each
        stuck foot's acceleration held at zero by a multiplier, its ground force:
        [M -C^T; C 0] (u_dot, f) = (rhs, -c_f), C = [I, -(a + b_f)^, G] its rows. Returns
        (u_dot: v, omega, then every leg's (psi, theta)_ddot (24,), f (6, 3)); a check of the
        minimal coordinates' elimination and ground forces."""
        stance = tuple(sorted(stance))
        Fbox = np.zeros(3) if Fbox is None else np.asarray(Fbox, float)
        nfree = LEGS - len(stance)
        r, qb, sq, v, w, sqd = self._unpack(y, nfree)
        R = quat_matrix(qb)
        q_all, qd_all = np.zeros((LEGS, 3)), np.zeros((LEGS, 3))
        free = [k for k in range(LEGS) if k not in stance]
        for k in range(LEGS):
            if k in stance:
                J, E, e, rates = self._stuck_leg(k, r, R, v, w, feet[k])
                q_all[k], qd_all[k] = [J.psi, *J.theta], rates
            else:
                q_all[k], qd_all[k] = sq[free.index(k)], sqd[free.index(k)]
        M, rhs, legs, _ = self._system(r, R, v, w, q_all, qd_all, (), feet, Fa, tau, Fbox)
        nu, nc = len(rhs), 3 * len(stance)
        C, cb = np.zeros((nc, nu)), np.zeros(nc)
        for i, k in enumerate(stance):
            J = legs[k][0]
            C[3 * i:3 * i + 3, :6] = np.hstack([np.eye(3), -_skew(J.a + J.bf)])
            C[3 * i:3 * i + 3, 6 + 3 * k:9 + 3 * k] = J.G
            cb[3 * i:3 * i + 3] = -J.cf
        K = np.block([[M, -C.T], [C, np.zeros((nc, nc))]])
        x = np.linalg.solve(K, np.concatenate([rhs, cb]))
        f = np.zeros((LEGS, 3))
        f[list(stance)] = x[nu:].reshape(-1, 3)
        return x[:nu], f

    def evaluate(self, y, stance, feet, Fa, tau, Fbox=None) -> dict:
        """Everything simulate reports at one state y (initial_state's layout): psi (6), theta
        (6, 2), l (6, 2), feet (6, 3), f (6, 3) the stuck feet's ground forces, qdd (6, 3) every
        leg's (psi, theta)_ddot, ud (u_dot), kinetic, potential, com, com_a, H (about the centre
        of mass), r, q, v, w."""
        stance = tuple(sorted(stance))
        Fbox = np.zeros(3) if Fbox is None else np.asarray(Fbox, float)
        nfree = LEGS - len(stance)
        r, qb, sq, v, w, sqd = self._unpack(y, nfree)
        R = quat_matrix(qb)
        ud, legs, free = self.accelerations(y, stance, feet, Fa, tau, Fbox)
        out = {"psi": np.zeros(LEGS), "theta": np.zeros((LEGS, 2)), "l": np.zeros((LEGS, 2)),
               "feet": np.zeros((LEGS, 3)), "f": np.zeros((LEGS, 3)), "qdd": np.zeros((LEGS, 3))}
        kin = 0.5 * self.box_mass * v @ v + 0.5 * w @ ((R * self.box_inertia) @ R.T) @ w
        pot = -self.box_mass * self.gravity @ r - Fbox @ r
        mx = self.box_mass * r
        ma = self.box_mass * ud[:3]
        mv = self.box_mass * v
        H = self.box_mass * _cx(r, v) + (R * self.box_inertia) @ R.T @ w   # about the origin
        for k in range(LEGS):
            J, E, e, rates = legs[k]
            if E is None:
                s = 6 + 3 * free.index(k)
                qdd = ud[s:s + 3]
            else:
                qdd = E @ ud[:6] + e
            out["qdd"][k] = qdd
            # the bodies' accelerations
            alin = np.einsum("bij,j->bi", J.Lb, ud[:6]) + np.einsum("bij,j->bi", J.Ll, qdd) + J.cl
            aang = ud[3:6] + np.einsum("bij,j->bi", J.Wl, qdd) + J.ca
            if E is not None:
                # the ground's force from the leg's own equations: G^T f = A_leg^T (M a - applied) - Q
                Iw_w = np.einsum("bij,bj->bi", J.Iw, J.w)
                res = (np.einsum("bik,bi->k", J.Ll, J.m[:, None] * (alin - self.gravity))
                       + np.einsum("bik,bi->k", J.Wl, np.einsum("bij,bj->bi", J.Iw, aang) + _cx(J.w, Iw_w)))
                res -= np.concatenate([[tau[k]], J.lg.T @ Fa[k]])
                out["f"][k] = np.linalg.solve(J.G.T, res)
            out["psi"][k], out["theta"][k], out["l"][k] = J.psi, J.theta, J.l
            out["feet"][k] = r + J.a + J.bf
            kin += 0.5 * np.einsum("b,bi,bi->", J.m, J.xd, J.xd) + 0.5 * np.einsum("bi,bij,bj->", J.w, J.Iw, J.w)
            pot -= J.m @ (J.X @ self.gravity) + Fa[k] @ J.l + tau[k] * J.psi
            mx = mx + J.m @ J.X
            ma = ma + J.m @ alin
            mv = mv + J.m @ J.xd
            H = H + np.einsum("b,bi->i", J.m, _cx(J.X, J.xd)) + np.einsum("bij,bj->i", J.Iw, J.w)
        c = mx / self.mass
        out.update(kinetic=kin, potential=pot, com=c, com_a=ma / self.mass, H=H - _cx(c, mv), ud=ud, r=r,
                   q=qb / np.linalg.norm(qb),
                   v=v, w=w)
        return out

    def initial_state(self, pose, stance=(), box_v=(0, 0, 0, 0, 0, 0), rates=None):
        """(y0, feet): simulate's state y = (r, quaternion, each free leg's (psi, theta), v, omega,
        their rates) at ``pose`` (legsim.Hexapod's keys) with the box moving at
        ``box_v`` (v, omega, world), the free legs at ``rates`` ((6, 3): psi_dot, theta_dot;
        default rest); the stuck feet's places (6, 3) (world; where the pose puts them)."""
        stance = tuple(sorted(int(k) for k in stance))
        kin = self.kinematics(pose)
        th = kin["theta"]
        free = [k for k in range(LEGS) if k not in stance]
        rates = np.zeros((LEGS, 3)) if rates is None else np.asarray(rates, float)
        q = np.asarray(pose["box_quat"], float)
        sq = [[float(pose["rowing_rad"][k]), *th[k]] for k in free]
        y0 = np.concatenate([np.asarray(pose["box_m"], float), q / np.linalg.norm(q), np.ravel(sq),
                             np.asarray(box_v, float), np.ravel(rates[free])])
        return y0, kin["foot_m"]

    def simulate(self, pose0, stance, actuator_force_n, rowing_torque_nm, t_end, t_eval=None, *,
                 box_force_n=None, box_v0=(0, 0, 0, 0, 0, 0), rates0=None, rtol=1e-12, atol=1e-12,
                 method="DOP853") -> HexapodResult:
        """The robot from ``pose0`` (legsim.Hexapod's pose keys) with the feet of ``stance``
        (leg indices) stuck where the pose puts them, the others free; constant
        ``actuator_force_n`` (6, 2) N (> 0 extends), ``rowing_torque_nm`` (6,) N m (on the yoke
        about the hip axis, its reaction on the box), ``box_force_n`` (3,) N at the box's centre,
        gravity; the box moving at ``box_v0`` (v, omega world) and the free legs at ``rates0``
        ((6, 3) psi_dot, phi3_dot, phi6_dot), default rest. DOP853 to ``t_end`` (s), sampled at
        ``t_eval`` (default the steps)."""
        stance = tuple(sorted(int(k) for k in stance))
        Fa = np.asarray(actuator_force_n, float).reshape(LEGS, 2)
        tau = np.asarray(rowing_torque_nm, float).reshape(LEGS)
        Fbox = np.zeros(3) if box_force_n is None else np.asarray(box_force_n, float)
        y0, feet = self.initial_state(pose0, stance, box_v0, rates0)
        nfree = LEGS - len(stance)
        nq = 7 + 3 * nfree
        nfev = [0]

        def rhs(t, y):
            nfev[0] += 1
            r, qb, sq, v, w, sqd = self._unpack(y, nfree)
            ud, _, _ = self.accelerations(y, stance, feet, Fa, tau, Fbox)
            wq = np.array([0.0, *w])
            qd = 0.5 * _qmul(wq, qb)               # world angular velocity: q_dot = 1/2 (0, w) q
            return np.concatenate([v, qd, sqd.ravel(), ud])

        sol = solve_ivp(rhs, (0.0, float(t_end)), y0, method=method, rtol=rtol, atol=atol,
                        t_eval=None if t_eval is None else np.asarray(t_eval, float), dense_output=False)
        if sol.status != 0:
            raise ReferenceError(f"integration failed: {sol.message}")
        N = len(sol.t)
        res = HexapodResult(sol.t, np.zeros((N, 7)), np.zeros((N, 6)), np.zeros((N, LEGS)), np.zeros((N, LEGS, 2)),
                            np.zeros((N, LEGS, 2)), np.zeros((N, LEGS, 3)), np.zeros((N, LEGS, 3)), np.zeros((N, 3)),
                            np.zeros(N), np.zeros(N), np.zeros(N), stance, np.zeros((N, 3)), np.zeros((N, 3)),
                            nfev[0])
        for i in range(N):
            o = self.evaluate(sol.y[:, i], stance, feet, Fa, tau, Fbox)
            res.box_q[i] = np.concatenate([o["r"], o["q"]])
            res.box_v[i] = np.concatenate([o["v"], o["w"]])
            res.rowing[i], res.theta[i], res.lengths[i] = o["psi"], o["theta"], o["l"]
            res.feet[i], res.foot_force[i], res.com[i] = o["feet"], o["f"], o["com"]
            res.kinetic[i], res.potential[i] = o["kinetic"], o["potential"]
            res.com_accel[i], res.angular_momentum[i] = o["com_a"], o["H"]
        res.energy = res.kinetic + res.potential
        return res


def _qmul(a, b) -> np.ndarray:
    """Quaternion product a b, (w, x, y, z)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw])
