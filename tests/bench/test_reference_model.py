"""Tests of the independent reference model (legsim_bench.reference).

Real values from leg.toml's comment, invariants (constraints, energy, balance,
time reversal, convergence) and cross-checks between the model's two routes
(reduced dynamics / virtual work vs Newton-Euler) and against the absolute-
coordinate multiplier formulation written here from leg.toml's joint list.
"""
import math
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    import legsim_bench.reference  # noqa: F401
except ImportError:  # the bench is not installed: use the source tree
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench.reference import (ForceCommand, LegModel, LengthCommand,  # noqa: E402
                                    NoEquilibriumError, Sinusoid, Step, UnreachableError,
                                    n, u)

TOML = ROOT / "models" / "leg.toml"
DATA = tomllib.loads(TOML.read_text())


@pytest.fixture(scope="module")
def rev():
    return LegModel.from_toml(TOML)


@pytest.fixture(scope="module")
def slot():
    return LegModel.from_toml(TOML, variant="slot")


# ---------------------------------------------------------------- helpers
BODY_ID = [int(b["id"]) for b in DATA["body"]]
LEN = {int(b["id"]): float(b["length"]) for b in DATA["body"]}
MASS = np.array([float(b["mass"]) for b in DATA["body"]])
INERTIA = np.array([float(b.get("inertia", b["mass"] * b["length"] ** 2 / 12)) for b in DATA["body"]])
G = np.array(DATA["gravity"], float)


def pose(q, bid):
    i = BODY_ID.index(bid)
    return q[3 * i:3 * i + 3]


def local(bid, end, spec):
    L = LEN[bid]
    return {"proximal": (-L / 2, 0.0), "distal": (L / 2, 0.0)}.get(end) or tuple(spec["at"])


def point(q, bid, xe):
    x, y, ph = pose(q, bid)
    return np.array([x, y]) + xe[0] * u(ph) + xe[1] * n(ph)


def joint_specs(variant):
    out = []
    for j in DATA["joint"]:
        if variant == "slot" and j["name"] in DATA["variant"]["slot"]:
            j = dict(DATA["variant"]["slot"][j["name"]], name=j["name"])
        out.append(j)
    return out


def residuals(q, variant):
    """Phi(q) of leg.toml's joints, written straight from the file; one array per joint."""
    res = []
    for j in joint_specs(variant):
        k = j["kind"]
        if k == "revolute_to_frame":
            b = j["body"]
            res.append(point(q, b, local(b, j["end"], j)) - np.array(DATA["frame"][j["point"]]))
        elif k == "revolute":
            (b1, b2), (e1, e2) = j["bodies"], j["ends"]
            res.append(point(q, b1, local(b1, e1, j)) - point(q, b2, local(b2, e2, j)))
        elif k == "prismatic":
            b1, b2 = j["bodies"]
            x1, y1, p1 = pose(q, b1)
            x2, y2, p2 = pose(q, b2)
            res.append(np.array([p2 - p1, n(p1) @ np.array([x2 - x1, y2 - y1])]))
        elif k == "slot":
            (b1, b2), (e1, _) = j["bodies"], j["ends"]
            x2, y2, p2 = pose(q, b2)
            res.append(np.array([n(p2) @ (point(q, b1, local(b1, e1, j)) - np.array([x2, y2]))]))
    return res


def phi_q(q, variant, h=1e-6):
    """Constraint Jacobian by central differences (test-side only)."""
    rows = []
    for k in range(len(residuals(q, variant))):
        cols = []
        for c in range(q.size):
            dq = np.zeros_like(q)
            dq[c] = h
            cols.append((residuals(q + dq, variant)[k] - residuals(q - dq, variant)[k]) / (2 * h))
        rows.append(np.array(cols).T)
    return rows


def applied(model, q, F, load):
    """Generalized applied forces on the absolute coordinates (x, y, moment about CoM)."""
    Q = np.zeros(q.size)
    for i in range(len(BODY_ID)):
        Q[3 * i:3 * i + 2] += MASS[i] * G
    foot = DATA["force"][0]
    sh = foot["body"]
    p = point(q, sh, local(sh, foot["end"], foot))
    i = BODY_ID.index(sh)
    Q[3 * i:3 * i + 2] += load
    r = p - q[3 * i:3 * i + 2]
    Q[3 * i + 2] += r[0] * load[1] - r[1] * load[0]
    jn = {j["name"]: j for j in DATA["joint"]}
    for a, f in zip(DATA["actuator"], F):
        cyl, rod = jn[a["joint"]]["bodies"]
        ua = u(pose(q, cyl)[2])
        Q[3 * BODY_ID.index(cyl):3 * BODY_ID.index(cyl) + 2] -= f * ua
        Q[3 * BODY_ID.index(rod):3 * BODY_ID.index(rod) + 2] += f * ua
    return Q


