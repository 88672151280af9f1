"""One leg of models/leg.toml on a rowing hip yoke, on a fixed box, in two spatial formulations.

(a) absolute: every body (yoke, six bars) has position + unit quaternion (7 numbers) and
    velocity (v world, omega body frame: 6 numbers); 39 rows on 42 velocity coordinates, 3
    degrees of freedom, in two sets: "tree" (the yoke's revolute about the vertical, 5 rows;
    the spanning tree's joints as 3D joints, 5 rows each; the two loop-closing joints by their
    2 in-plane rows) and "plane" (the yoke's 5 rows, each bar held in the yoke's plane by 3,
    the leg's 16 planar rows along the yoke's in-plane axes). RK4 on the rotation group (RKMK).
(b) relative (semi-recursive): z = (psi, phi1, s1, phi3, phi4, s2, theta6): the yoke angle, the
    pinned bars' angles in the yoke's plane, the actuators' extensions, the shank's angle on
    the upper rod; the two cut joints (C_rod_thigh, D) give 4 loop-closure rows.
(c) reference: minimal coordinates (psi, phi3, phi6), the leg's other bars in closed form,
    integrated by scipy's DOP853 at rtol = atol = 1e-12.

The actuators and the rowing motor are forces (constant here), not driven coordinates.
Usage: python spatial_leg.py --table      (the figures of docs/design/spatial.md)
       python spatial_leg.py --planar     (the planar check against the legsim library of
                                           $LEGSIM_MAIN, default this tree, if built)
"""
from __future__ import annotations

import argparse
import math
import sys
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
LEG_TOML = ROOT / "models" / "leg.toml"
G = 9.81

# ASSUMPTIONS (the paper gives no yoke or hip numbers): a 1.0 kg yoke whose centre of mass is
# 0.03 m out from the vertical hip axis, principal inertias (0.004, 0.006, 0.005) kg m^2 in the
# yoke frame (x out along the leg's plane, z up); the leg's frame point B sits 0.08 m out from
# the hip axis, the leg's plane contains the axis. The bars' inertia about their own axis is that
# of a tube of radius 0.025 m (m r^2 / 2); about the two transverse axes m L^2 / 12 (leg.toml's
# in-plane value, so the planar dynamics are unchanged).
YOKE_MASS = 1.0
YOKE_COM = np.array([0.03, 0.0, 0.0])
YOKE_INERTIA = np.array([0.004, 0.006, 0.005])
HIP_OFFSET = 0.08
BAR_RADIUS = 0.025


# ---------------------------------------------------------------------------------------------
# the leg's data
class Leg:
    """leg.toml's bodies, frame points, joints and stand pose, as the planar model reads them."""

    def __init__(self, path: Path = LEG_TOML):
        d = tomllib.loads(Path(path).read_text())
        self.L = np.array([b["length"] for b in d["body"]])
        self.m = np.array([b["mass"] for b in d["body"]])
        self.J = np.array([b.get("inertia", b["mass"] * b["length"]**2 / 12.0) for b in d["body"]])
        self.frame = {k: np.array(v, float) for k, v in d["frame"].items()}
        self.joints = []
        for j in d["joint"]:
            kind = j["kind"]
            if kind == "revolute_to_frame":
                b = j["body"] - 1
                self.joints.append((j["name"], kind, b, self.point(b, j["end"], j), j["point"]))
            elif kind == "revolute":
                i, k = (x - 1 for x in j["bodies"])
                self.joints.append((j["name"], kind, i, self.point(i, j["ends"][0], j),
                                    k, self.point(k, j["ends"][1], j)))
            elif kind == "prismatic":
                i, k = (x - 1 for x in j["bodies"])
                self.joints.append((j["name"], kind, i, k))
            else:
                raise ValueError(kind)
        self.actuators = []
        joint_bodies = {j["name"]: j.get("bodies") for j in d["joint"]}
        for a in d["actuator"]:
            cyl, rod = (x - 1 for x in joint_bodies[a["joint"]])
            self.actuators.append((a["name"], cyl, rod))
        self.foot = (d["foot"]["body"] - 1, self.point(d["foot"]["body"] - 1, d["foot"]["end"], {}))
        st = d["pose"]["stand"]
        self.stand_guess = np.array(st["guess"], float)
        self.stand_drive = (st["phi3"], st["phi6"])
        self.D_at = None
        for j in d["joint"]:
            if j["name"] == "D":
                self.D_at = np.array(j["at"], float)

    def point(self, b, end, j):
        if end == "proximal":
            return np.array([-self.L[b] / 2, 0.0])
        if end == "distal":
            return np.array([self.L[b] / 2, 0.0])
        return np.array(j["at"], float)

    def actuator_length(self, a, pose):
        """planar: the proximal end of the cylinder to the distal end of the rod."""
        _, c, r = self.actuators[a]
        pc = planar_point(pose[c], [-self.L[c] / 2, 0])
        pr = planar_point(pose[r], [self.L[r] / 2, 0])
        return float(np.linalg.norm(pr - pc))


def u_of(phi):
    return np.array([math.sin(phi), -math.cos(phi)])


def n_of(phi):
    return np.array([math.cos(phi), math.sin(phi)])


def planar_point(qb, s):
    return qb[:2] + s[0] * u_of(qb[2]) + s[1] * n_of(qb[2])


def planar_closed_form(leg: Leg, phi3, phi6):
    """The six bars' planar poses (x, y, phi) from the thigh and shank angles."""
    L = leg.L
    A, B = leg.frame["A"], leg.frame["B"]
    C = B + L[2] * u_of(phi3)
    e = C - A
    u1 = e / np.linalg.norm(e)
    phi1 = math.atan2(u1[0], -u1[1])
    u6 = u_of(phi6)
    r6 = C + L[5] / 2 * u6
    D = r6 + leg.D_at[0] * u6 + leg.D_at[1] * n_of(phi6)
    e4 = D - B
    u4 = e4 / np.linalg.norm(e4)
    phi4 = math.atan2(u4[0], -u4[1])
    return np.array([
        [*(A + L[0] / 2 * u1), phi1],
        [*(C - L[1] / 2 * u1), phi1],
        [*(B + L[2] / 2 * u_of(phi3)), phi3],
        [*(B + L[3] / 2 * u4), phi4],
        [*(D - L[4] / 2 * u4), phi4],
        [*r6, phi6]])


# ---------------------------------------------------------------------------------------------
# rotations
def cross(a, b):
    """a x b of two 3-vectors (numpy's cross is slow on single vectors)"""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def hat(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def quat_exp(theta):
    """the unit quaternion of the rotation vector theta (exp(theta^ / 2))."""
    t = math.sqrt(theta @ theta)
    if t < 1e-4:
        s = 0.5 - t * t / 48.0
        c = 1.0 - t * t / 8.0 + t**4 / 384.0
    else:
        s = math.sin(t / 2) / t
        c = math.cos(t / 2)
    return np.array([c, s * theta[0], s * theta[1], s * theta[2]])


def quat_matrix(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def matrix_quat(R):
    w = math.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    if w > 0.1:
        return np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w),
                         (R[1, 0] - R[0, 1]) / (4 * w)])
    raise ValueError("rotation too far from identity for this prototype's conversion")


def dexp_inv_right(theta, w):
    """theta' for R = R0 exp(theta^) with R' = R w^ (w in the body frame): Jr(theta)^-1 w."""
    t2 = theta @ theta
    t = math.sqrt(t2)
    if t < 1e-3:
        c = 1.0 / 12.0 + t2 / 720.0
    else:
        c = 1.0 / t2 - (1 + math.cos(t)) / (2 * t * math.sin(t))
    tw = cross(theta, w)
    return w + 0.5 * tw + c * cross(theta, tw)


def rot_z(psi):
    c, s = math.cos(psi), math.sin(psi)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


# planar (x, y, z) -> yoke frame: x out, y up, the plane's normal -y_yoke
PLANE = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])   # columns: e1, e3, -e2
BAR_AXES = np.array([[0, 1.0, 0], [-1.0, 0, 0], [0, 0, 1.0]])  # Rz(-pi/2): body (u, n, k)


def bar_rotation(psi, phi):
    """a bar's world rotation: its body axes (u, n, k) in the plane turned by psi."""
    return rot_z(psi) @ PLANE @ rot_z(phi) @ BAR_AXES


