"""Stroke stops of the two-leg robot (models/robot.toml) that hold.

With both feet stuck and all four actuators on a stop the dynamics has 40 rows on 39
coordinates: one row depends on the others (the stance's self-stress). The core's
factorization drops that many dependent rows (factor_build, Layout::surplus; their
multipliers 0), so the stops hold; the normal ground forces, which the self-stress does not
change, must be the statics' of the bench's reference (RobotModel.statics), and the stop
forces the reference's actuator forces plus some multiple of its self-stress.
"""
from __future__ import annotations

import sys

import numpy as np
import pytest

import legsim

from conftest import ROOT, robot_sim as _robot_sim

try:
    import legsim_bench.reference  # noqa: F401
except ImportError:  # the bench is not installed: its source tree
    sys.path.insert(0, str(ROOT / "bench"))
from legsim_bench.reference.robot import RobotModel  # noqa: E402

ROBOT = ROOT / "models" / "robot.toml"
LMIN = np.array([0.40, 0.35, 0.40, 0.35])  # the strokes' minima (m): upper, lower per leg


@pytest.fixture(scope="module")
def ref():
    return RobotModel.from_toml(ROBOT)


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_four_stops_hold_on_two_stuck_feet(ref, integrator):
    s = _robot_sim(integrator=integrator)
    s.assemble_on_ground(LMIN)
    for a in range(4):
        s.command_force(a, 0.0)
    q0 = s.q.copy()
    shortest = np.full(4, np.inf)
    for _ in range(300):
        s.step(1)
        shortest = np.minimum(shortest, s.actuator_lengths()[0])
    # the stops hold every step: no actuator passes its minimum, the robot stays where it is
    assert np.all(shortest >= LMIN - 1e-9), shortest - LMIN
    assert np.max(np.abs(s.q - q0)) < 1e-9
    c = s.contacts()
    assert list(c["state"]) == ["stuck", "stuck"]
    assert "near_singular" not in s.events()
    # the stops push (their force extends the rod) and they balance the robot as the
    # statics does: N is determinate, the stop forces are the reference's plus a self-stress
    st = ref.statics(LMIN)
    F = s.actuator_forces()
    assert np.all(F >= 0)
    assert np.max(np.abs(c["normal"] - st.normal)) < 1e-6
    nF = st.self_stress[-4:]
    ds = float((F - st.actuator_forces) @ nF / (nF @ nF))
    assert np.max(np.abs(F - st.actuator_forces - ds * nF)) < 1e-6
    nT = st.self_stress[-8:-4].reshape(2, 2) @ ref.ground.tangent
    assert np.max(np.abs(c["tangential"] - st.tangential - ds * nT)) < 1e-6


@pytest.mark.parametrize("integrator,command", [("galpha", "servo"), ("rk4", "force"),
                                                ("galpha", "force")])
def test_crouch_onto_all_four_stops_is_simulable(integrator, command):
    # the robot folds onto its four lower stops, leaves the ground and lands on them
    s = _robot_sim(integrator=integrator)
    s.assemble_on_ground()
    for a in range(4):
        if command == "servo":
            s.command_length(a, LMIN[a])
        else:
            s.command_force(a, -1500.0)
    shortest = np.full(4, np.inf)
    for _ in range(800):
        s.step(1)
        shortest = np.minimum(shortest, s.actuator_lengths()[0])
    assert {"stroke_min", "liftoff", "touchdown"} <= set(s.events())
    assert np.all(shortest >= LMIN - 1e-9), shortest - LMIN
    assert np.max(np.abs(s.actuator_lengths()[0] - LMIN)) < 1e-9
    c = s.contacts()
    assert list(c["state"]) == ["stuck", "stuck"]
    assert np.all(c["normal"] > 0)
    # at rest on its stops and feet: the ground carries the robot's weight
    assert np.max(np.abs(s.qd)) < 1e-6
    weight = -sum(s.model.masses) * s.model.gravity[1]
    assert abs(c["normal"].sum() - weight) < 1e-6 * weight


def _robot_file(tmp_path, mu):
    """models/robot.toml with the ground's friction mu (static and kinetic)."""
    text = ROBOT.read_text().replace('file = "leg.toml"', f'file = "{ROOT / "models" / "leg.toml"}"')
    text = text.replace("mu_static = 0.6", f"mu_static = {mu}").replace("mu_kinetic = 0.5",
                                                                          f"mu_kinetic = {mu}")
    path = tmp_path / f"robot_mu{mu}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
@pytest.mark.parametrize("mu,dy,steps", [(0.6, 10.0, 1600), (0.6, -1.0, 200), (0.0, -1.0, 200)])
def test_stops_are_checked_after_a_touchdown_s_projection(tmp_path, integrator, mu, dy, steps):
    # the robot dropped from 10 m, or started with its feet 1 m inside the ground: the
    # touchdown's projection puts the feet on the line and must leave no actuator past a stop
    _robot_sim()  # skips when the build has no room for the robot
    s = legsim.Sim(str(_robot_file(tmp_path, mu)), integrator=integrator)
    q = s.assemble_on_ground().copy()
    s.set_contact(0, "free")
    s.set_contact(1, "free")
    q[1::3] += dy
    s.set_state(q)
    lmax = np.array([hi for _, hi in s.model.strokes])
    worst = -np.inf
    for _ in range(steps):
        s.step(1)
        L = s.actuator_lengths()[0]
        worst = max(worst, np.max(LMIN - L), np.max(L - lmax))
    assert "touchdown" in s.events() and "stroke_min" in s.events()
    assert worst <= 1e-9, worst


@pytest.mark.parametrize("above", [1e-9, 1e-6])
@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_stops_reached_together_on_stuck_feet_hold(integrator, above):
    """The upper actuators started `above` their minima, the lower ones at theirs, zero force:
    the four stops together would not agree (the stance with both feet stuck leaves the
    lengths one relation: the fourth follows from the other three). The stops that arrive
    hold, no actuator passes its end; every step OK, no energy made (the robot settles)."""
    s = _robot_sim(integrator=integrator)
    start = LMIN + np.array([above, 0.0, above, 0.0])
    s.assemble_on_ground(start)
    for a in range(4):
        s.command_force(a, 0.0)
    m = np.repeat(s.model.masses, 3)
    m[2::3] = s.model.inertias

    def energy():
        return 0.5 * float(m @ (s.qd * s.qd)) + 9.81 * float(s.model.masses @ s.q[1::3])

    e0 = energy()
    shortest = np.full(4, np.inf)
    for _ in range(300):
        s.step(1)
        L = s.actuator_lengths()[0]
        shortest = np.minimum(shortest, L)
        assert energy() <= e0 + 1e-9
    L = s.actuator_lengths()[0]
    assert np.all(shortest >= LMIN - 1e-9), shortest - LMIN
    # the lower actuators start on their ends: their stops arrive at t = 0 (located at the
    # step's start), and with them held the stance ties the upper lengths by one relation:
    # the robot rests there, the uppers within their strokes (above their minima)
    assert np.max(np.abs(L[[1, 3]] - LMIN[[1, 3]])) < 1e-9
    assert np.max(np.abs(s.qd)) < 1e-9
    assert list(s.contacts()["state"]) == ["stuck", "stuck"]