def multiplier_reactions(model, q, qdd, F, load, variant):
    """Reactions from M qdd = Q - Phi_q^T lambda (the core's formulation)."""
    blocks = phi_q(q, variant)
    Pq = np.vstack(blocks)
    Md = np.column_stack([MASS, MASS, INERTIA]).reshape(-1)
    rhs = applied(model, q, F, load) - Md * qdd
    lam = np.linalg.lstsq(Pq.T, rhs, rcond=None)[0]
    out, r0 = [], 0
    for j, blk in zip(joint_specs(variant), blocks):
        lam_k = lam[r0:r0 + blk.shape[0]]
        r0 += blk.shape[0]
        first = j["body"] if "body" in j else j["bodies"][0]
        i = BODY_ID.index(first)
        out.append(-(blk[:, 3 * i:3 * i + 3].T @ lam_k))
    return np.array(out), float(np.max(np.abs(Pq.T @ lam - rhs)))


# ------------------------------------------------------------------ tests
def test_axis_convention():
    assert np.allclose(u(0.0), [0.0, -1.0]) and np.allclose(n(0.0), [1.0, 0.0])
    phi = 0.3
    assert np.allclose(u(phi), [math.sin(phi), -math.cos(phi)])
    assert np.allclose((u(phi + 1e-7) - u(phi - 1e-7)) / 2e-7, n(phi), atol=1e-8)


def test_stand_pose_facts(rev):
    th = rev.stand_theta()
    assert np.allclose(th, [math.pi / 3, 0.0])
    q = rev.absolute_q(th)
    C = point(q, 3, local(3, "distal", {}))
    D = point(q, 6, (-0.10, 0.0))
    assert np.allclose(C, [0.4330127, -0.25], atol=1e-7)
    assert np.allclose(D, [0.4330127, -0.45], atol=1e-7)
    assert np.allclose(rev.foot(th), [0.4330127, -0.85], atol=1e-7)
    assert np.allclose(rev.lengths(th), [0.6614378, 0.6244998], atol=1e-7)
    assert abs(pose(q, 1)[2] - 0.7137244) < 1e-7 and pose(q, 2)[2] == pose(q, 1)[2]
    assert abs(pose(q, 4)[2] - 0.7661626) < 1e-7 and pose(q, 5)[2] == pose(q, 4)[2]
    assert pose(q, 3)[2] == th[0] and pose(q, 6)[2] == th[1]


@pytest.mark.parametrize("variant", ["revolute", "slot"])
def test_constraints_hold(variant, rev, slot):
    model = rev if variant == "revolute" else slot
    rng = np.random.default_rng(1)
    for k in range(20):
        th = model.stand_theta() + rng.uniform(-1.0, 1.0, model.ndof) * ([1.0, 1.5, 0.15][:model.ndof])
        q = model.absolute_q(th)
        assert q.shape == (18,)
        r = np.concatenate(residuals(q, variant))
        assert r.size == (16 if variant == "revolute" else 15)
        assert np.max(np.abs(r)) < 1e-14
        # the stated lengths: cylinder proximal end to rod distal end
        l_up = np.linalg.norm(point(q, 2, (LEN[2] / 2, 0)) - point(q, 1, (-LEN[1] / 2, 0)))
        l_lo = np.linalg.norm(point(q, 5, (LEN[5] / 2, 0)) - point(q, 4, (-LEN[4] / 2, 0)))
        assert np.allclose(model.lengths(th), [l_up, l_lo], atol=1e-14)