def hip_point(psi, xy):
    """a planar point of the leg (frame coordinates) in the world, the yoke at angle psi."""
    return rot_z(psi) @ (np.array([HIP_OFFSET, 0.0, 0.0]) + PLANE @ np.array([xy[0], xy[1], 0.0]))


def bar_inertia(leg: Leg, b):
    return np.array([leg.m[b] * BAR_RADIUS**2 / 2, leg.J[b], leg.J[b]])


# ---------------------------------------------------------------------------------------------
# (a) absolute spatial coordinates
class Absolute:
    """Bodies 0 (yoke), 1..6 (the bars); q per body (r, quaternion), v per body (v, omega_body)."""

    ROWS = ("plane", "tree", "full3d")

    def __init__(self, leg: Leg, F=(50.0, 0.0), tau=1.0, rows="tree", group=True):
        """rows: "plane": each bar held in the yoke's plane (3 rows) and the planar joints' rows
        along the yoke's in-plane axes; "tree": the spanning tree's joints as 3D joints (5 rows)
        and the two cut joints' 2 in-plane rows along a body's own axes; "full3d": every joint a
        3D joint (redundant: 3 rows per closed loop)."""
        assert rows in self.ROWS
        self.leg, self.F, self.tau, self.variant = leg, np.array(F, float), tau, rows
        self.group = group      # RK4 on the group (True) or on the quaternions' components
        self.nb = 7
        self.mass = np.concatenate([[YOKE_MASS], leg.m])
        self.inertia = np.vstack([YOKE_INERTIA] + [bar_inertia(leg, b) for b in range(6)])
        self.Minv = np.concatenate([np.concatenate([[1 / m] * 3, 1 / I])
                                    for m, I in zip(self.mass, self.inertia)])
        self.nv = 6 * self.nb
        self.s_axis = -YOKE_COM                       # the hip axis point in the yoke's frame
        self.s_origin = np.array([HIP_OFFSET, 0, 0]) - YOKE_COM  # the leg's frame point B
        self._build_rows()
        self.m_rows = len(self.rows)

    # expressions: a point (r + R s) or a vector (R c) of a body, or a constant (body -1)
    def _build_rows(self):
        leg = self.leg
        P = lambda b, s: ("p", b, np.asarray(s, float))        # noqa: E731
        V = lambda b, c: ("v", b, np.asarray(c, float))        # noqa: E731
        K = lambda c: ("v", -1, np.asarray(c, float))          # noqa: E731
        e1, e2, e3 = np.eye(3)
        rows = []
        # the yoke's revolute to the box about the vertical through the origin
        for e in (e1, e2, e3):
            rows.append(("hip", (P(0, self.s_axis), None), K(e)))
        rows.append(("hip", (V(0, e3), None), K(e1)))
        rows.append(("hip", (V(0, e3), None), K(e2)))
        pa, pc, pk = V(0, PLANE[:, 0]), V(0, PLANE[:, 1]), V(0, PLANE[:, 2])
        origin = P(0, self.s_origin)
        if self.variant != "plane":
            cut = ("C_rod_thigh", "D") if self.variant == "tree" else ()
            self.rows = rows + self._rows_3d(P, V, K, cut)
            return
        # each bar in the yoke's plane: its centre on it, its k axis along the plane's normal
        for b in range(1, 7):
            rows.append(("plane", (P(b, [0, 0, 0]), origin), pk))
            rows.append(("plane", (V(b, e3), None), pa))
            rows.append(("plane", (V(b, e3), None), pc))
        # the leg's planar joints, in the yoke's plane
        for j in leg.joints:
            kind = j[1]
            if kind == "revolute_to_frame":
                _, _, b, s, fp = j
                f = self.s_origin + PLANE @ np.array([*leg.frame[fp], 0.0])
                x = (P(b + 1, [*s, 0]), P(0, f))
            elif kind == "revolute":
                _, _, i, si, k, sk = j
                x = (P(i + 1, [*si, 0]), P(k + 1, [*sk, 0]))
            if kind in ("revolute_to_frame", "revolute"):
                rows.append((j[0], x, pa))
                rows.append((j[0], x, pc))
            else:   # prismatic: u_i . n_k = sin(phi_i - phi_k) = 0; k's centre on i's axis
                _, _, i, k = j
                rows.append((j[0], (V(i + 1, e1), None), V(k + 1, e2)))
                rows.append((j[0], (P(k + 1, [0, 0, 0]), P(i + 1, [0, 0, 0])), V(i + 1, e2)))
        self.rows = rows

    def _rows_3d(self, P, V, K, cut):
        """the joints as 3D joints (revolute: 3 + 2 rows, prismatic: 3 + 2), the joints in `cut`
        by their 2 rows in the plane of their second body's axes (u, n)"""
        leg, rows = self.leg, []
        e1, e2, e3 = np.eye(3)
        kw = (V(0, PLANE[:, 2]),)
        for j in leg.joints:
            kind = j[1]
            if kind in ("revolute_to_frame", "revolute"):
                if kind == "revolute_to_frame":
                    _, _, b, s, fp = j
                    f = self.s_origin + PLANE @ np.array([*leg.frame[fp], 0.0])
                    x, i, other = (P(b + 1, [*s, 0]), P(0, f)), b + 1, kw[0]
                else:
                    _, _, i, si, k, sk = j
                    x, i, other = (P(i + 1, [*si, 0]), P(k + 1, [*sk, 0])), i + 1, None
                if j[0] in cut:
                    rows.append((j[0], x, V(k + 1, e1)))
                    rows.append((j[0], x, V(k + 1, e2)))
                    continue
                for e in (e1, e2, e3):
                    rows.append((j[0], x, K(e)))
                ax = (V(i, e3), None)
                if other is None:
                    rows.append((j[0], ax, V(k + 1, e1)))
                    rows.append((j[0], ax, V(k + 1, e2)))
                else:
                    rows.append((j[0], ax, V(0, PLANE[:, 0])))
                    rows.append((j[0], ax, V(0, PLANE[:, 1])))
            else:
                _, _, i, k = j
                rows.append((j[0], (V(i + 1, e1), None), V(k + 1, e2)))
                rows.append((j[0], (V(i + 1, e1), None), V(k + 1, e3)))
                rows.append((j[0], (V(i + 1, e2), None), V(k + 1, e3)))
                x = (P(k + 1, [0, 0, 0]), P(i + 1, [0, 0, 0]))
                rows.append((j[0], x, V(i + 1, e2)))
                rows.append((j[0], x, V(i + 1, e3)))
        return rows

    def _expr(self, ex, st):
        """value, Jacobian {body: 3 x 6}, velocity, the acceleration's velocity-quadratic part"""
        kind, b, c = ex
        if b < 0:
            z = np.zeros(3)
            return c, {}, z, z
        R, w = st["R"][b], st["w"][b]
        wc = cross(w, c)
        if kind == "p":
            val = st["r"][b] + R @ c
            jac = np.hstack([np.eye(3), -R @ hat(c)])
            vel = st["v"][b] + R @ wc
        else:
            val = R @ c
            jac = np.hstack([np.zeros((3, 3)), -R @ hat(c)])
            vel = R @ wc
        return val, {b: jac}, vel, R @ cross(w, wc)

    def _diff(self, pair, st):
        a = self._expr(pair[0], st)
        if pair[1] is None:
            return a
        b = self._expr(pair[1], st)
        jac = dict(a[1])
        for k, v in b[1].items():
            jac[k] = jac.get(k, 0) - v
        return a[0] - b[0], jac, a[2] - b[2], a[3] - b[3]

    def rows_eval(self, st, need_gamma=True):
        m = len(self.rows)
        phi = np.zeros(m)
        J = np.zeros((m, self.nv))
        gam = np.zeros(m)
        for i, (_, pair, y) in enumerate(self.rows):
            x, jx, vx, ax = self._diff(pair, st)
            yv, jy, vy, ay = self._expr(y, st)
            phi[i] = x @ yv
            for b, jb in jx.items():
                J[i, 6 * b:6 * b + 6] += yv @ jb
            for b, jb in jy.items():
                J[i, 6 * b:6 * b + 6] += x @ jb
            gam[i] = -(ax @ yv + 2 * vx @ vy + x @ ay)
        return phi, J, gam

    def state(self, r, q, v, w):
        return {"r": r, "R": [quat_matrix(qq) for qq in q], "v": v, "w": w}

    def forces(self, st):
        Q = np.zeros(self.nv)
        for b in range(self.nb):
            Q[6 * b + 2] = -self.mass[b] * G
            Ib = self.inertia[b]
            Q[6 * b + 3:6 * b + 6] = -cross(st["w"][b], Ib * st["w"][b])
        Q[3:6] += st["R"][0].T @ np.array([0, 0, self.tau])
        for a, (_, cyl, rod) in enumerate(self.leg.actuators):
            f = self.F[a] * (st["R"][cyl + 1] @ np.array([1.0, 0, 0]))
            Q[6 * (rod + 1):6 * (rod + 1) + 3] += f
            Q[6 * (cyl + 1):6 * (cyl + 1) + 3] -= f
        return Q

    def accel(self, st):
        _, J, gam = self.rows_eval(st)
        Q = self.forces(st)
        JW = J * self.Minv
        A = JW @ J.T
        lam = np.linalg.solve(A, JW @ Q - gam)
        return self.Minv * (Q - J.T @ lam), lam

    @staticmethod
    def config_add(r, q, dv):
        """q (+) dv: positions + dv's linear parts, quaternions times exp of its angular parts."""
        d = dv.reshape(-1, 6)
        return r + d[:, :3], np.array([quat_mul(qq, quat_exp(th)) for qq, th in zip(q, d[:, 3:])])

    def step(self, y, h, normalize=False):
        if not self.group:
            return self.step_components(y, h)
        return self.step_group(y, h, normalize)

    def step_components(self, y, h):
        """classical RK4 on the quaternions' 4 components, q' = q (0, omega) / 2, each stage's
        rotation from q / |q|, and q normalized at the end of the step"""
        r0, q0, v0, w0 = y

        def f(r, q, v, w):
            qn = q / np.linalg.norm(q, axis=1)[:, None]
            st = {"r": r, "R": [quat_matrix(x) for x in qn], "v": v, "w": w}
            a, _ = self.accel(st)
            a = a.reshape(-1, 6)
            qd = np.array([0.5 * quat_mul(q[b], np.r_[0.0, w[b]]) for b in range(self.nb)])
            return v, qd, a[:, :3], a[:, 3:]

        y0 = (r0, q0, v0, w0)
        k1 = f(*y0)
        k2 = f(*(x + h / 2 * k for x, k in zip(y0, k1)))
        k3 = f(*(x + h / 2 * k for x, k in zip(y0, k2)))
        k4 = f(*(x + h * k for x, k in zip(y0, k3)))
        r, q, v, w = (x + h / 6 * (a + 2 * b + 2 * c + d)
                      for x, a, b, c, d in zip(y0, k1, k2, k3, k4))
        q = q / np.linalg.norm(q, axis=1)[:, None]
        return self.project((r, q, v, w))

    def step_group(self, y, h, normalize=False):
        """RK4 on the group (Munthe-Kaas, exact dexp^-1): each body's rotation R0 exp(theta^),
        classical RK4 on (dr, theta, v, omega) from theta = 0, then R0 exp(theta1^)."""
        r0, q0, v0, w0 = y
        R0 = [quat_matrix(qq) for qq in q0]

        def f(dr, th, v, w):
            st = {"r": r0 + dr, "R": [R0[b] @ quat_matrix(quat_exp(th[b])) for b in range(self.nb)],
                  "v": v, "w": w}
            a, _ = self.accel(st)
            a = a.reshape(-1, 6)
            thd = np.array([dexp_inv_right(th[b], w[b]) for b in range(self.nb)])
            return v, thd, a[:, :3], a[:, 3:]

        Z = np.zeros((self.nb, 3))
        k1 = f(Z, Z, v0, w0)
        k2 = f(*(x + h / 2 * k for x, k in zip((Z, Z, v0, w0), k1)))
        k3 = f(*(x + h / 2 * k for x, k in zip((Z, Z, v0, w0), k2)))
        k4 = f(*(x + h * k for x, k in zip((Z, Z, v0, w0), k3)))
        inc = [x + h / 6 * (a + 2 * b + 2 * c + d)
               for x, a, b, c, d in zip((Z, Z, v0, w0), k1, k2, k3, k4)]
        r = r0 + inc[0]
        q = np.array([quat_mul(q0[b], quat_exp(inc[1][b])) for b in range(self.nb)])
        if normalize:
            q /= np.linalg.norm(q, axis=1)[:, None]
        return self.project((r, q, inc[2], inc[3]))

    def project(self, y, tol=1e-13, iters=6):
        """M-weighted Newton onto Phi = 0, then the velocities onto J v = 0."""
        r, q, v, w = y
        for _ in range(iters):
            st = self.state(r, q, v, w)
            phi, J, _ = self.rows_eval(st)
            if np.max(np.abs(phi)) <= tol:
                break
            JW = J * self.Minv
            dv = -JW.T @ np.linalg.solve(JW @ J.T, phi)
            r, q = self.config_add(r, q, dv)
        st = self.state(r, q, v, w)
        _, J, _ = self.rows_eval(st)
        JW = J * self.Minv
        vel = np.hstack([v, w]).reshape(-1)
        vel = vel - JW.T @ np.linalg.solve(JW @ J.T, J @ vel)
        vel = vel.reshape(-1, 6)
        return r, q, vel[:, :3].copy(), vel[:, 3:].copy()

    def initial(self, pose, psi=0.0):
        """the bars' planar poses (x, y, phi) placed in the yoke's plane at angle psi, at rest."""
        Ry = rot_z(psi)
        r = [Ry @ YOKE_COM]
        q = [matrix_quat(Ry)]
        for b in range(6):
            r.append(hip_point(psi, pose[b, :2]))
            q.append(matrix_quat(bar_rotation(psi, pose[b, 2])))
        z = np.zeros((self.nb, 3))
        return np.array(r), np.array(q), z.copy(), z.copy()

    def health(self, y):
        """the Jacobian's smallest singular value, max | |q| - 1 |, max |Phi|"""
        phi, J, _ = self.rows_eval(self.state(*y))
        return (np.linalg.svd(J, compute_uv=False)[-1],
                np.max(np.abs(np.linalg.norm(y[1], axis=1) - 1)),
                np.max(np.abs(phi)))

    def outputs(self, y):
        """psi and the foot in the world"""
        r, q, v, w = y
        R = [quat_matrix(qq) for qq in q]
        psi = math.atan2(R[0][1, 0], R[0][0, 0])
        b, s = self.leg.foot
        foot = r[b + 1] + R[b + 1] @ np.array([*s, 0.0])
        return psi, foot

    def energy(self, y):
        r, q, v, w = y
        T = sum(0.5 * self.mass[b] * v[b] @ v[b] + 0.5 * w[b] @ (self.inertia[b] * w[b])
                for b in range(self.nb))
        V = sum(self.mass[b] * G * r[b][2] for b in range(self.nb))
        R = [quat_matrix(qq) for qq in q]
        work = 0.0
        for a, (_, c, rd) in enumerate(self.leg.actuators):
            pc = r[c + 1] + R[c + 1] @ np.array([-self.leg.L[c] / 2, 0, 0])
            pr = r[rd + 1] + R[rd + 1] @ np.array([self.leg.L[rd] / 2, 0, 0])
            work += self.F[a] * np.linalg.norm(pr - pc)
        return T + V - work


