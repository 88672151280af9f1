"""The swing of scenes/robot_swing.toml through the Python API (docs/design/robot-on-ground.md
section 8): the left foot lifts off, swings and touches down stuck while the right foot holds.

The touchdown impulse is checked against the bench's reference: the pre-impact state is the
core's own step without the touchdown (a twin whose model has the right foot only, started
from the state before the touchdown step), and RobotModel's Newton-Euler columns (its own
joints and feet, not the core's Jacobian) give the inelastic impact at the landed pose:
v+ = v- + M^-1 A x, A^T v+ = 0, so the energy lost is Carnot's 1/2 (A^T v-)^T (A^T M^-1 A)^-1
(A^T v-). Balance (RK4): with the feet's ground forces and gravity, the robot's momentum rate.
"""
from __future__ import annotations

import sys

import numpy as np
import pytest

import legsim

from conftest import ROOT

try:
    import legsim_bench.reference  # noqa: F401
except ImportError:  # the bench is not installed: its source tree
    sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.reference.robot import RobotModel  # noqa: E402
from test_robot import _robot_sim  # noqa: E402

L_SERVO = [0.6546600993028372, 0.6164024580497154, 0.6546600993028372, 0.6164024580497155]
L_STAND = [0.6614378277661477, 0.6244997998398398, 0.6614378277661477, 0.6244997998398398]
H = 1e-3


def _commands(t):
    """The set-points of scenes/robot_swing.toml at t."""
    L = list(L_STAND)
    if t >= 0.08 - 1e-12:
        L[2] -= 0.020            # the left upper swings the foot inward
    if t >= 0.05 - 1e-12:
        L[3] -= 0.030            # the left lower lifts it
    return L


def _command(s, t):
    for a, L in enumerate(_commands(t)):
        s.command_length(a, L)


def _right_foot_only(base: legsim.Sim, step: float) -> legsim.Sim:
    """The same robot with the left foot's contact left out, stepped by `step`: its step is
    the core's step of a free left foot, with no touchdown in it."""
    m = base.model
    desc = type(m.desc).from_buffer_copy(m.desc)
    desc.n_contacts = 1
    return legsim.Sim(legsim.Model(desc, m.library, m.variant, "robot, right foot only"),
                      integrator=base.integrator, step=step)


@pytest.fixture(scope="module")
def ref():
    return RobotModel.from_toml(ROOT / "models" / "robot.toml")


def _masses(s):
    m = np.repeat(s.model.masses, 3)
    m[2::3] = s.model.inertias
    return m


def _swing(integrator):
    """Runs the swing to its touchdown step: (sim, event sequence, worst momentum balance,
    the state before the touchdown step)."""
    s = _robot_sim(integrator=integrator)
    s.assemble_on_ground(L_SERVO)
    masses = _masses(s)
    weight = masses[0::3].sum() * 9.81
    seq, balance = [], 0.0
    before = None
    for k in range(300):
        t = k * H
        _command(s, t)
        before = (s.q.copy(), s.qd.copy(), t)
        s.step(1)
        ev = s.events()
        s.clear_events()
        c = s.contacts()
        if ev:
            seq.append((round((k + 1) * H, 6), ev, list(c["state"])))
        # balance: gravity and the ground forces give the whole robot's momentum rate
        rate = np.array([masses[0::3] @ s.qdd[0::3], masses[1::3] @ s.qdd[1::3]])
        ground = np.array([c["tangential"].sum(), c["normal"].sum() - weight])
        balance = max(balance, np.max(np.abs(rate - ground)) / weight)
        if "touchdown" in ev:
            break
    return s, seq, balance, before


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_swing_lifts_touches_down_and_loses_carnots_energy(ref, integrator):
    """The touchdown is located inside its step at t_e: the pre-impact state is a twin's
    single step from the step's start to t_e (the core's own part step, of that size), the
    impact the reference's at that pose, and the rest of the step a twin's step from the
    reference's post-impact state on both feet stuck."""
    s, seq, balance, before = _swing(integrator)
    print(integrator, seq, "balance", balance)
    assert seq == [(0.051, ["liftoff"], ["stuck", "free"]), (0.103, ["touchdown"], ["stuck", "stuck"])]
    if integrator == "rk4":   # its qdd is the dynamics' at the state (generalized-alpha's is
        assert balance < 1e-9  # its algorithmic acceleration)

    c = s.contacts()
    P = c["impulse"][1]
    assert P[0] > 0 and abs(P[1]) <= 0.6 * P[0]               # inside the static cone: stuck
    q0, v0, t0 = before
    t_e = s.contact_event_time(1)
    assert t0 < t_e < t0 + H
    if integrator != "rk4":   # the twins below restart generalized-alpha's history: not its steps
        s4 = _swing("rk4")[0]
        assert abs(s4.contact_event_time(1) - t_e) < 1e-2 * H    # its trajectory: O(h^2)
        assert np.allclose(P, s4.contacts()["impulse"][1], atol=2e-3)   # RK4's, to O(h^2)
        return
    # the pre-impact state: the core's part step to t_e, taken by a twin without the left foot
    twin = _right_foot_only(s, t_e - t0)
    twin.set_state(q0, v0, t0)
    _command(twin, t0)
    twin.set_contact(0, "stuck")
    assert np.max(np.abs(twin.qd - v0)) < 1e-12           # the right foot was stuck already
    twin.step(1)
    q_minus, v_minus = twin.q, twin.qd

    # the reference's impact at the landed pose: its Newton-Euler columns (32 joint
    # reactions, 2 x 2 ground forces), v+ = v- + M^-1 A x with A^T v+ = 0
    A, _, _, gcol = ref._ne_system(q_minus, np.zeros_like(q_minus), np.zeros(4), (0.0, 0.0, 0.0), np.zeros(2))
    Minv = 1.0 / ref._Mflat
    D = A.T @ (Minv[:, None] * A)
    x = -np.linalg.solve(D, A.T @ v_minus)
    v_ref = v_minus + Minv * (A @ x)
    P_ref = x[gcol + 2:gcol + 4]
    P_ref = np.array([P_ref @ ref.ground.normal, P_ref @ ref.ground.tangent])
    ke = lambda v: 0.5 * float(ref._Mflat @ (v * v))  # noqa: E731
    lost_ref = ke(v_minus) - ke(v_ref)
    carnot = 0.5 * float((A.T @ v_minus) @ np.linalg.solve(D, A.T @ v_minus))
    assert abs(lost_ref - carnot) < 1e-12

    # the rest of the step: a twin on both feet stuck from the reference's post-impact state
    rest = _robot_sim(integrator=integrator, step=t0 + H - t_e)
    rest.set_state(q_minus, v_ref, t_e)
    _command(rest, t0)
    rest.set_contact(0, "stuck")
    rest.set_contact(1, "stuck")
    rest.step(1)
    print(f"{integrator}: t_e {t_e:.12f} s, impulse {P} N s (reference {P_ref}), Carnot "
          f"{carnot:.12f} J; end state vs the twins' |q| {np.max(np.abs(s.q - rest.q)):.2e} "
          f"|v| {np.max(np.abs(s.qd - rest.qd)):.2e}")
    assert np.max(np.abs(P - P_ref)) < 1e-6 * np.max(np.abs(P_ref))
    assert np.max(np.abs(s.q - rest.q)) < 1e-9
    assert np.max(np.abs(s.qd - rest.qd)) < 1e-6 * np.max(np.abs(v_minus))
