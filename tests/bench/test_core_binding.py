"""The ctypes binding of the core (bench/legsim_bench/core.py) against facts of
the leg, the C API's contracts, and the bench's reference model.

Needs the shared libraries liblegsim.so / liblegsim_f32.so (the host CMake
build, targets legsim and legsim_f32; LEGSIM_LIB_DIR overrides where they are
looked for). Skipped, with that reason, only if they are not built.
"""
from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if importlib.util.find_spec("legsim_bench") is None:
    sys.path.insert(0, str(ROOT / "bench"))

from legsim_bench import core as lc  # noqa: E402

if not lc.library_available("double"):
    pytest.skip("liblegsim.so is not built (cmake --build build/host, or set LEGSIM_LIB_DIR)",
                allow_module_level=True)

needs_float = pytest.mark.skipif(not lc.library_available("float"),
                                 reason="liblegsim_f32.so is not built")

# stand-pose facts of models/leg.toml (its comment) and of the reference README
STAND_LENGTHS = (0.6614378, 0.6244998)
STAND_FOOT = (0.4330127, -0.85)
STAND_PHI1, STAND_PHI4 = 0.7137244, 0.7661626
STATICS_GRAVITY = (-93.9289570005, 1.3866057692)
FREE_FALL_FOOT_01 = (0.449053671717, -0.898374031750)


def stand(**kw) -> lc.Core:
    c = lc.Core(**kw)
    c.assemble_pose("stand")
    return c


def test_layout_matches_the_library():
    api = lc.load("double")
    m = api.model("revolute")
    # fields after every array: a wrong capacity or layout would read garbage here
    assert m.name.decode() == "inta-csic-leg"
    assert (m.n_bodies, m.n_joints, m.n_actuators, m.n_forces, m.n_poses) == (6, 8, 2, 1, 1)
    assert m.foot_body == 5 and tuple(m.foot_point) == (0.3, 0.0)
    assert m.pose[0].name.decode() == "stand"
    assert [round(b.mass_kg, 6) for b in m.body[:6]] == [1.2, 0.4, 1.5, 1.0, 0.3, 1.8]
    assert (m.actuator[0].stroke_min_m, m.actuator[0].stroke_max_m) == (0.40, 0.80)
    assert (m.actuator[1].stroke_min_m, m.actuator[1].stroke_max_m) == (0.35, 0.70)
    msg = (lc.C.c_char * 128)()
    assert api.lib.legsim_model_check(lc.C.byref(m), msg, 128) == lc.OK
    assert api.lib.legsim_model_check(lc.C.byref(api.model("slot")), msg, 128) == lc.OK
    assert api.sim_size > 0 and api.config["LEGSIM_USE_FLOAT"] == 0


def test_stand_pose_facts():
    c = stand()
    assert (c.n_bodies, c.n_coords, c.n_constraints, c.n_joints, c.n_actuators) == (6, 18, 16, 8, 2)
    l, rate = c.actuator_lengths()
    np.testing.assert_allclose(l, STAND_LENGTHS, atol=1e-7)
    np.testing.assert_allclose(rate, 0.0, atol=1e-12)
    np.testing.assert_allclose(c.foot(), STAND_FOOT, atol=1e-7)
    q = c.q
    assert q[2] == pytest.approx(STAND_PHI1, abs=1e-7) and q[11] == pytest.approx(STAND_PHI4, abs=1e-7)
    assert q[8] == pytest.approx(math.pi / 3, abs=1e-12) and q[17] == pytest.approx(0.0, abs=1e-12)
    assert c.constraint_residual() <= 1e-10
    np.testing.assert_allclose(c.qd, 0.0)
    np.testing.assert_allclose(c.statics(), STATICS_GRAVITY, atol=1e-7)
    assert c.report().condition < lc.COND_WARN


def test_slot_variant_has_15_equations():
    c = stand(variant="slot")
    assert c.n_constraints == 15
    np.testing.assert_allclose(c.foot(), STAND_FOOT, atol=1e-7)


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_free_fall_matches_the_reference_and_stays_on_the_constraints(integrator):
    c = stand(integrator=integrator, step=1e-4)
    c.step(1000)
    assert c.time == pytest.approx(0.1, abs=1e-12) and c.step_count == 1000
    tol = 1e-9 if integrator == "rk4" else 1e-7
    np.testing.assert_allclose(c.foot(), FREE_FALL_FOOT_01, atol=tol)
    phi, mx = c.constraints()
    assert phi.shape == (16,) and mx <= 1e-9 and mx == pytest.approx(np.max(np.abs(phi)))
    R = c.reactions()
    assert R.shape == (8, 3) and np.all(np.isfinite(R))
    assert c.multipliers().shape == (16,)
    assert c.qdd.shape == (18,)
    J = c.jacobian()
    assert J.shape == (16, 18)
    # RK4 projects the velocities onto Phi_q qd = 0; index-3 generalized-alpha
    # satisfies them only to O(h^2) (5e-8 m/s at h = 1e-4)
    assert np.max(np.abs(J @ c.qd)) < (1e-8 if integrator == "rk4" else 1e-6)