# ---------------------------------------------------------------------------------------------
# second-order time jets: value, gradient in z, first and second time derivative (z'' = 0)
class Jet:
    __slots__ = ("v", "d", "t", "b")

    def __init__(self, v, d, t, b):
        self.v, self.d, self.t, self.b = v, d, t, b

    @staticmethod
    def coord(z, zd, k):
        d = np.zeros(len(z))
        d[k] = 1.0
        return Jet(z[k], d, zd[k], 0.0)

    def _c(self, o):
        return o if isinstance(o, Jet) else Jet(o, 0.0 * self.d, 0.0, 0.0)

    def __add__(self, o):
        o = self._c(o)
        return Jet(self.v + o.v, self.d + o.d, self.t + o.t, self.b + o.b)

    __radd__ = __add__

    def __sub__(self, o):
        o = self._c(o)
        return Jet(self.v - o.v, self.d - o.d, self.t - o.t, self.b - o.b)

    def __rsub__(self, o):
        return self._c(o) - self

    def __neg__(self):
        return Jet(-self.v, -self.d, -self.t, -self.b)

    def __mul__(self, o):
        if not isinstance(o, Jet):
            return Jet(self.v * o, self.d * o, self.t * o, self.b * o)
        return Jet(self.v * o.v, self.d * o.v + self.v * o.d, self.t * o.v + self.v * o.t,
                   self.b * o.v + 2 * self.t * o.t + self.v * o.b)

    __rmul__ = __mul__

    def fn(self, f0, f1, f2):
        return Jet(f0, f1 * self.d, f1 * self.t, f1 * self.b + f2 * self.t * self.t)

    def __truediv__(self, o):
        if not isinstance(o, Jet):
            return self * (1.0 / o)
        return self * o.fn(1 / o.v, -1 / o.v**2, 2 / o.v**3)


