"""Inverse dynamics of the robot with both feet stuck (docs/design/robot-on-ground.md
section 8): three lengths drive its three degrees of freedom, the fourth actuator follows,
and the forces of all four (one self-stress too many) are fixed by the statics_rule.

Checked against the bench's independent reference (RobotModel.inverse_dynamics: minimal
coordinates, Newton-Euler with the rule) and against legsim's own forward dynamics (the
forces fed back reproduce the motion).
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
from test_robot import _robot_sim, _robot_with_box_load  # noqa: E402

FOLLOW = 3   # left.lower follows
AMP = np.array([0.010, -0.015, 0.008, 0.0])     # m
FREQ = np.array([1.5, 1.0, 2.0, 0.0])           # Hz
PHASE = np.array([0.0, 0.7, 1.9, 0.0])          # rad


@pytest.fixture(scope="module")
def ref():
    return RobotModel.from_toml(ROOT / "models" / "robot.toml")


def _schedule(L0, t):
    w = 2 * np.pi * FREQ
    a = w * t + PHASE
    return L0 + AMP * np.sin(a), AMP * w * np.cos(a), -AMP * w * w * np.sin(a)


def _weight(s):
    return s.model.masses.sum() * 9.81


@pytest.mark.parametrize("rule", ["equal_friction", "min_tangential"])
@pytest.mark.parametrize("load", [(0.0, 0.0, 0.0), (40.0, -150.0, 12.0)])
def test_inverse_dynamics_on_ground_matches_the_reference(ref, rule, load):
    s = _robot_with_box_load(load)
    s.set_options(statics_rule=rule)
    L0 = ref.stand_lengths()
    s.assemble_on_ground(L0)
    start = ref.assemble(L0)
    scale = _weight(s)
    worst = np.zeros(6)
    guess = None
    masses = np.repeat(s.model.masses, 3)
    masses[2::3] = s.model.inertias
    for t in np.linspace(0.0, 0.6, 13):
        L, Ld, Ldd = _schedule(L0, t)
        F, Lo, Ldo, Lddo = s.inverse_dynamics_on_ground(L, Ld, Ldd, follow=["left.lower"])
        r = ref.inverse_dynamics(L, Ld, Ldd, follow=FOLLOW, start=start, box_load=load, rule=rule,
                                 guess=guess)
        guess = r.i
        c = s.contacts()
        assert list(c["state"]) == ["stuck", "stuck"]
        assert np.max(np.abs(c["position"] - start.feet)) < 1e-10  # the feet stay (Newton tol)
        worst = np.maximum(worst, [
            np.max(np.abs(s.q - r.q)), np.max(np.abs(s.qdd - r.qdd)),
            np.max(np.abs([Lo[3] - r.lengths[3], Ldo[3] - r.rates[3], Lddo[3] - r.accels[3]])),
            np.max(np.abs(F - r.actuator_forces)) / scale,
            np.max(np.abs(s.reactions() - r.reactions)) / scale,
            max(np.max(np.abs(c["normal"] - r.normal)), np.max(np.abs(c["tangential"] - r.tangential)))
            / scale])
        assert list(c["holds"]) == list(r.holds)
        np.testing.assert_array_equal(Lo[:3], L[:3])                    # the driven ones as given
        # balance: the ground forces, the load and the weight give the momentum rate
        qdd = s.qdd
        tg, nm = np.array([1.0, 0.0]), np.array([0.0, 1.0])
        ground = np.outer(c["normal"], nm) + np.outer(c["tangential"], tg)
        rate = np.array([np.sum(masses[0::3] * qdd[0::3]), np.sum(masses[1::3] * qdd[1::3])])
        total = ground.sum(axis=0) + np.array(load[:2]) + np.array([0.0, -scale])
        assert np.max(np.abs(total - rate)) < 1e-10 * scale
        if rule == "equal_friction":
            assert abs(c["tangential"][0] * c["normal"][1] - c["tangential"][1] * c["normal"][0]) \
                < 1e-10 * scale ** 2
        else:
            assert abs(c["tangential"][0] - c["tangential"][1]) < 1e-10 * scale
    print(rule, load, "worst q, qdd, follower, F/W, R/W, ground/W", worst)
    assert worst[0] < 1e-10 and worst[1] < 1e-8 and worst[2] < 1e-9
    assert worst[3] < 1e-10 and worst[4] < 1e-10 and worst[5] < 1e-10


def test_forces_fed_to_forward_dynamics_reproduce_the_motion(ref):
    """At each instant: the inverse dynamics' forces as force commands give its
    accelerations and ground forces back (round-off); along 0.2 s, RK4 with the forces
    held over each 1 ms step follows the driven motion to within the hold's O(h) error."""
    s = _robot_sim()
    L0 = ref.stand_lengths()
    s.assemble_on_ground(L0)
    fwd = _robot_sim()
    fwd.assemble_on_ground(L0)
    worst_qdd = worst_ground = 0.0
    for t in np.linspace(0.0, 0.5, 6):
        L, Ld, Ldd = _schedule(L0, t)
        F = s.inverse_dynamics_on_ground(L, Ld, Ldd, follow=[FOLLOW])[0]
        c = s.contacts()
        fwd.set_state(s.q, s.qd, 0.0)
        for a in range(4):
            fwd.command_force(a, F[a])
        for k in range(2):
            fwd.set_contact(k, "stuck")             # solves the dynamics at this state
        cf = fwd.contacts()
        worst_qdd = max(worst_qdd, np.max(np.abs(fwd.qdd - s.qdd)))
        worst_ground = max(worst_ground, np.max(np.abs(cf["normal"] - c["normal"])),
                           np.max(np.abs(cf["tangential"] - c["tangential"])))
    print("forward dynamics vs inverse: qdd", worst_qdd, "ground", worst_ground)
    assert worst_qdd < 1e-9 and worst_ground < 1e-8

    # runs of 0.2 s: RK4 with the forces of each step's midpoint held over it (second order
    # in h: measured 1.55e-6 m at h = 1 ms, 3.9e-7 m at 0.5 ms; with the forces of the
    # step's start held it would be first order, 7.8e-4 m at 1 ms)
    errors = []
    for h in (1e-3, 5e-4):
        fwd = _robot_sim(step=h)
        fwd.assemble_on_ground(L0)
        s.assemble_on_ground(L0)
        s.inverse_dynamics_on_ground(*_schedule(L0, 0.0), follow=[FOLLOW])
        fwd.set_state(s.q, s.qd, 0.0)
        fwd.set_contact(0, "stuck")
        fwd.set_contact(1, "stuck")
        n = int(round(0.2 / h))
        for k in range(n):
            F = s.inverse_dynamics_on_ground(*_schedule(L0, (k + 0.5) * h), follow=[FOLLOW])[0]
            for a in range(4):
                fwd.command_force(a, F[a])
            fwd.step(1)
        s.inverse_dynamics_on_ground(*_schedule(L0, n * h), follow=[FOLLOW])
        assert list(fwd.contacts()["state"]) == ["stuck", "stuck"]
        errors.append(np.max(np.abs(fwd.q - s.q)))
    print("forward runs vs the driven motion, 0.2 s, h = 1 and 0.5 ms:", errors)
    assert errors[0] < 3e-6
    assert 3.0 < errors[0] / errors[1] < 5.0


