"""A small independent check for the peers: the leg in absolute coordinates.

This is *not* the bench's reference model (that one lives in
``legsim_bench.reference``: minimal coordinates + DOP853, written
independently). It is the peers' own cross-check, so the peers can be
validated before, and besides, that reference:

    M qdd + Phi_q^T lambda = Q(q),   Phi_q qdd = gamma - 2 a Phi_dot - b^2 Phi

(index-1 form with a weak Baumgarte term that only damps drift; the exact
solution is unchanged), integrated by scipy's DOP853 at rtol 1e-12. Analytic
Jacobian and gamma, written from leg_model's conventions and nothing else.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from . import leg_model as lm


def _rot_d(phi: float, xi: float, eta: float) -> np.ndarray:
    """d/dphi of xi u + eta n = xi n - eta u."""
    return xi * lm.n(phi) - eta * lm.u(phi)


def jacobian_gamma(model: lm.LegModel, q: np.ndarray, qd: np.ndarray):
    """Phi_q (m x 18) and gamma = -(Phi_q qd)_q qd."""
    rows, gam = [], []
    N = 3 * model.n_bodies

    def blank():
        return np.zeros(N)

    for j in model.joints:
        if j.kind in ("revolute_to_frame", "revolute"):
            for c in range(2):
                r = blank()
                g = 0.0
                for sgn, i, (xi, eta) in zip((1.0, -1.0), j.bodies, j.points):
                    phi, w = q[3 * i + 2], qd[3 * i + 2]
                    r[3 * i + c] += sgn
                    r[3 * i + 2] += sgn * _rot_d(phi, xi, eta)[c]
                    s = xi * lm.u(phi) + eta * lm.n(phi)
                    g += sgn * w * w * s[c]
                rows.append(r)
                gam.append(g)
        elif j.kind == "prismatic":
            i, k = j.bodies
            r = blank()
            r[3 * k + 2], r[3 * i + 2] = 1.0, -1.0
            rows.append(r)
            gam.append(0.0)
            phi, w = q[3 * i + 2], qd[3 * i + 2]
            ni, ui = lm.n(phi), lm.u(phi)
            d = q[3 * k: 3 * k + 2] - q[3 * i: 3 * i + 2]
            dv = qd[3 * k: 3 * k + 2] - qd[3 * i: 3 * i + 2]
            r = blank()
            r[3 * k: 3 * k + 2] = ni
            r[3 * i: 3 * i + 2] = -ni
            r[3 * i + 2] = -d @ ui
            rows.append(r)
            gam.append(2.0 * w * (dv @ ui) + w * w * (d @ ni))
        elif j.kind == "slot":
            (i, k), ((xi, eta),) = j.bodies, j.points
            phi_i, w_i = q[3 * i + 2], qd[3 * i + 2]
            phi_k, w_k = q[3 * k + 2], qd[3 * k + 2]
            nk, uk = lm.n(phi_k), lm.u(phi_k)
            s = xi * lm.u(phi_i) + eta * lm.n(phi_i)
            ds = _rot_d(phi_i, xi, eta)
            d = q[3 * i: 3 * i + 2] + s - q[3 * k: 3 * k + 2]
            dv = qd[3 * i: 3 * i + 2] + w_i * ds - qd[3 * k: 3 * k + 2]
            r = blank()
            r[3 * i: 3 * i + 2] = nk
            r[3 * i + 2] = ds @ nk
            r[3 * k: 3 * k + 2] = -nk
            r[3 * k + 2] = -d @ uk
            rows.append(r)
            gam.append(w_i * w_i * (s @ nk) + 2.0 * w_k * (dv @ uk) + w_k * w_k * (d @ nk))
    return np.array(rows), np.array(gam)


def accelerations(model, q, qd, forces, baumgarte=(20.0, 20.0)):
    M = model.masses()
    Q = np.zeros_like(q)
    for i, b in enumerate(model.bodies):
        Q[3 * i: 3 * i + 2] = b.mass * model.gravity
    Q += lm.actuator_forces_q(model, q, forces)
    J, gamma = jacobian_gamma(model, q, qd)
    a, b = baumgarte
    rhs_c = gamma - 2.0 * a * (J @ qd) - b * b * lm.constraints(model, q)
    m = J.shape[0]
    K = np.zeros((q.size + m, q.size + m))
    K[: q.size, : q.size] = np.diag(M)
    K[: q.size, q.size:] = J.T
    K[q.size:, : q.size] = J
    sol = np.linalg.solve(K, np.concatenate([Q, rhs_c]))
    return sol[: q.size], sol[q.size:]


def run(scene: str, t_end: float, *, variant: str = "revolute", t_eval=None,
        rtol: float = 1e-12, atol: float = 1e-14, model_path=None) -> dict:
    """Same dict as the peers' run() (t, q, qd); no timing (not a peer)."""
    model = lm.load(model_path, variant)
    forces = lm.scene_forces(model, scene)
    q0 = lm.stand_q0(model)
    N = q0.size

    def f(_t, y):
        q, qd = y[:N], y[N:]
        qdd, _ = accelerations(model, q, qd, forces)
        return np.concatenate([qd, qdd])

    if t_eval is None:
        t_eval = np.array([0.0, t_end])
    sol = solve_ivp(f, (0.0, t_end), np.concatenate([q0, np.zeros(N)]), method="DOP853",
                    rtol=rtol, atol=atol, t_eval=t_eval)
    if not sol.success:
        raise RuntimeError(sol.message)
    return {"t": sol.t, "q": sol.y[:N].T.copy(), "qd": sol.y[N:].T.copy(),
            "engine": "selfref (absolute coordinates, DOP853)", "variant": variant}