def jsin(a):
    s, c = math.sin(a.v), math.cos(a.v)
    return a.fn(s, c, -s)


def jcos(a):
    s, c = math.sin(a.v), math.cos(a.v)
    return a.fn(c, -s, -c)


def jsqrt(a):
    r = math.sqrt(a.v)
    return a.fn(r, 0.5 / r, -0.25 / (r * a.v))


def ju(phi):
    return (jsin(phi), -jcos(phi))


def jn(phi):
    return (jcos(phi), jsin(phi))


def jadd(p, s, u):
    return (p[0] + u[0] * s, p[1] + u[1] * s)


class Bar:
    """a bar's planar pose as jets: centre (x, y), angle, and its unit axis u (given or from phi)"""

    def __init__(self, x, y, phi, u=None, n=None):
        self.x, self.y, self.phi = x, y, phi
        self.u = u if u is not None else ju(phi)
        self.n = n if n is not None else jn(phi)

    def point(self, s):
        return (self.x + self.u[0] * s[0] + self.n[0] * s[1],
                self.y + self.u[1] * s[0] + self.n[1] * s[1])


# ---------------------------------------------------------------------------------------------
# Kane's equations for the yoke + six planar bars, from the bars' planar jets and psi's
class LegInPlane:
    def __init__(self, leg: Leg, F=(50.0, 0.0), tau=1.0):
        self.leg, self.F, self.tau = leg, np.array(F, float), tau
        self.Ib = [bar_inertia(leg, b) for b in range(6)]

    def mass_and_forces(self, psi: Jet, bars: list[Bar], omega_of):
        """M(z), Q(z, z') - the velocity terms; omega_of(bar) gives the bar's (angle rate jet)"""
        nz = len(psi.d)
        M = np.zeros((nz, nz))
        Q = np.zeros(nz)
        cp, sp = jcos(psi), jsin(psi)
        ez = np.array([0, 0, 1.0])
        kw = np.array([sp.v, -cp.v, 0.0])
        # the yoke
        Ry = rot_z(psi.v)
        p = [YOKE_COM[0] * cp - YOKE_COM[1] * sp, YOKE_COM[0] * sp + YOKE_COM[1] * cp]
        Vm = np.array([p[0].d, p[1].d, np.zeros(nz)])
        ab = np.array([p[0].b, p[1].b, 0.0])
        Om = np.outer(ez, psi.d)
        w = ez * psi.t
        al = ez * psi.b
        Iw = Ry @ np.diag(YOKE_INERTIA) @ Ry.T
        M += YOKE_MASS * Vm.T @ Vm + Om.T @ Iw @ Om
        Fy = np.array([0, 0, -YOKE_MASS * G])
        Q += Vm.T @ (Fy - YOKE_MASS * ab) + Om.T @ (ez * self.tau - Iw @ al - cross(w, Iw @ w))
        # the bars, each in the plane turned by psi
        ucyl = {}
        Vbars = []
        for b, bar in enumerate(bars):
            X = bar.x + HIP_OFFSET
            p = [X * cp, X * sp, bar.y]
            Vm = np.array([c.d for c in p])
            ab = np.array([c.b for c in p])
            ph = omega_of(bar)
            R = bar_rotation(psi.v, ph.v)
            Om = np.outer(ez, psi.d) + np.outer(kw, ph.d)
            w = ez * psi.t + kw * ph.t
            al = ez * psi.b + kw * ph.b + ph.t * psi.t * cross(ez, kw)
            Iw = R @ np.diag(self.Ib[b]) @ R.T
            m = self.leg.m[b]
            M += m * Vm.T @ Vm + Om.T @ Iw @ Om
            Q += Vm.T @ (np.array([0, 0, -m * G]) - m * ab) + Om.T @ (-Iw @ al - cross(w, Iw @ w))
            ucyl[b] = R[:, 0]
            Vbars.append(Vm)
        for a, (_, cyl, rod) in enumerate(self.leg.actuators):
            f = self.F[a] * ucyl[cyl]
            Q += Vbars[rod].T @ f - Vbars[cyl].T @ f
        return M, Q


def planar_angle_jet(bar: Bar):
    """phi's jet: the bar's angle from its axis u = (sin phi, -cos phi): phi' = u x u'"""
    if bar.phi is not None:
        return bar.phi
    u = bar.u
    # phi = atan2(u0, -u1); d phi = u0 du1' ... via the 2D cross product u x du
    v = math.atan2(u[0].v, -u[1].v)
    d = u[0].v * u[1].d - u[1].v * u[0].d
    t = u[0].v * u[1].t - u[1].v * u[0].t
    b = u[0].v * u[1].b - u[1].v * u[0].b        # u x u'' (u' x u' = 0)
    return Jet(v, d, t, b)


def unit(e):
    r = jsqrt(e[0] * e[0] + e[1] * e[1])
    return (e[0] / r, e[1] / r)


def rot90(u):
    """n from u: n = (-u1, u0) for u = (sin, -cos), n = (cos, sin)"""
    return (-u[1], u[0])