def test_all_four_lengths_must_keep_the_feet_stuck(ref):
    """legsim_inverse_dynamics on the stuck stance: consistent lengths (the follower's, as
    the follow call gives them) give the same forces; a follower 0.1 mm off is refused
    (UNREACHABLE) and changes nothing."""
    s = _robot_sim()
    L0 = ref.stand_lengths()
    s.assemble_on_ground(L0)
    L, Ld, Ldd = _schedule(L0, 0.3)
    F, Lo, Ldo, Lddo = s.inverse_dynamics_on_ground(L, Ld, Ldd, follow=[FOLLOW])
    c = s.contacts()
    F4 = s.inverse_dynamics(Lo, Ldo, Lddo)
    c4 = s.contacts()
    assert np.max(np.abs(F4 - F)) < 1e-8
    assert np.max(np.abs(c4["tangential"] - c["tangential"])) < 1e-8
    q = s.q.copy()
    with pytest.raises(legsim.UnreachableError):
        s.inverse_dynamics(Lo + np.array([0, 0, 0, 1e-4]), Ldo, Lddo)
    with pytest.raises(legsim.UnreachableError):
        s.inverse_dynamics(Lo, Ldo + np.array([0, 0, 0, 1e-3]), Lddo)
    with pytest.raises(legsim.NoEquilibriumError):   # accelerations that do not keep them
        s.inverse_dynamics(Lo, Ldo, Lddo + np.array([0, 0, 0, 0.05]))
    np.testing.assert_array_equal(s.q, q)