@pytest.mark.parametrize("variant", ["revolute", "slot"])
def test_jets_against_differences(variant, rev, slot):
    """Analytic Jacobian and bias acceleration vs central differences."""
    model = rev if variant == "revolute" else slot
    rng = np.random.default_rng(2)
    th = model.stand_theta() + 0.3 * rng.standard_normal(model.ndof) * ([1, 1, 0.2][:model.ndof])
    thd = rng.standard_normal(model.ndof)
    h = 1e-5
    J = model.jacobian(th)
    Jfd = np.column_stack([(model.absolute_q(th + h * e) - model.absolute_q(th - h * e)) / (2 * h)
                           for e in np.eye(model.ndof)])
    assert np.allclose(J, Jfd, atol=1e-8)
    # q_ddot at theta_ddot = 0 is the bias d2q/ds2 along theta_dot
    h = 1e-4
    bias_fd = (model.absolute_q(th + h * thd) - 2 * model.absolute_q(th) + model.absolute_q(th - h * thd)) / h ** 2
    K = model._jets(th, thd)
    assert np.allclose(K.b.reshape(-1), bias_fd, atol=2e-6)
    assert np.allclose(model.absolute_qd(th, thd), J @ thd, atol=1e-14)


def test_theta_from_lengths_roundtrip(rev, slot):
    rng = np.random.default_rng(3)
    for k in range(20):
        th = rev.stand_theta() + rng.uniform(-0.4, 0.4, 2)
        assert np.allclose(rev.theta_from_lengths(rev.lengths(th)), th, atol=1e-11)
        assert np.allclose(rev.theta_from_lengths(rev.lengths(th), near=th + 0.01), th, atol=1e-11)
    # rows continue the branch from the previous row
    path = rev.stand_theta() + np.outer(np.linspace(0, 0.3, 7), [-1.0, 1.0])
    assert np.allclose(rev.theta_from_lengths(rev.lengths(path)), path, atol=1e-11)
    ths = slot.stand_theta() + np.array([0.2, -0.3, 0.05])
    assert np.allclose(slot.theta_from_lengths(slot.lengths(ths), s=ths[2]), ths, atol=1e-12)
    with pytest.raises(UnreachableError):
        rev.theta_from_lengths([0.80, 0.60])          # |C - A| <= 0.75


@pytest.mark.parametrize("load", [(0.0, 0.0), (0.0, 300.0), (-120.0, 250.0)])
def test_statics_balance_and_virtual_work(rev, load):
    th = rev.stand_theta() + np.array([-0.15, 0.2])
    L = rev.lengths(th)
    F, R = rev.statics(L, foot_load=load)
    # Newton-Euler vs virtual work on the reduced equations
    assert np.allclose(F, rev.statics_reduced(th, foot_load=load), rtol=1e-11, atol=1e-9)
    # whole leg: frame reactions + foot load + gravity = 0, forces and moments about the origin
    q = rev.absolute_q(th)
    names = [j["name"] for j in DATA["joint"]]
    total, moment = np.array(load, float) + MASS.sum() * G, 0.0
    foot = rev.foot(th)
    moment += foot[0] * load[1] - foot[1] * load[0]
    for i in range(6):
        moment += q[3 * i] * MASS[i] * G[1] - q[3 * i + 1] * MASS[i] * G[0]
    for k, j in enumerate(DATA["joint"]):
        if j["kind"] == "revolute_to_frame":
            total = total + R[k, :2]
            p = np.array(DATA["frame"][j["point"]])
            moment += p[0] * R[k, 1] - p[1] * R[k, 0]
            # the reported moment is that of the force at the pin about the CoM
            r = p - pose(q, j["body"])[:2]
            assert abs(R[k, 2] - (r[0] * R[k, 1] - r[1] * R[k, 0])) < 1e-10
    assert np.allclose(total, 0.0, atol=1e-10) and abs(moment) < 1e-10
    assert names.index("A") == 0


def test_statics_stand_values(rev):
    L = rev.lengths(rev.stand_theta())
    F0, R0 = rev.statics(L)
    F3, R3 = rev.statics(L, foot_load=(0.0, 300.0))
    assert np.allclose(F0, [-93.9289570004631, 1.3866057692308], rtol=1e-11)
    assert np.allclose(F3, [699.7964363189138, 1.3866057692308], rtol=1e-11)
    # the prismatic reactions are normal to the actuator axes
    for k, j in enumerate(DATA["joint"]):
        if j["kind"] == "prismatic":
            ph = pose(rev.absolute_q(rev.stand_theta()), j["bodies"][0])[2]
            assert abs(R0[k, :2] @ u(ph)) < 1e-11
    # rest with the statics forces: zero accelerations
    acc = rev.accelerations(rev.stand_theta(), [0, 0], F3, foot_load=(0.0, 300.0))
    assert np.max(np.abs(acc)) < 1e-10