# ---------------------------------------------------------------------------------------------
# (b) relative (semi-recursive) coordinates with loop closure
class Relative:
    """z = (psi, phi1, s1, phi3, phi4, s2, theta6); rows: C_rod_thigh and D, in the plane."""
    names = ("psi", "phi1", "s1", "phi3", "phi4", "s2", "theta6")

    def __init__(self, leg: Leg, F=(50.0, 0.0), tau=1.0):
        self.leg = leg
        self.dyn = LegInPlane(leg, F, tau)
        self.nz, self.m_rows = 7, 4

    def kinematics(self, z, zd):
        L = self.leg.L
        A, B = self.leg.frame["A"], self.leg.frame["B"]
        psi, phi1, s1, phi3, phi4, s2, th6 = (Jet.coord(z, zd, k) for k in range(7))
        u1 = ju(phi1)
        c1 = jadd((A[0], A[1]), L[0] / 2, u1)
        b1 = Bar(c1[0], c1[1], phi1, u1)
        c2 = (c1[0] + u1[0] * s1, c1[1] + u1[1] * s1)
        b2 = Bar(c2[0], c2[1], phi1, u1)
        u3 = ju(phi3)
        b3 = Bar(B[0] + u3[0] * (L[2] / 2), B[1] + u3[1] * (L[2] / 2), phi3, u3)
        u4 = ju(phi4)
        b4 = Bar(B[0] + u4[0] * (L[3] / 2), B[1] + u4[1] * (L[3] / 2), phi4, u4)
        b5 = Bar(b4.x + u4[0] * s2, b4.y + u4[1] * s2, phi4, u4)
        C = b2.point((L[1] / 2, 0.0))
        phi6 = phi1 + th6
        u6 = ju(phi6)
        b6 = Bar(C[0] + u6[0] * (L[5] / 2), C[1] + u6[1] * (L[5] / 2), phi6, u6)
        bars = [b1, b2, b3, b4, b5, b6]
        c3 = b3.point((L[2] / 2, 0.0))
        d5 = b5.point((L[4] / 2, 0.0))
        d6 = b6.point(self.leg.D_at)
        rows = [C[0] - c3[0], C[1] - c3[1], d5[0] - d6[0], d5[1] - d6[1]]
        return psi, bars, rows

    def rows_eval(self, z, zd):
        _, _, rows = self.kinematics(z, zd)
        return (np.array([r.v for r in rows]), np.array([r.d for r in rows]),
                -np.array([r.b for r in rows]))

    def accel(self, z, zd):
        psi, bars, rows = self.kinematics(z, zd)
        M, Q = self.dyn.mass_and_forces(psi, bars, planar_angle_jet)
        J = np.array([r.d for r in rows])
        gam = -np.array([r.b for r in rows])
        K = np.block([[M, J.T], [J, np.zeros((4, 4))]])
        x = np.linalg.solve(K, np.concatenate([Q, gam]))
        return x[:7], x[7:], M

    def step(self, y, h):
        z, zd = y

        def f(z, zd):
            return zd, self.accel(z, zd)[0]

        k1 = f(z, zd)
        k2 = f(z + h / 2 * k1[0], zd + h / 2 * k1[1])
        k3 = f(z + h / 2 * k2[0], zd + h / 2 * k2[1])
        k4 = f(z + h * k3[0], zd + h * k3[1])
        z = z + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        zd = zd + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        return self.project((z, zd))

    def project(self, y, tol=1e-13, iters=6):
        z, zd = y
        for _ in range(iters):
            phi, J, _ = self.rows_eval(z, zd)
            if np.max(np.abs(phi)) <= tol:
                break
            M = self.accel(z, zd)[2]
            W = np.linalg.inv(M)
            z = z - W @ J.T @ np.linalg.solve(J @ W @ J.T, phi)
        _, J, _ = self.rows_eval(z, zd)
        W = np.linalg.inv(self.accel(z, zd)[2])
        zd = zd - W @ J.T @ np.linalg.solve(J @ W @ J.T, J @ zd)
        return z, zd

    def initial(self, pose, psi=0.0):
        u1, u4 = u_of(pose[0, 2]), u_of(pose[3, 2])
        s1 = (pose[1, :2] - pose[0, :2]) @ u1
        s2 = (pose[4, :2] - pose[3, :2]) @ u4
        z = np.array([psi, pose[0, 2], s1, pose[2, 2], pose[3, 2], s2, pose[5, 2] - pose[0, 2]])
        return z, np.zeros(7)

    def health(self, y):
        phi, J, _ = self.rows_eval(*y)
        return np.linalg.svd(J, compute_uv=False)[-1], 0.0, np.max(np.abs(phi))

    def outputs(self, y):
        z, zd = y
        psi, bars, _ = self.kinematics(z, zd)
        return psi.v, foot_world(self.leg, psi.v, bars)

    def energy(self, y):
        return energy_in_plane(self, self.kinematics(*y)[:2], y)


def foot_world(leg, psi, bars):
    b, s = leg.foot
    p = bars[b].point(s)
    return hip_point(psi, (p[0].v, p[1].v))


def energy_in_plane(form, kin, y):
    """T + V - F l - tau psi from the jets (T = z'^T M z' / 2)"""
    psi, bars = kin
    M, _ = form.dyn.mass_and_forces(psi, bars, planar_angle_jet)
    zd = y[1]
    T = 0.5 * zd @ M @ zd
    V = YOKE_MASS * G * 0.0 + sum(form.leg.m[b] * G * bars[b].y.v for b in range(6))
    work = 0.0
    for a, (_, c, r) in enumerate(form.leg.actuators):
        pc = bars[c].point((-form.leg.L[c] / 2, 0.0))
        pr = bars[r].point((form.leg.L[r] / 2, 0.0))
        work += form.dyn.F[a] * math.hypot(pr[0].v - pc[0].v, pr[1].v - pc[1].v)
    return T + V - work


# ---------------------------------------------------------------------------------------------
# (c) the reference: minimal coordinates (psi, phi3, phi6), the other bars in closed form
class Minimal:
    def __init__(self, leg: Leg, F=(50.0, 0.0), tau=1.0):
        self.leg = leg
        self.dyn = LegInPlane(leg, F, tau)

    def kinematics(self, z, zd):
        L = self.leg.L
        A, B = self.leg.frame["A"], self.leg.frame["B"]
        psi, phi3, phi6 = (Jet.coord(z, zd, k) for k in range(3))
        u3 = ju(phi3)
        C = (B[0] + u3[0] * L[2], B[1] + u3[1] * L[2])
        u1 = unit((C[0] - A[0], C[1] - A[1]))
        n1 = rot90(u1)
        b1 = Bar(A[0] + u1[0] * (L[0] / 2), A[1] + u1[1] * (L[0] / 2), None, u1, n1)
        b2 = Bar(C[0] - u1[0] * (L[1] / 2), C[1] - u1[1] * (L[1] / 2), None, u1, n1)
        b3 = Bar(B[0] + u3[0] * (L[2] / 2), B[1] + u3[1] * (L[2] / 2), phi3, u3)
        u6 = ju(phi6)
        b6 = Bar(C[0] + u6[0] * (L[5] / 2), C[1] + u6[1] * (L[5] / 2), phi6, u6)
        D = b6.point(self.leg.D_at)
        u4 = unit((D[0] - B[0], D[1] - B[1]))
        n4 = rot90(u4)
        b4 = Bar(B[0] + u4[0] * (L[3] / 2), B[1] + u4[1] * (L[3] / 2), None, u4, n4)
        b5 = Bar(D[0] - u4[0] * (L[4] / 2), D[1] - u4[1] * (L[4] / 2), None, u4, n4)
        return psi, [b1, b2, b3, b4, b5, b6]

    def rhs(self, t, y):
        z, zd = y[:3], y[3:]
        psi, bars = self.kinematics(z, zd)
        M, Q = self.dyn.mass_and_forces(psi, bars, planar_angle_jet)
        return np.concatenate([zd, np.linalg.solve(M, Q)])

    def initial(self, pose, psi=0.0):
        return np.array([psi, pose[2, 2], pose[5, 2]]), np.zeros(3)

    def outputs(self, y):
        z, zd = y
        psi, bars = self.kinematics(z, zd)
        return psi.v, foot_world(self.leg, psi.v, bars)

    def energy(self, y):
        return energy_in_plane(self, self.kinematics(*y), y)


# ---------------------------------------------------------------------------------------------
# runs
def stand_pose(leg: Leg):
    return planar_closed_form(leg, *leg.stand_drive)


def run_fixed(form, h, T, sample):
    """integrate with step h to T; psi, foot and energy every `sample` seconds"""
    pose = stand_pose(form.leg)
    y = form.initial(pose)
    if isinstance(form, Absolute):
        y = form.project(y)
    n = int(round(T / h))
    every = int(round(sample / h))
    out = []
    for k in range(n + 1):
        if k % every == 0:
            psi, foot = form.outputs(y)
            out.append([k * h, psi, *foot, form.energy(y), *form.health(y)])
        if k < n:
            y = form.step(y, h)
    return unwrap(np.array(out), form.tau if isinstance(form, Absolute) else form.dyn.tau), y


def unwrap(out, tau):
    """psi continuous over the samples; the energy column less the rowing torque's work"""
    out[:, 1] = np.unwrap(out[:, 1])
    out[:, 5] -= tau * out[:, 1]
    return out


def run_reference(leg, T, sample, F=(50.0, 0.0), tau=1.0, tol=1e-12):
    from scipy.integrate import solve_ivp
    form = Minimal(leg, F, tau)
    z0, zd0 = form.initial(stand_pose(leg))
    ts = np.arange(0.0, T + sample / 2, sample)
    sol = solve_ivp(form.rhs, (0.0, T), np.concatenate([z0, zd0]), method="DOP853",
                    rtol=tol, atol=tol, t_eval=ts)
    out = []
    for t, yy in zip(sol.t, sol.y.T):
        psi, foot = form.outputs((yy[:3], yy[3:]))
        out.append([t, psi, *foot, form.energy((yy[:3], yy[3:])), 0.0, 0.0, 0.0])
    return unwrap(np.array(out), tau), sol


def traj_error(a, b):
    """the largest foot-position (m) and psi (rad) difference over the samples"""
    return (float(np.max(np.linalg.norm(a[:, 2:5] - b[:, 2:5], axis=1))),
            float(np.max(np.abs(a[:, 1] - b[:, 1]))))