def test_driven_lengths_must_fix_the_motion(ref):
    """Two followers on two stuck feet (38 rows for 39 coordinates), a follower index
    beyond the actuators, one stuck foot, and a follower on the hanging leg are refused."""
    s = _robot_sim()
    L0 = ref.stand_lengths()
    s.assemble_on_ground(L0)
    z = np.zeros(4)
    with pytest.raises(legsim.BadInputError):
        s.inverse_dynamics_on_ground(L0, z, z, follow=[2, 3])
    with pytest.raises(legsim.BadInputError):
        s.inverse_dynamics_on_ground(L0, z, z, follow=[5])
    s.set_contact(1, "free")                 # one foot: 38 rows with 4 lengths, 37 with 3
    with pytest.raises(legsim.BadInputError):
        s.inverse_dynamics_on_ground(L0, z, z, follow=[FOLLOW])
    leg = legsim.Sim(str(ROOT / "models" / "leg.toml"))
    leg.assemble_pose("stand")
    L = leg.actuator_lengths()[0]
    with pytest.raises(legsim.BadInputError):
        leg.inverse_dynamics_on_ground(L, [0, 0], [0, 0], follow=["lower"])
    # no follower on the hanging leg: the ordinary inverse dynamics
    F = leg.inverse_dynamics_on_ground(L, [0.01, 0], [0, 0])[0]
    np.testing.assert_allclose(F, leg.inverse_dynamics(L, [0.01, 0], [0, 0]), rtol=0, atol=1e-9)


def test_velocity_and_acceleration_analyses_refuse_a_stance(ref):
    """On stuck feet the four rates over-determine the motion: the plain analyses are refused
    (ContactError, nothing changes); the on-ground inverse dynamics gives the stance's qd and
    qdd (three rates drive, the follower's written back), and with the feet free they run."""
    s = _robot_sim()
    s.assemble_on_ground(ref.stand_lengths())
    q = s.q.copy()
    with pytest.raises(legsim.ContactError):
        s.velocity_analysis([0.01, 0.0, 0.0, 0.0])
    with pytest.raises(legsim.ContactError):
        s.acceleration_analysis([0.01, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(s.q, q)
    _, L, Ld, _ = s.inverse_dynamics_on_ground(ref.stand_lengths(), [0.01, 0.0, 0.0, 0.0], np.zeros(4),
                                               follow=[FOLLOW])
    assert abs(Ld[3]) > 1e-4 and np.max(np.abs(s.contacts()["slip"])) < 1e-12
    s.set_contact(0, "free")
    s.set_contact(1, "free")
    qd = s.velocity_analysis([0.01, 0.0, 0.0, 0.0])
    assert np.max(np.abs(qd)) > 1e-3