def test_reactions_match_multiplier_formulation(rev, slot):
    """Newton-Euler reactions == -Phi_q^T lambda of leg.toml's joints, in a dynamic state."""
    for model, variant in ((rev, "revolute"), (slot, "slot")):
        load = (30.0, 80.0)
        F = [150.0, -60.0]
        r = model.simulate(0.05, t_eval=[0.05], actuators=[ForceCommand(F[0]), ForceCommand(F[1])],
                           foot_load=load, thetad0=[0.5, -1.0, 0.3][:model.ndof])
        Rm, res = multiplier_reactions(model, r.q[-1], r.qdd[-1], F, np.array(load), variant)
        assert res < 1e-7
        assert np.allclose(r.reactions[-1], Rm, atol=2e-6)
        assert r.ne_residual[-1] < 1e-9
    # statics too
    th = rev.stand_theta()
    F3, R3 = rev.statics(rev.lengths(th), foot_load=(0.0, 300.0))
    Rm, res = multiplier_reactions(rev, rev.absolute_q(th), np.zeros(18), F3, np.array([0.0, 300.0]),
                                   "revolute")
    assert res < 1e-7 and np.allclose(R3, Rm, atol=2e-6)


def test_energy_conserved_revolute(rev):
    r = rev.simulate(1.0, t_eval=np.linspace(0.0, 1.0, 101),
                     actuators=[ForceCommand(-60.0), ForceCommand(20.0)])
    scale = max(np.max(r.kinetic), abs(r.energy[0]))
    assert np.max(r.kinetic) > 1.0                     # it really moves
    assert np.max(np.abs(r.energy - r.energy[0])) / scale < 1e-9
    assert not r.out_of_stroke
    assert np.max(r.ne_residual) < 1e-9


def test_energy_conserved_slot(slot):
    r = slot.simulate(0.5, t_eval=np.linspace(0.0, 0.5, 51),
                      actuators=[ForceCommand(-80.0), ForceCommand(10.0)], foot_load=(20.0, 40.0))
    scale = max(np.max(r.kinetic), abs(r.energy[0]))
    assert np.max(r.kinetic) > 0.1
    assert np.max(np.abs(r.energy - r.energy[0])) / scale < 1e-9


def test_free_fall_reference_value(rev):
    r = rev.simulate(0.1, t_eval=[0.0, 0.1], actuators=[ForceCommand(0.0), ForceCommand(0.0)])
    assert np.allclose(r.foot[0], [0.4330127018922, -0.85], atol=1e-12)
    assert np.allclose(r.foot[-1], [0.4490536717173, -0.8983740317501], atol=2e-12)


def test_time_reversal(rev):
    F = [ForceCommand(-60.0), ForceCommand(20.0)]
    a = rev.simulate(0.3, t_eval=[0.3], actuators=F, thetad0=[0.4, -0.7])
    b = rev.simulate(0.3, t_eval=[0.3], actuators=F, theta0=a.theta[-1], thetad0=-a.thetad[-1])
    assert np.allclose(b.theta[-1], rev.stand_theta(), atol=1e-11)
    assert np.allclose(b.thetad[-1], [-0.4, 0.7], atol=1e-10)


def test_tolerance_convergence(rev):
    kw = dict(t_eval=[0.5], actuators=[LengthCommand(Sinusoid(0.62, 0.03, 2.0)), ForceCommand(20.0)])
    lo = rev.simulate(0.5, rtol=1e-9, atol=1e-9, **kw)
    mid = rev.simulate(0.5, **kw)
    hi = rev.simulate(0.5, rtol=1e-13, atol=1e-13, **kw)
    assert np.max(np.abs(mid.theta[-1] - hi.theta[-1])) < 1e-10
    assert np.max(np.abs(lo.theta[-1] - hi.theta[-1])) < 1e-6
    assert np.max(np.abs(mid.reactions[-1] - hi.reactions[-1])) < 1e-7


def test_force_step_breakpoint(rev):
    """A step at t0 equals two runs glued at t0."""
    step = rev.simulate(0.1, t_eval=[0.04, 0.1], actuators=[ForceCommand(Step(-90.0, 200.0, 0.04)),
                                                             ForceCommand(0.0)])
    a = rev.simulate(0.04, t_eval=[0.04], actuators=[ForceCommand(-90.0), ForceCommand(0.0)])
    b = rev.simulate(0.06, t_eval=[0.06], actuators=[ForceCommand(200.0), ForceCommand(0.0)],
                     theta0=a.theta[-1], thetad0=a.thetad[-1])
    assert np.allclose(step.theta[0], a.theta[-1], atol=1e-13)
    assert np.allclose(step.theta[-1], b.theta[-1], atol=1e-12)
    assert step.actuator_forces[0, 0] == 200.0           # the value after the step at t0