# ---------------------------------------------------------------------------------------------
# operation counts of a fixed-structure kernel (multiply-adds; a division counts as one)
def symbolic_ldl(adj, order):
    """L D L^T of a symmetric pattern (adjacency sets) in the given order: nnz(L) below the
    diagonal, multiply-adds of the factorization and of one solve (forward, 1/D, backward)."""
    g = {i: set(adj[i]) - {i} for i in range(len(adj))}
    nnz = fact = 0
    for p in order:
        nb = g.pop(p)
        c = len(nb)
        nnz += c
        fact += c + c * (c + 1) // 2
        for a in nb:
            g[a] |= nb - {a}
            g[a].discard(p)
    return nnz, fact, 2 * nnz + len(adj)


def min_degree(adj, groups=None):
    """greedy minimum degree on the elimination graph (ties: lowest index); with groups, each
    group's nodes are eliminated before the next group's."""
    g = {i: set(adj[i]) - {i} for i in range(len(adj))}
    groups = groups or [list(range(len(adj)))]
    order = []
    for grp in groups:
        left = set(grp)
        while left:
            p = min(left, key=lambda i: (len(g[i]), i))
            left.remove(p)
            nb = g.pop(p)
            for a in nb:
                g[a] |= nb - {a}
                g[a].discard(p)
            order.append(p)
    return order


def gram_pattern(nz_rows):
    """the pattern of A W A^T from the columns of each row of A, and the multiply-adds of forming
    its lower triangle (W diagonal: one product per shared column, A W once)"""
    n = len(nz_rows)
    adj = [set() for _ in range(n)]
    form = sum(len(r) for r in nz_rows)
    for i in range(n):
        for k in range(i + 1):
            c = len(nz_rows[i] & nz_rows[k])
            if c:
                adj[i].add(k)
                adj[k].add(i)
                form += c
    return adj, form


