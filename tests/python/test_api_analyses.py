"""legsim.Sim's analyses against independent references: virtual work and finite
differences of the assembly, the balance of the whole leg, facts of models/leg.toml."""
from __future__ import annotations

import math

import numpy as np
import pytest

import legsim

G = np.array([0.0, -9.81])  # m/s^2
# stand-pose facts of models/leg.toml (its comment)
STAND_LENGTHS = (0.6614378, 0.6244998)
STAND_FOOT = (0.4330127, -0.85)
STAND_PHI1, STAND_PHI4 = 0.7137244, 0.7661626
FRAME_JOINTS = [0, 2, 3]  # A, B_thigh, B_lower: revolute_to_frame
FOOT_LOAD = np.array([30.0, 250.0])  # N, world, at the foot


def tol(precision, double, float_):
    return double if precision == "double" else float_


def test_stand_pose_facts(stand, precision):
    s = stand(precision=precision)
    assert (s.n_bodies, s.n_coords, s.n_constraints, s.n_joints, s.n_actuators,
            s.n_forces) == (6, 18, 16, 8, 2, 1)
    l, rate = s.actuator_lengths()
    t = tol(precision, 1e-7, 1e-5)
    np.testing.assert_allclose(l, STAND_LENGTHS, atol=t)
    np.testing.assert_array_equal(rate, 0.0)
    np.testing.assert_allclose(s.foot(), STAND_FOOT, atol=t)
    q = s.q
    assert q[2] == pytest.approx(STAND_PHI1, abs=t) and q[11] == pytest.approx(STAND_PHI4, abs=t)
    assert q[8] == pytest.approx(math.pi / 3, abs=t) and q[17] == pytest.approx(0.0, abs=t)
    assert s.constraint_residual() <= s.options["newton_tol"]
    np.testing.assert_array_equal(s.qd, 0.0)
    rep = s.report()
    assert 1.0 <= rep.condition < legsim.COND_WARN and rep.event_names() == []


def test_slot_variant_from_the_file(stand, model_toml):
    """The paper's knee (eq. (18)): one equation less, the same stand pose."""
    s = stand(str(model_toml), variant="slot")
    assert s.variant == "slot" and s.n_constraints == 15 and s.model.joint_names[-1] == "D"
    np.testing.assert_allclose(s.foot(), STAND_FOOT, atol=1e-7)
    assert s.constraint_residual() <= 1e-10


def _potential(s: legsim.Sim, masses, foot_load) -> float:
    """Potential (J) of gravity and of a constant foot load in the current pose."""
    q = s.q.reshape(-1, 3)
    return float(-np.sum(masses * (q[:, :2] @ G)) - foot_load @ s.foot())


def test_statics_is_virtual_work(stand, precision):
    """Equilibrium: the actuator forces' virtual work balances the loads',
    F_k = dV/dl_k, with V from central differences of assembled poses."""
    s = stand(precision=precision)
    s.set_force("foot_load", FOOT_LOAD)
    F = s.statics()
    m = s.model.masses
    l0, _ = s.actuator_lengths()
    q0 = s.q
    eps = tol(precision, 1e-5, 2e-3)
    dV = []
    for k in range(2):
        V = []
        for sgn in (1, -1):
            s.set_state(q0)
            s.assemble(l0 + sgn * eps * np.eye(2)[k])
            V.append(_potential(s, m, FOOT_LOAD))
        dV.append((V[0] - V[1]) / (2 * eps))
    np.testing.assert_allclose(F, dV, rtol=tol(precision, 1e-7, 2e-3), atol=tol(precision, 1e-6, 0.2))
    assert abs(F[0]) > 100.0  # the foot load is felt


def test_statics_reactions_balance_the_whole_leg(stand, precision):
    """The frame joints hold the weight and the foot load, forces and moments."""
    s = stand(precision=precision)
    s.set_force(0, FOOT_LOAD)
    s.statics()
    R = s.reactions()
    q = s.q.reshape(-1, 3)
    m = s.model.masses
    weight = m[:, None] * G[None, :]
    bodies = [0, 2, 3]  # the first-listed body of A, B_thigh, B_lower
    # float: the balance is as good as the float statics, whose reactions move by up to
    # 1e-5 of the largest one when the stand pose moves by one ulp (measured: the force
    # residual 1.4e-3 N median, 4.6e-3 N worst of 60 such poses, largest reaction 536 N)
    t = tol(precision, 1e-9, 1e-5 * np.max(np.abs(R)))
    force = R[FRAME_JOINTS, :2].sum(axis=0) + weight.sum(axis=0) + FOOT_LOAD
    np.testing.assert_allclose(force, 0.0, atol=t)

    def cross(r, f):
        return r[0] * f[1] - r[1] * f[0]
    # moments about the world origin: each reaction's moment is about its body's centre
    M = sum(cross(q[b, :2], R[j, :2]) + R[j, 2] for j, b in zip(FRAME_JOINTS, bodies))
    M += sum(cross(q[i, :2], weight[i]) for i in range(s.n_bodies))
    M += cross(s.foot(), FOOT_LOAD)
    assert abs(M) < t
    assert np.max(np.abs(R)) > 50.0


