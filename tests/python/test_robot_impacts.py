"""Touchdown impacts of the two-leg robot as a linear complementarity problem.

An impact's impulses on the feet only push (P_n >= 0); a foot that separates leaves with no
impulse; a foot that stays has its impulse inside the friction cone (stuck) or on its mu_k
edge against its sliding. The core enumerates the modes (contact.cpp, impact). Here the same
impact is computed independently: the pre-impact velocity from a twin whose ground is far
below (the same step with no contact), the constraint Jacobian at the core's landed q (the
joints' from the API, the feet's by central differences), and every mode combination solved
as one dense KKT system of M v+ = M v- + J^T p, with the first consistent one in the same
priority order.
"""
from __future__ import annotations

import itertools

import numpy as np
import pytest

import legsim

from conftest import ROOT

ROBOT = ROOT / "models" / "robot.toml"


def _robot_file(tmp_path, ground_y=0.0, mu_s=0.6, mu_k=0.5):
    text = ROBOT.read_text().replace('file = "leg.toml"', f'file = "{ROOT / "models" / "leg.toml"}"')
    text = text.replace("point = [0.0, 0.0]              # m, world", f"point = [0.0, {ground_y}]")
    text = text.replace("mu_static = 0.6", f"mu_static = {mu_s}").replace(
        "mu_kinetic = 0.5", f"mu_kinetic = {mu_k}")
    path = tmp_path / f"robot_{ground_y}_{mu_s}_{mu_k}.toml"
    path.write_text(text)
    return str(path)


def _need_robot():
    lib = legsim.load_library("double")
    if lib.config["LEGSIM_MAX_BODIES"] < 13 or lib.config.get("LEGSIM_MAX_CONTACTS", 0) < 2:
        pytest.skip(f"{lib.path} is built without room for the robot")