def absolute_structure(a: Absolute, seed=1):
    """the structural non-zero columns of each row of J at a generic configuration"""
    rng = np.random.default_rng(seed)
    r = rng.normal(size=(a.nb, 3))
    q = rng.normal(size=(a.nb, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    w = rng.normal(size=(a.nb, 3))
    v = rng.normal(size=(a.nb, 3))
    _, J, _ = a.rows_eval(a.state(r, q, v, w))
    return [set(np.nonzero(np.abs(row) > 1e-14)[0]) for row in J], J


def relative_structure(b: Relative, seed=1):
    """the structural non-zeros of R (body velocities (v world, omega body) from z') and of Phi_z"""
    rng = np.random.default_rng(seed)
    z = rng.normal(size=7)
    z[2] = 0.3
    z[5] = 0.25
    psi, bars, rows = b.kinematics(z, rng.normal(size=7))
    ez = np.array([0, 0, 1.0])
    kw = np.array([math.sin(psi.v), -math.cos(psi.v), 0.0])
    blocks = [np.vstack([np.outer([-math.sin(psi.v), math.cos(psi.v), 0], psi.d),
                         np.outer(ez, psi.d)])]
    for bar in bars:
        ph = planar_angle_jet(bar)
        R = bar_rotation(psi.v, ph.v)
        X = bar.x + HIP_OFFSET
        V = np.array([(X * jcos(psi)).d, (X * jsin(psi)).d, bar.y.d])
        Om = R.T @ (np.outer(ez, psi.d) + np.outer(kw, ph.d))
        blocks.append(np.vstack([V, Om]))
    Rm = np.vstack(blocks)
    Jz = np.array([r.d for r in rows])
    return Rm, Jz


def leg_costs(leg: Leg, rows="tree"):
    """per-stage and per-step multiply-adds of the linear algebra, both formulations, one leg"""
    out = {}
    a = Absolute(leg, rows=rows)
    nzr, J = absolute_structure(a)
    m = len(nzr)
    adj, form = gram_pattern(nzr)
    nnzJ = sum(len(r) for r in nzr)
    res = {}
    for name, order in (("natural", list(range(m))), ("min_degree", min_degree(adj))):
        nnzL, fact, solve = symbolic_ldl(adj, order)
        stage = form + fact + solve + 2 * nnzJ + a.nv           # J W Q - gamma, W (Q - J^T lambda)
        end = form + fact + solve + 3 * nnzJ + a.nv             # velocity projection
        res[name] = dict(nnzA=sum(len(s) for s in adj) // 2 + m, nnzL=nnzL, form=form, fact=fact,
                         solve=solve, stage=stage, step=4 * stage + end)
    out["a"] = dict(nq=7 * a.nb, nv=a.nv, rows=m, nnzJ=nnzJ, orders=res)
    b = Relative(leg)
    Rm, Jz = relative_structure(b)
    cols = [set(np.nonzero(np.abs(Rm[:, k]) > 1e-14)[0]) for k in range(7)]
    nnzR = int(np.sum(np.abs(Rm) > 1e-14))
    _, formM = gram_pattern(cols)                   # R^T M R, M diagonal per body (body frame)
    nz = 7
    kkt = [set(range(nz)) for _ in range(nz)] + [set() for _ in range(Jz.shape[0])]
    for i, row in enumerate(Jz):
        for k in np.nonzero(np.abs(row) > 1e-14)[0]:
            kkt[nz + i].add(int(k))
            kkt[int(k)].add(nz + i)
    nnzL, fact, solve = symbolic_ldl(kkt, list(range(nz + Jz.shape[0])))
    nnzPhi = int(np.sum(np.abs(Jz) > 1e-14))
    stage = formM + fact + solve + 2 * nnzR + 0          # Q_bar = R^T (Q - M bias)
    end = fact + solve + 2 * nnzPhi + nz              # the velocity projection
    out["b"] = dict(nq=nz, nv=nz, rows=Jz.shape[0], nnzR=nnzR, nnzPhi=nnzPhi,
                    orders={"coords_first": dict(nnzA=sum(len(s) for s in kkt) // 2 + len(kkt),
                                                  nnzL=nnzL, form=formM, fact=fact, solve=solve,
                                                  stage=stage, step=4 * stage + end + formM)})
    return out


def hexapod_costs(leg: Leg, stuck=3, rows="tree"):
    """the six legs on a free box (6 velocity coordinates), `stuck` feet with 3 rows each"""
    out = {}
    # (a): the box is body 0, leg l's bodies 1 + 7 l ...; its hip rows act on the box too
    a = Absolute(leg, rows=rows)
    nzr, _ = absolute_structure(a)
    rows, groups, hip = [], [], []
    for l in range(6):
        base = 6 + a.nv * l
        grp = []
        for i, cols in enumerate(nzr):
            c = {base + x for x in cols}
            if a.rows[i][0] == "hip":
                c |= set(range(6)) if i < 3 else set(range(3, 6))
                hip.append(len(rows))
            else:
                grp.append(len(rows))
            rows.append(c)
        if l < stuck:
            shank = base + 6 * 6
            for _ in range(3):
                grp.append(len(rows))
                rows.append(set(range(shank, shank + 6)))
        groups.append(grp)
    adj, form = gram_pattern(rows)
    nnzJ = sum(len(r) for r in rows)
    nv = 6 + a.nv * 6
    res = {}
    for name, order in (("min_degree", min_degree(adj)),
                        ("legs_then_hips", min_degree(adj, groups + [hip]))):
        nnzL, fact, solve = symbolic_ldl(adj, order)
        stage = form + fact + solve + 2 * nnzJ + nv
        end = form + fact + solve + 3 * nnzJ + nv
        res[name] = dict(nnzA=sum(len(x) for x in adj) // 2 + len(adj), nnzL=nnzL, form=form,
                         fact=fact, solve=solve, stage=stage, step=4 * stage + end)
    out["a"] = dict(nq=7 + 49 * 6, nv=nv, rows=len(rows), nnzJ=nnzJ, orders=res)
    # (b): z = box (6) + 7 per leg; rows: 4 loop rows per leg, 3 per stuck foot (box + chain)
    b = Relative(leg)
    Rm, Jz = relative_structure(b)
    nz = 6 + 7 * 6
    cols_of_body = []                       # R's pattern: each body velocity's z columns
    cols_of_body += [set(range(6))] * 6
    for l in range(6):
        for k in range(Rm.shape[0]):
            nzc = np.nonzero(np.abs(Rm[k]) > 1e-14)[0]
            cols_of_body.append(set(range(6)) | {6 + 7 * l + int(c) for c in nzc})
    zcols = [set() for _ in range(nz)]
    for i, c in enumerate(cols_of_body):
        for k in c:
            zcols[k].add(i)
    _, formM = gram_pattern(zcols)
    nnzR = sum(len(c) for c in cols_of_body)
    shank_rows = range(6 * 6, 6 * 7)          # the shank's block of the leg's R
    foot_cols = set()
    for k in shank_rows:
        foot_cols |= {int(c) for c in np.nonzero(np.abs(Rm[k]) > 1e-14)[0]}
    nodes = [set() for _ in range(nz)]
    order = []
    def link(i, k):
        nodes[i].add(k)
        nodes[k].add(i)
    for i in range(nz):                       # M_bar: box-box, leg-leg, box-leg dense
        for k in range(nz):
            li, lk = (i - 6) // 7 if i >= 6 else -1, (k - 6) // 7 if k >= 6 else -1
            if i != k and (li == lk or li < 0 or lk < 0):
                nodes[i].add(k)
    nrows = 0
    for l in range(6):
        order += list(range(6 + 7 * l, 13 + 7 * l))
        leg_rows = [{6 + 7 * l + int(c) for c in np.nonzero(np.abs(r) > 1e-14)[0]} for r in Jz]
        if l < stuck:
            leg_rows += [set(range(6)) | {6 + 7 * l + c for c in foot_cols}] * 3
        for cset in leg_rows:
            nodes.append(set())
            idx = len(nodes) - 1
            for c in cset:
                link(idx, c)
            order.append(idx)
            nrows += 1
    order += list(range(6))
    nnzL, fact, solve = symbolic_ldl(nodes, order)
    nnzPhi = sum(len(x) for x in nodes[nz:])
    stage = formM + fact + solve + 2 * nnzR
    end = fact + solve + 2 * nnzPhi + nz
    # coordinates: the velocity coordinates and one more (the box's quaternion: 4 for 3 rates)
    out["b"] = dict(nq=nz + 1, nv=nz, rows=nrows, nnzR=nnzR, orders={"legs_then_box": dict(
        nnzA=sum(len(x) for x in nodes) // 2 + len(nodes), nnzL=nnzL, form=formM, fact=fact,
        solve=solve, stage=stage, step=4 * stage + end + formM)})
    return out


def kkt_tree_order(a: Absolute, nb_offset=0, row_offset=0):
    """(a)'s [M J^T; J 0] in the tree's order, leaves first: a body's 6 coordinates, then the
    rows of its joint to its parent; the cut joints' rows; the yoke; the hip rows last.
    Nodes: coordinates 0 .. nv-1, rows nv + i."""
    names = [r[0] for r in a.rows]
    rows_of = lambda n: [row_offset + i for i, x in enumerate(names) if x == n]   # noqa: E731
    coords = lambda b: list(range(nb_offset + 6 * b, nb_offset + 6 * b + 6))    # noqa: E731
    seq = [(6, "C_rod_shank"), (2, "upper_actuator"), (1, "A"), (5, "lower_actuator"),
           (4, "B_lower"), (3, "B_thigh")]
    order = []
    for b, joint in seq:
        order += coords(b) + rows_of(joint)
    order += rows_of("C_rod_thigh") + rows_of("D") + coords(0)
    return order, rows_of("hip")


def kkt_costs(J, order, nv, check=True):
    """symbolic L D L^T of [M J^T; J 0] (M diagonal) in `order` (rows as nv + i); with check,
    a numerical L D L^T at J and random masses confirms that no pivot vanishes"""
    m = J.shape[0]
    n = nv + m
    adj = [set() for _ in range(n)]
    for i in range(m):
        for c in np.nonzero(np.abs(J[i]) > 1e-14)[0]:
            adj[nv + i].add(int(c))
            adj[int(c)].add(nv + i)
    nnzL, fact, solve = symbolic_ldl(adj, [o if o < nv else o for o in order])
    minpiv = None
    if check:
        K = np.zeros((n, n))
        K[:nv, :nv] = np.diag(np.random.default_rng(2).uniform(0.5, 2.0, nv))
        K[nv:, :nv] = J
        K[:nv, nv:] = J.T
        K = K[np.ix_(order, order)]
        piv = []
        for k in range(n):
            d = K[k, k]
            piv.append(abs(d))
            if d == 0:
                break
            l = K[k + 1:, k] / d
            K[k + 1:, k + 1:] -= np.outer(l, K[k, k + 1:])
        minpiv = float(min(piv))
    return nnzL, fact, solve, minpiv


def kkt_leg_and_hexapod(leg: Leg, stuck=3):
    """(a) "tree" rows in the tree's KKT order: one leg on a fixed box, and six on a free box"""
    a = Absolute(leg, rows="tree")
    _, J = absolute_structure(a)
    order, hip = kkt_tree_order(a, 0, a.nv)
    leg_res = kkt_costs(J, order + hip, a.nv)
    nnzJ = int(np.sum(np.abs(J) > 1e-14))
    stage = leg_res[1] + leg_res[2] + 2 * nnzJ
    out = {"leg": dict(nnzL=leg_res[0], fact=leg_res[1], solve=leg_res[2], min_pivot=leg_res[3],
                       stage=stage, step=5 * stage)}
    # the hexapod: the box is coordinates 0..5; leg l's bodies at 6 + 42 l; its rows after all
    # coordinates; its hip rows also act on the box (a rotated copy is structure enough)
    nv = 6 + a.nv * 6
    rows = []
    order, hips = [], []
    m0 = J.shape[0]
    nrow_leg = m0 + 3
    total_rows = 6 * m0 + 3 * stuck
    H = np.zeros((total_rows, nv))
    r = 0
    for l in range(6):
        base = 6 + a.nv * l
        H[r:r + m0, base:base + a.nv] = J
        for i in range(5):
            H[r + i, 0:6] = 1.0 if i < 3 else np.r_[0, 0, 0, 1.0, 1.0, 1.0]
        lo, hi_ = kkt_tree_order(a, base, nv + r)
        # a stuck foot: 3 rows on the shank, eliminated right after the shank's coordinates
        if l < stuck:
            foot = [nv + 6 * m0 + 3 * l + k for k in range(3)]
            f0 = 6 * m0 + 3 * l
            H[f0:f0 + 3, base + a.nv - 6:base + a.nv] = np.random.default_rng(l).normal(size=(3, 6))
            lo = lo[:6] + foot + lo[6:]
        order += lo
        hips += hi_
        r += m0
    order += hips + list(range(6))
    hx = kkt_costs(H, order, nv, check=False)
    nnzH = int(np.sum(np.abs(H) > 1e-14))
    # coordinates: the box's 7 (position, quaternion) and 7 per body of each leg
    out["hexapod"] = dict(nq=7 + 6 * 7 * a.nb, nv=nv, rows=total_rows, nnzL=hx[0], fact=hx[1],
                          solve=hx[2],
                          stage=hx[1] + hx[2] + 2 * nnzH, step=5 * (hx[1] + hx[2] + 2 * nnzH))
    return out


# ---------------------------------------------------------------------------------------------
# the figures
STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)


def accuracy(leg, T=1.0, steps=STEPS, sample=0.01, F=(50.0, 0.0), tau=1.0, forms=None, log=print):
    """per formulation and step: the largest foot error over the run against the reference,
    psi's, the energy balance's drift, the smallest singular value, max | |q| - 1 |"""
    ref, sol = run_reference(leg, T, sample, F, tau)
    log(f"reference: DOP853 rtol = atol = 1e-12, {sol.nfev} evaluations, energy balance drift "
        f"{np.ptp(ref[:, 5]):.1e} J")
    forms = forms or {"a": lambda: Absolute(leg, F, tau, rows="tree"),
                      "a-plane": lambda: Absolute(leg, F, tau, rows="plane"),
                      "a-quat": lambda: Absolute(leg, F, tau, rows="tree", group=False),
                      "b": lambda: Relative(leg, F, tau)}
    res = {}
    for name, make in forms.items():
        for h in (steps if name != "a-quat" else steps[:2]):
            out, _ = run_fixed(make(), h, T, sample)
            ef, ep = traj_error(out, ref)
            de = float(np.max(np.abs(out[:, 5] - out[0, 5])))
            res[name, h] = dict(foot=ef, psi=ep, energy=de,
                                smin=float(np.min(out[:, 6])), quat=float(np.max(out[:, 7])),
                                phi=float(np.max(out[:, 8])), out=out)
            log(f"{name:8s} h = {h:.1e}: foot {ef:.2e} m, psi {ep:.2e} rad, energy {de:.2e} J, "
                f"sigma_min {res[name, h]['smin']:.3f}, | |q| - 1 | {res[name, h]['quat']:.1e}")
    return res, ref


def order_of(res, name, steps, key="foot"):
    x = np.log(np.array(steps))
    y = np.log(np.array([res[name, h][key] for h in steps]))
    return float(np.polyfit(x, y, 1)[0])


def planar_check(leg, T=1.0, h=1e-3, sample=0.01, log=print):
    """rowing torque 0: psi stays 0, and the foot moves as the planar model's; against the
    reference (tau = 0) and, where it loads, the legsim library's planar leg (RK4, same h)"""
    ref, _ = run_reference(leg, T, sample, tau=0.0)
    res = {}
    for name, form in (("a", Absolute(leg, tau=0.0)), ("b", Relative(leg, tau=0.0))):
        out, _ = run_fixed(form, h, T, sample)
        res[name] = dict(psi=float(np.max(np.abs(out[:, 1]))), foot=traj_error(out, ref)[0],
                         lateral=float(np.max(np.abs(out[:, 3]))), out=out)
        log(f"planar check {name}: max |psi| {res[name]['psi']:.1e}, max |foot y| "
            f"{res[name]['lateral']:.1e} m, foot vs minimal reference {res[name]['foot']:.2e} m")
    try:
        import os
        main = Path(os.environ.get("LEGSIM_MAIN", ROOT))   # a tree with build/host built
        os.environ.setdefault("LEGSIM_LIB_DIR", str(main / "build/host/firmware_core"))
        sys.path.insert(0, str(main / "python"))
        import legsim
        sim = legsim.Sim(str(main / "models/leg.toml"), integrator="rk4", step=h)
        sim.assemble_pose("stand")
        sim.command_force("upper", 50.0)
        feet = [sim.foot().copy()]
        every = int(round(sample / h))
        for _ in range(int(round(T / sample))):
            sim.step(every)
            if sim.events():      # a stroke stop: legsim's planar leg has stops, these models not
                break
            feet.append(sim.foot().copy())
        feet = np.array(feet)
        n = len(feet)
        world = np.column_stack([HIP_OFFSET + feet[:, 0], feet[:, 1]])
        for name in ("a", "b"):
            mine = res[name]["out"][:n]
            e = float(np.max(np.hypot(mine[:, 2] - world[:, 0], mine[:, 4] - world[:, 1])))
            res[name]["legsim"] = e
            log(f"planar check {name}: foot vs legsim's planar leg (RK4, h = {h:g}) {e:.2e} m "
                f"over t <= {(n - 1) * sample:.2f} s (then {sim.events() or 'no event'})")
        e = float(np.max(np.hypot(ref[:n, 2] - world[:, 0], ref[:n, 4] - world[:, 1])))
        log(f"planar check: minimal reference vs legsim's planar leg {e:.2e} m")
        res["legsim_vs_ref"] = e
    except Exception as ex:   # the library is optional here
        log(f"planar check: legsim not available ({type(ex).__name__}: {ex})")
    return res


def md_row(*cells):
    """a markdown table row; integers with thousands separators"""
    return "| " + " | ".join(f"{c:,}" if isinstance(c, int) else str(c) for c in cells) + " |"


def cost_table(leg, log=print):
    lc = {v: leg_costs(leg, v) for v in ("tree", "plane")}
    kk = {st: kkt_leg_and_hexapod(leg, st) for st in (0, 3, 6)}
    hx = {(v, st): hexapod_costs(leg, st, v) for v in ("tree", "plane") for st in (0, 3, 6)}
    cols = ("coordinates", "velocity coordinates", "rows", "nnz(J)", "nnz(A), lower", "nnz(L)",
            "factor", "solve", "RK4 stage", "RK4 step")
    log("\n" + md_row("one leg, fixed box", *cols))
    log(md_row(*["---"] * (len(cols) + 1)))
    cost = lambda r: (r["fact"], r["solve"], r["stage"], r["step"])      # noqa: E731
    for v in ("tree", "plane"):
        c = lc[v]["a"]
        for o, r in c["orders"].items():
            log(md_row(f"(a) {v} rows, J M^-1 J^T, {o} order", c["nq"], c["nv"], c["rows"],
                       c["nnzJ"], r["nnzA"], r["nnzL"], *cost(r)))
    k = kk[0]["leg"]
    c = lc["tree"]["a"]
    log(md_row("(a) tree rows, [M J^T; J 0], tree order", c["nq"], c["nv"], c["rows"], c["nnzJ"],
               "-", k["nnzL"], *cost(k)))
    c = lc["tree"]["b"]
    r = c["orders"]["coords_first"]
    log(md_row("(b) relative, [R^T M R, Phi_z^T; Phi_z 0]", c["nq"], c["nv"], c["rows"],
               f"{c['nnzPhi']} (R: {c['nnzR']})", r["nnzA"], r["nnzL"], *cost(r)))
    cols = ("feet stuck", "coordinates", "velocity coordinates", "rows", "nnz(L)", "factor",
            "solve", "RK4 stage", "RK4 step")
    log("\n" + md_row("hexapod, free box", *cols))
    log(md_row(*["---"] * (len(cols) + 1)))
    for st in (0, 3, 6):
        c = hx["tree", st]["a"]
        r = c["orders"]["legs_then_hips"]
        log(md_row("(a) tree rows, J M^-1 J^T, legs then hip rows", st, c["nq"], c["nv"],
                   c["rows"], r["nnzL"], *cost(r)))
    for st in (0, 3, 6):
        k = kk[st]["hexapod"]
        log(md_row("(a) tree rows, [M J^T; J 0], legs then box", st, k["nq"], k["nv"], k["rows"],
                   k["nnzL"], *cost(k)))
    for st in (0, 3, 6):
        c = hx["plane", st]["a"]
        r = c["orders"]["legs_then_hips"]
        log(md_row("(a) plane rows, J M^-1 J^T, legs then hip rows", st, c["nq"], c["nv"],
                   c["rows"], r["nnzL"], *cost(r)))
    for st in (0, 3, 6):
        c = hx["tree", st]["b"]
        r = c["orders"]["legs_then_box"]
        log(md_row("(b) relative, KKT, legs then box", st, c["nq"], c["nv"], c["rows"],
                   r["nnzL"], *cost(r)))
    return lc, kk, hx


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--table", action="store_true",
                    help="accuracy and cost tables (several minutes)")
    ap.add_argument("--costs", action="store_true", help="the operation counts alone")
    ap.add_argument("--planar", action="store_true", help="the planar check")
    ap.add_argument("--T", type=float, default=1.0)
    args = ap.parse_args(argv)
    leg = Leg()
    if args.table or args.costs:
        cost_table(leg)
    if args.planar or args.table:
        planar_check(leg, T=args.T)
    if args.table:
        res, _ = accuracy(leg, T=args.T)
        print("\n" + md_row("formulation", "h (s)", "foot error (m)", "psi error (rad)",
                            "energy balance (J)", "min sigma(J)", "max abs(abs(q) - 1)"))
        print(md_row(*["---"] * 7))
        names = ("a", "a-plane", "a-quat", "b")
        for (name, h), r in sorted(res.items(), key=lambda x: names.index(x[0][0])):
            print(md_row(name, f"{h:g}", f"{r['foot']:.2e}", f"{r['psi']:.2e}",
                         f"{r['energy']:.2e}", f"{r['smin']:.4f}", f"{r['quat']:.1e}"))
        for name in ("a", "a-plane", "b"):
            print(f"order of accuracy {name}: foot {order_of(res, name, STEPS):.2f}, "
                  f"psi {order_of(res, name, STEPS, 'psi'):.2f}")


if __name__ == "__main__":
    main()