def test_inverse_dynamics_at_rest_is_statics(stand, precision):
    s = stand(precision=precision)
    F = s.statics()
    R = s.reactions()
    Fid = s.inverse_dynamics(STAND_LENGTHS, [0.0, 0.0], [0.0, 0.0])
    t = tol(precision, 1e-5, 1e-2)
    np.testing.assert_allclose(Fid, F, atol=t)
    np.testing.assert_allclose(s.reactions(), R, atol=t)


def test_velocity_and_acceleration_analysis_are_derivatives_of_the_assembly(stand):
    """q(t) assembled at l(t) = l0 + r t + a t^2 / 2: central differences give qd, qdd."""
    s = stand(newton_tol=1e-13)
    l0, _ = s.actuator_lengths()
    q0 = s.q
    r, a = np.array([0.05, -0.03]), np.array([0.4, 0.7])
    h = 1e-3
    qs = {}
    for t in (-h, h):
        s.set_state(q0)
        qs[t] = s.assemble(l0 + r * t + 0.5 * a * t * t)
    s.set_state(q0)
    s.assemble(l0)
    qd = s.velocity_analysis(r)
    np.testing.assert_allclose(qd, (qs[h] - qs[-h]) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(s.actuator_lengths()[1], r, atol=1e-12)
    J = s.jacobian()
    assert np.max(np.abs(J @ qd)) < 1e-12  # the joints move rigidly
    qdd = s.acceleration_analysis(a)
    np.testing.assert_allclose(qdd, (qs[h] - 2 * q0 + qs[-h]) / h ** 2, atol=1e-5)
    assert np.max(np.abs(qdd)) > 0.1


def test_statics_sweep_reports_what_statics_gives_at_its_worst_points(stand):
    s = stand()
    n = 5
    w = s.statics_sweep(n)
    assert w.n_poses + w.n_failed == n * n and w.n_poses > 0
    assert w.max_reaction_n.shape == (8,) and w.at_length_m.shape == (8, 2)
    grid = [np.linspace(*s.model.strokes[k], n) for k in range(2)]
    for a in range(2):  # each actuator's worst point is a grid point, and statics agrees
        l = w.actuator_at_length_m[a]
        assert any(np.isclose(l[0], grid[0], atol=1e-12)) and any(np.isclose(l[1], grid[1], atol=1e-12))
        s.assemble_pose("stand")
        s.assemble(l)
        assert abs(s.statics()[a]) == pytest.approx(w.max_actuator_force_n[a], rel=1e-9)
    for j in range(8):
        s.assemble_pose("stand")
        s.assemble(w.at_length_m[j])
        s.statics()
        assert np.hypot(*s.reactions()[j, :2]) == pytest.approx(w.max_reaction_n[j], rel=1e-9)


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_free_fall_stays_on_the_constraints(stand, integrator):
    s = stand(integrator=integrator, step=1e-4)
    s.run(0.1)
    assert s.time == pytest.approx(0.1, abs=1e-12) and s.step_count == 1000
    assert s.foot()[1] < STAND_FOOT[1] - 0.01  # it falls
    phi, mx = s.constraints()
    assert phi.shape == (16,) and mx <= 1e-9 and mx == pytest.approx(np.max(np.abs(phi)))
    assert np.max(np.abs(s.jacobian() @ s.qd)) < (1e-8 if integrator == "rk4" else 1e-6)
    assert s.reactions().shape == (8, 3) and s.multipliers().shape == (16,)
    assert s.qdd.shape == (18,) and np.all(np.isfinite(s.qdd))
    with pytest.raises(ValueError, match="whole number of steps"):
        s.run(0.00015)


def test_float_is_close_to_double(stand):
    if not legsim.library_available("float"):
        pytest.skip("liblegsim_f32.so is not built")
    d, f = stand(precision="double"), stand(precision="float")
    assert f.library.config["LEGSIM_USE_FLOAT"] == 1 and f.q.dtype == np.float64
    np.testing.assert_allclose(f.statics(), d.statics(), atol=5e-3)
    d.step(100)
    f.step(100)
    assert np.max(np.abs(f.q - d.q)) < 1e-4


def test_length_servo_holds_its_command(stand):
    s = stand(integrator="galpha")
    s.command_length("upper", 0.68)
    s.command_length("lower", 0.60)
    s.run(1.5)
    l, _ = s.actuator_lengths()
    # the PD servo's static error under gravity: about 94 N / kp (20 kN/m) ~ 5 mm
    np.testing.assert_allclose(l, [0.68, 0.60], atol=6e-3)
    assert abs(l[0] - 0.68) > 1e-4  # a servo, not a constraint
    np.testing.assert_allclose(np.abs(s.actuator_forces()), 20000.0 * np.abs(l - [0.68, 0.60]),
                               rtol=0.05, atol=1.0)