def _start(path, integrator, dy, v, omega, twin_path=None):
    """The stand shifted by dy, moving as one rigid body (v of the box centre, omega), feet
    free; and its twin of twin_path in the same state."""
    s = legsim.Sim(path, integrator=integrator)
    q = s.assemble_on_ground(pose="stand").copy()
    s.set_contact(0, "free")
    s.set_contact(1, "free")
    c = q[0:2].copy()
    qd = np.zeros_like(q)
    for b in range(len(q) // 3):
        r = q[3 * b:3 * b + 2] - c
        qd[3 * b:3 * b + 2] = np.asarray(v) + omega * np.array([-r[1], r[0]])
        qd[3 * b + 2] = omega
    q[1::3] += dy
    s.set_state(q, qd)
    twin = legsim.Sim(twin_path, integrator=integrator)
    twin.set_state(q, qd)
    return s, twin


def _feet_jacobian(path, q):
    s = legsim.Sim(path)
    s.assemble_on_ground(pose="stand")
    G = np.zeros((4, len(q)))
    e = 1e-6
    for k in range(len(q)):
        dq = np.zeros(len(q))
        dq[k] = e
        s.set_state(q + dq)
        a = s.contacts()["position"].reshape(-1)
        s.set_state(q - dq)
        b = s.contacts()["position"].reshape(-1)
        G[:, k] = (a - b) / (2 * e)
    s.set_state(q)
    return G, s.jacobian()


def _impact_lcp(M, Jj, G, v, mu_s, mu_k, current=("stick", "stick")):
    """v+ and the feet's (P_n, P_t) of the first consistent mode combination (ground y = 0,
    normal (0, 1), tangent (1, 0)); the priority as the core's: the current mode, then stick,
    slip, free."""
    n = M.shape[0]
    modes = ["stick", "slip+", "slip-", "free"]
    rank = {"stick": 1, "slip+": 2, "slip-": 2, "free": 3}
    best = None
    for combo in itertools.product(modes, repeat=2):
        rows, cols = [Jj], [Jj.T]   # constraint rows; impulse directions (generalized)
        for k, md in enumerate(combo):
            gn, gt = G[2 * k + 1], G[2 * k]
            if md == "stick":
                rows += [gn[None], gt[None]]
                cols += [gn[:, None], gt[:, None]]
            elif md in ("slip+", "slip-"):
                sgn = 1.0 if md == "slip+" else -1.0
                rows += [gn[None]]
                cols += [(gn - sgn * mu_k * gt)[:, None]]   # P_t = -s mu_k P_n
        R, C = np.vstack(rows), np.hstack(cols)
        K = np.block([[M, -C], [R, np.zeros((R.shape[0], C.shape[1]))]])
        rhs = np.concatenate([M @ v, np.zeros(R.shape[0])])
        try:
            x = np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:
            continue
        vp, p = x[:n], x[n:]
        P, ok, i = np.zeros((2, 2)), True, Jj.shape[0]
        for k, md in enumerate(combo):
            vn, vt = G[2 * k + 1] @ vp, G[2 * k] @ vp
            if md == "free":
                ok &= vn >= -1e-9
            elif md == "stick":
                P[k] = p[i], p[i + 1]
                i += 2
                ok &= P[k, 0] >= -1e-9 and abs(P[k, 1]) <= mu_s * P[k, 0] + 1e-9
            else:
                sgn = 1.0 if md == "slip+" else -1.0
                P[k] = p[i], -sgn * mu_k * p[i]
                i += 1
                ok &= P[k, 0] >= -1e-9 and sgn * vt > 1e-9
        if not ok:
            continue
        score = sum(0 if md == cur else rank[md] for md, cur in zip(combo, current))
        if best is None or score < best[0]:
            best = (score, combo, vp, P)
    return best


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_a_foot_moving_up_gets_no_pulling_impulse(tmp_path, integrator):
    # both feet 2 mm below the line and moving up: both leave, no impulse, the velocities
    # those of the same step with no ground
    _need_robot()
    s, twin = _start(str(ROBOT), integrator, -0.002, (0.0, 0.5), 0.0,
                     _robot_file(tmp_path, ground_y=-10.0))
    s.step(1)
    twin.step(1)
    c = s.contacts()
    assert list(c["state"]) == ["free", "free"]
    assert np.all(c["impulse"] == 0)
    assert {"touchdown", "liftoff"} <= set(s.events())
    assert np.max(np.abs(s.qd - twin.qd)) < 1e-12


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
@pytest.mark.parametrize("mu_s,mu_k,v,omega", [
    (0.6, 0.5, (0.0, -0.3), 0.8),    # rocking onto the left foot: it sticks, the right leaves
    (0.6, 0.5, (0.3, -0.3), -0.8),   # onto the right foot, moving sideways
    (0.1, 0.08, (0.6, -0.3), 0.8),   # outside the cone: the landing foot slides
    (0.6, 0.5, (0.05, -0.4), 0.0),   # flat: both land
])
def test_touchdown_impact_is_the_lcp_solution(tmp_path, integrator, mu_s, mu_k, v, omega):
    _need_robot()
    path = _robot_file(tmp_path, mu_s=mu_s, mu_k=mu_k)
    s, twin = _start(path, integrator, -0.001, v, omega,
                     _robot_file(tmp_path, ground_y=-10.0, mu_s=mu_s, mu_k=mu_k))
    s.step(1)
    twin.step(1)
    assert "touchdown" in s.events() and "touchdown" not in twin.events()
    G, Jj = _feet_jacobian(path, s.q)
    masses = np.array([[m, m, i] for m, i in zip(s.model.masses, s.model.inertias)]).reshape(-1)
    best = _impact_lcp(np.diag(masses), Jj, G, twin.qd, mu_s, mu_k)
    assert best is not None
    _, combo, vp, P = best
    c = s.contacts()
    state = {"stick": "stuck", "slip+": "sliding", "slip-": "sliding", "free": "free"}
    assert list(c["state"]) == [state[md] for md in combo]
    assert np.max(np.abs(s.qd - vp)) < 1e-7 * (1 + np.max(np.abs(vp)))
    assert np.max(np.abs(c["impulse"] - P)) < 1e-6 * (1 + np.max(np.abs(P)))
    assert np.all(c["impulse"][:, 0] >= 0)