def test_servo_equilibrium_is_statics(rev):
    """Start where kp (l_cmd - l) equals the statics forces: the servo holds the leg at rest."""
    from scipy.optimize import fsolve
    Lc = rev.lengths(rev.stand_theta())
    kp = np.array([a["servo_kp"] for a in DATA["actuator"]])
    l_eq = fsolve(lambda l: kp * (Lc - l) - rev.statics(l)[0], Lc, xtol=1e-12)
    F_eq = rev.statics(l_eq)[0]
    assert np.allclose(kp * (Lc - l_eq), F_eq, atol=1e-8)
    r = rev.simulate(0.5, t_eval=[0.0, 0.5], actuators=[LengthCommand(Lc[0]), LengthCommand(Lc[1])],
                     theta0=rev.theta_from_lengths(l_eq))
    assert not r.saturated.any()
    assert np.allclose(r.lengths[-1], l_eq, atol=1e-10)
    assert np.allclose(r.actuator_forces, F_eq, atol=1e-5)
    assert np.max(np.abs(r.thetadd)) < 1e-6


def test_servo_saturates(rev):
    L = rev.lengths(rev.stand_theta())
    r = rev.simulate(0.1, t_eval=np.linspace(0, 0.1, 11),
                     actuators=[LengthCommand(Step(L[0], 0.55, 0.02)), LengthCommand(L[1])])
    assert r.saturated[:, 0].any()
    assert np.max(np.abs(r.actuator_forces)) <= 1500.0


def test_inverse_dynamics_matches_forward(rev):
    L = rev.lengths(rev.stand_theta())
    r = rev.simulate(0.5, t_eval=np.linspace(0, 0.5, 26), foot_load=(0.0, 50.0),
                     actuators=[LengthCommand(Sinusoid(L[0], 0.03, 2.0)), LengthCommand(Sinusoid(L[1], 0.02, 3.0))])
    idr = rev.inverse_dynamics(r.lengths, r.length_rates, r.length_accels, foot_load=(0.0, 50.0))
    assert np.allclose(idr.theta, r.theta, atol=1e-12)
    assert np.allclose(idr.actuator_forces, r.actuator_forces, atol=1e-8)
    assert np.allclose(idr.actuator_forces_reduced, r.actuator_forces, atol=1e-8)
    assert np.allclose(idr.reactions, r.reactions, atol=1e-8)
    # a prescribed sinusoid, single instant, statics limit
    s = Sinusoid(L[0], 0.0, 1.0)
    one = rev.inverse_dynamics([s(0.0), L[1]], [s.rate(0.0), 0.0], [s.accel(0.0), 0.0])
    assert np.allclose(one.actuator_forces, rev.statics(L)[0], atol=1e-10)


def test_slot_variant(slot):
    r = slot.simulate(0.1, t_eval=[0.05, 0.1], actuators=[ForceCommand(-90.0), ForceCommand(5.0)],
                      foot_load=(10.0, 30.0))
    kD = [j["name"] for j in DATA["joint"]].index("D")
    for q, R in zip(r.q, r.reactions):
        phi6 = pose(q, 6)[2]
        assert abs(R[kD, :2] @ u(phi6)) < 1e-10            # normal to the shank axis
        assert np.linalg.norm(R[kD, :2]) > 1e-3
    assert np.max(r.ne_residual) < 1e-9
    with pytest.raises(NoEquilibriumError):
        slot.statics(slot.lengths(slot.stand_theta()), foot_load=(0.0, 300.0))


def test_statics_sweep(rev):
    w = rev.statics_sweep(5, foot_load=(0.0, 300.0))
    assert w.n_poses + w.n_failed == 25 and w.n_failed >= 5     # upper 0.8 m is unreachable
    F3, R3 = rev.statics(rev.lengths(rev.stand_theta()), foot_load=(0.0, 300.0))
    assert np.all(w.max_actuator_force > 0) and w.max_reaction.shape == (8,)
    for k in range(8):
        F, R = rev.statics(w.reaction_at_lengths[k], foot_load=(0.0, 300.0))
        assert abs(np.hypot(*R[k, :2]) - w.max_reaction[k]) < 1e-9