def test_reactions_against_the_reference_model():
    from legsim_bench.reference import ForceCommand, LegModel
    m = LegModel.from_toml(str(ROOT / "models" / "leg.toml"))
    r = m.simulate(0.1, t_eval=[0.0, 0.1], actuators=[ForceCommand(50.0), ForceCommand(0.0)],
                   rtol=1e-12, atol=1e-12)
    c = stand(integrator="rk4", step=1e-3, newton_tol=1e-13)
    c.command_force(0, 50.0)
    c.step(100)
    assert np.max(np.abs(c.q - r.q[-1])) < 1e-10
    assert np.max(np.abs(c.reactions() - r.reactions[-1])) < 1e-7


@needs_float
def test_float_build_close_to_double_after_free_fall():
    d = stand(precision="double", step=1e-3)
    f = stand(precision="float", step=1e-3)
    assert f.api.config["LEGSIM_USE_FLOAT"] == 1 and f.api.real is lc.C.c_float
    d.step(100)
    f.step(100)
    assert np.max(np.abs(f.q - d.q)) < 1e-4
    assert np.max(np.abs(f.foot() - d.foot())) < 1e-4


def test_statuses_raise_with_their_names():
    c = lc.Core()
    with pytest.raises(lc.LegsimError) as e:
        c.step(1)  # nothing assembled yet
    assert e.value.status == lc.ERR_STATE and e.value.name == "LEGSIM_ERR_STATE"
    assert "not assembled" in str(e.value)
    c.assemble_pose("stand")
    with pytest.raises(lc.LegsimError) as e:
        c.command_force(0, 1e9)
    assert e.value.status == lc.ERR_BAD_INPUT
    with pytest.raises(lc.LegsimError) as e:
        c.command_length(1, 0.9)
    assert e.value.status == lc.ERR_OUT_OF_STROKE
    with pytest.raises(lc.LegsimError) as e:
        c.set_options(step=-1.0)
    assert e.value.status == lc.ERR_BAD_INPUT
    assert c.step_size == 1e-3  # refused options leave the old ones
    with pytest.raises(ValueError):
        lc.Core(disable=["no_such_flag"])


def test_disabled_outputs_say_so():
    c = stand(disable=["reactions"])
    c.step(5)
    with pytest.raises(lc.LegsimError) as e:
        c.reactions()
    assert e.value.status == lc.ERR_DISABLED
    # every flag the binding knows is one the library accepts, and no other
    every = sum(lc.DISABLE.values())
    lc.Core(disable=every)
    with pytest.raises(lc.LegsimError) as e:
        lc.Core(disable=every + 1 + max(lc.DISABLE.values()))
    assert e.value.status == lc.ERR_BAD_INPUT


def test_length_servo_and_inverse_dynamics():
    c = stand(integrator="galpha", step=1e-3)
    c.command_length(0, 0.68)
    c.command_length(1, 0.60)
    c.step(1500)
    l, _ = c.actuator_lengths()
    # the PD servo's static error under gravity: about 94 N / kp (20 kN/m) ~ 5 mm
    np.testing.assert_allclose(l, [0.68, 0.60], atol=6e-3)
    assert abs(l[0] - 0.68) > 1e-4  # a servo, not a constraint
    c2 = stand()
    F = c2.inverse_dynamics(STAND_LENGTHS, [0.0, 0.0], [0.0, 0.0])
    np.testing.assert_allclose(F, STATICS_GRAVITY, atol=1e-5)


def test_identical_runs_are_bit_identical():
    def run():
        c = stand(integrator="rk4", step=1e-3)
        c.command_force(0, -60.0)
        c.command_force(1, 10.0)
        c.step(300)
        return c.q_bytes()
    assert run() == run()


def test_timed_step_is_in_process():
    c = stand(step=1e-3)
    ns = c.timed_step(100)
    assert ns > 0 and c.step_count == 100
