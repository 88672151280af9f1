"""The two-leg robot (models/robot.toml) in the core through the Python API, against
the bench's independent reference (legsim_bench.reference.robot.RobotModel).

The robot is compiled in when the build's capacities hold it (host defaults) and loads
from its file by the library's loader; the stand assembly (both feet stuck on the ground
line) must give the reference's closed-form pose, and the stuck feet's ground forces,
with gravity, must balance the whole robot's momentum rate.
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


@pytest.fixture(scope="module")
def ref():
    return RobotModel.from_toml(ROBOT)


def test_robot_file_and_compiled_in_robot_are_one_model():
    s = _robot_sim()
    b = legsim.Model.builtin(symbol="robot")
    assert bytes(s.model.desc) == bytes(b.desc)
    assert s.model.contact_names == ["right.foot", "left.foot"]
    assert s.n_bodies == 13 and s.n_constraints == 32 and s.n_contacts == 2
    assert s.model.ground["mu_static"] == 0.6 and s.model.ground["mu_kinetic"] == 0.5


def test_stand_assembly_matches_the_reference(ref):
    s = _robot_sim()
    lengths = ref.stand_lengths()
    q = s.assemble_on_ground(lengths, feet_mid=0.0)
    a = ref.assemble(lengths, feet_mid=0.0)
    # the reference's closed form against the core's Newton: round-off apart
    assert np.max(np.abs(q - a.q)) < 1e-12
    assert abs(s.box()[1] - 1.000) < 5e-4
    c = s.contacts()
    assert list(c["state"]) == ["stuck", "stuck"]
    assert np.max(np.abs(c["position"] - a.feet)) < 1e-12
    assert abs(c["position"][0, 0] - 0.6330) < 5e-5 and abs(c["position"][1, 0] + 0.6330) < 5e-5
    assert np.max(np.abs(c["position"][:, 1])) < 1e-14          # on the line y = 0
    assert np.max(np.abs(s.actuator_lengths()[0] - lengths)) < 1e-12
    # from the robot file's own stand pose (its guess has the feet on the line already)
    q2 = s.assemble_on_ground()
    assert np.max(np.abs(q2 - a.q)) < 1e-9


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_stuck_feet_hold_and_ground_forces_balance_the_robot(ref, integrator):
    s = _robot_sim(integrator=integrator)
    s.assemble_on_ground(ref.stand_lengths())
    for a, L in enumerate(ref.stand_lengths()):
        s.command_length(a, L)   # the servos hold the stand
    feet0 = s.contacts()["position"].copy()
    s.step(100)
    c = s.contacts()
    assert list(c["state"]) == ["stuck", "stuck"]
    assert np.max(np.abs(c["position"] - feet0)) < 1e-9        # the feet do not move
    # momentum rate of the whole robot = gravity + ground forces (joint forces cancel)
    m = np.repeat(s.model.masses, 2)
    qdd = s.qdd.reshape(-1, 3)[:, :2].reshape(-1)
    lhs = (m * qdd).reshape(-1, 2).sum(axis=0)
    weight = s.model.masses.sum() * s.model.gravity
    ground = np.array([0.0, 1.0]) * c["normal"].sum() + np.array([1.0, 0.0]) * c["tangential"].sum()
    # RK4: qdd and the ground forces come from one solve, so they balance to round-off.
    # Generalized-alpha reports its index-3 qdd, and forces from the acceleration-level
    # solve at the same state (legsim_multipliers' note), whose velocities are projected
    # onto the rows after that qdd was found: they differ by its own acceleration error
    # (2.7e-3 N of 318 N here: the servos' damping times the projection's correction).
    tol = 1e-9 if integrator == "rk4" else 1e-5
    assert np.max(np.abs(lhs - weight - ground)) < tol * s.model.masses.sum() * 9.81
    assert c["normal"].sum() > 0.9 * s.model.masses.sum() * 9.81


def test_fig7_scene_a_matches_the_reference(ref):
    """Design section 7, Scene A: from the servo stand at rest, the right upper actuator
    switches to force mode at its hold force + 50 N for 0.1 s, the other three stay on
    their servos; RK4 at h = 1 ms against the reference's DOP853 (rtol 1e-11). RK4's
    global error is O(h^4) ~ (1e-3)^4 times the motion's fourth derivative scale: the
    box moves 4 mm in 0.1 s, so 1e-9 m (rad, N/1e3) is a safe bound."""
    from legsim_bench.reference import ForceCommand, LengthCommand
    servo = [LengthCommand(float(x)) for x in ref.stand_lengths()]
    z_eq = ref.equilibrium(servo)
    start = ref.simulate(0.0, t_eval=[0.0], actuators=servo, i0=z_eq[[2, 3, 4]])
    hold = float(start.actuator_forces[0, 0])
    cmds = [ForceCommand(hold + 50.0)] + servo[1:]
    r = ref.simulate(0.1, t_eval=[0.0, 0.1], actuators=cmds, i0=z_eq[[2, 3, 4]])

    s = _robot_sim(integrator="rk4", step=1e-3)
    s.set_state(start.q[0])
    s.set_contact("right.foot", "stuck")
    s.set_contact("left.foot", "stuck")
    for a in range(1, 4):
        s.command_length(a, servo[a].length)
    s.command_force(0, hold + 50.0)
    s.run(0.1)
    q = s.q
    assert np.max(np.abs(q[:3] - r.q[-1][:3])) < 1e-9                  # box (x, y, phi)
    assert abs(q[3 * 3 + 2] - r.q[-1][3 * 3 + 2]) < 1e-9               # right phi3 (thigh)
    assert abs(q[3 * 6 + 2] - r.q[-1][3 * 6 + 2]) < 1e-9               # right phi6 (shank)
    c = s.contacts()
    print("scene A errors: box", np.abs(q[:3] - r.q[-1][:3]).max(), "phi3", abs(q[11] - r.q[-1][11]),
          "phi6", abs(q[20] - r.q[-1][20]), "N", np.abs(c["normal"] - r.normal[-1]).max(),
          "T", np.abs(c["tangential"] - r.tangential[-1]).max(), "N, T", c["normal"], c["tangential"])
    assert np.max(np.abs(c["normal"] - r.normal[-1])) < 1e-6
    assert np.max(np.abs(c["tangential"] - r.tangential[-1])) < 1e-6
    # the figures of design section 7
    assert abs(q[3 * 3 + 2] - 1.07133) < 1e-5 and abs(q[3 * 6 + 2] + 0.01484) < 1e-5


# ---- statics of the stance on two stuck feet, with the stated rule (design section 3) ----
def _robot_with_box_load(load) -> legsim.Sim:
    """The robot with a load (Fx, Fy N, M N m) on the box centre: two force elements
    (a point force and a torque on body 0) added to a copy of its description."""
    base = _robot_sim().model
    desc = type(base.desc).from_buffer_copy(base.desc)
    nf = desc.n_forces
    for k, (kind, value) in enumerate([(0, (load[0], load[1])), (1, (load[2], 0.0))]):
        f = desc.force[nf + k]
        f.name = b"box.load" if kind == 0 else b"box.moment"
        f.kind = kind
        f.body[0], f.body[1] = 0, -1
        f.point[0][0] = f.point[0][1] = 0.0
        f.value[0], f.value[1] = value
    desc.n_forces = nf + 2
    return legsim.Sim(legsim.Model(desc, base.library, base.variant, "robot + box load"))


@pytest.mark.parametrize("rule", ["equal_friction", "min_tangential"])
@pytest.mark.parametrize("load", [(0.0, 0.0, 0.0), (40.0, -150.0, 12.0), (-90.0, 30.0, -25.0)])
def test_stance_statics_matches_the_reference(ref, rule, load):
    s = _robot_with_box_load(load)
    s.set_options(statics_rule=rule)
    lengths = ref.stand_lengths()
    s.assemble_on_ground(lengths)
    F = s.statics()
    r = ref.statics(lengths, box_load=load, rule=rule)
    c = s.contacts()
    scale = s.model.masses.sum() * 9.81
    print(rule, load, "F", F, "N", c["normal"], "T", c["tangential"],
          "errors F", np.abs(F - r.actuator_forces).max(), "N, T",
          np.abs(c["normal"] - r.normal).max(), np.abs(c["tangential"] - r.tangential).max(),
          "reactions", np.abs(s.reactions() - r.reactions).max())
    assert np.max(np.abs(F - r.actuator_forces)) < 1e-9 * scale
    assert np.max(np.abs(c["normal"] - r.normal)) < 1e-10 * scale
    assert np.max(np.abs(c["tangential"] - r.tangential)) < 1e-10 * scale
    assert np.max(np.abs(s.reactions() - r.reactions)) < 1e-9 * scale
    assert list(c["holds"]) == list(r.holds)
    assert list(c["state"]) == ["stuck", "stuck"]           # statics changes no state
    if rule == "equal_friction":                             # the rule itself
        assert abs(c["tangential"][0] * c["normal"][1] - c["tangential"][1] * c["normal"][0]) \
            < 1e-10 * scale ** 2
    else:
        assert abs(c["tangential"][0] - c["tangential"][1]) < 1e-10 * scale
    # the ground forces and the load balance the weight (statics: no momentum rate)
    total = np.array([c["tangential"].sum() + load[0], c["normal"].sum() + load[1]])
    assert np.max(np.abs(total - np.array([0.0, scale]))) < 1e-10 * scale


def test_stand_statics_figures_of_the_design(ref):
    """Design section 4: 326.539 N upper, 1.387 N lower per leg, N = 158.922 N per foot
    (equal_friction; with no tangential load the rule gives T = 0 on both feet)."""
    s = _robot_sim()
    s.assemble_on_ground(ref.stand_lengths())
    F = s.statics()
    c = s.contacts()
    assert np.allclose(F, [326.539, 1.387, 326.539, 1.387], atol=5e-4)
    assert np.allclose(c["normal"], [158.922, 158.922], atol=5e-4)
    assert np.max(np.abs(c["tangential"])) < 1e-9 and all(c["holds"])


def test_stance_statics_says_which_feet_friction_holds(ref):
    """A sideways load beyond mu_s times the weight: both feet out of the cone under
    equal_friction (they reach it together), named per foot, and nothing refused; below
    it both hold (equal use on both: |T_0|/N_0 = |T_1|/N_1 = Fx / (N_0 + N_1); the moment
    cancels the load's about the ground, the box centre being 1 m up). A load that tips the robot: the ground
    would have to pull on the far foot, which cannot hold."""
    for fx, holds in [(200.0, False), (150.0, True)]:
        s = _robot_with_box_load((fx, 0.0, fx * 1.0))
        s.assemble_on_ground(ref.stand_lengths())
        s.statics()
        c = s.contacts()
        assert list(c["holds"]) == [holds, holds]
        assert np.allclose(c["friction_use"], fx / c["normal"].sum(), rtol=1e-9)
    s = _robot_with_box_load((250.0, 0.0, 0.0))
    s.assemble_on_ground(ref.stand_lengths())
    s.statics()
    c = s.contacts()
    assert c["normal"][1] < 0 and not c["holds"][1]


def test_stance_statics_rule_option_is_checked():
    s = _robot_sim()
    with pytest.raises(ValueError):
        s.set_options(statics_rule="paper")
    assert s.options["statics_rule"] == "equal_friction"
    s.set_options(statics_rule="min_tangential")
    assert s.options["statics_rule"] == "min_tangential"
