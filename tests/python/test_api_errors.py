"""Every failing status of the C API reaches Python as the exception for it, with
the status code and C name, and the refused call changes nothing."""
from __future__ import annotations

import math

import numpy as np
import pytest

import legsim

NAN = float("nan")


def test_every_status_has_its_exception_class(precision):
    lib = legsim.load_library(precision)
    for st in legsim.Status:
        if st == legsim.Status.OK:
            continue
        e = legsim.error_for(st, "legsim_x", lib.status_str(st))
        assert isinstance(e, legsim.LegsimError) and type(e) is not legsim.LegsimError
        assert e.status == int(st) and type(e).status_code == int(st)
        assert e.status_name == f"LEGSIM_{st.name}" == st.c_name
        assert e.text and e.text != lib.status_str(0)  # the library explains each one
        assert str(e).startswith(f"legsim_x: LEGSIM_{st.name}")
    assert legsim.status_name(99) == "status 99"
    assert type(legsim.error_for(99, "f")) is legsim.LegsimError


def _raises(cls, name, fn, *args):
    with pytest.raises(cls) as e:
        fn(*args)
    assert e.value.status_name == name and e.value.status == legsim.Status[name[7:]]
    return e.value


def test_unreachable_singular_and_out_of_stroke_assembly(stand, precision):
    s = stand(precision=precision)
    before = s.state_bytes()
    e = _raises(legsim.UnreachableError, "LEGSIM_ERR_UNREACHABLE", s.assemble, [0.80, 0.35])
    assert e.function == "legsim_assemble"
    assert s.state_bytes() == before  # q left unchanged
    _raises(legsim.SingularError, "LEGSIM_ERR_SINGULAR", s.assemble, [0.60, 0.70])
    assert s.state_bytes() == before
    _raises(legsim.OutOfStrokeError, "LEGSIM_ERR_OUT_OF_STROKE", s.assemble, [0.90, 0.5])
    _raises(legsim.OutOfStrokeError, "LEGSIM_ERR_OUT_OF_STROKE", s.command_length, "lower", 0.9)
    assert s.state_bytes() == before
    s.step(1)  # still usable


@pytest.mark.parametrize("call", [
    lambda s: s.command_force(0, NAN),
    lambda s: s.command_force("upper", math.inf),
    lambda s: s.command_force(0, 1e9),        # above max_force
    lambda s: s.command_force(5, 1.0),        # no actuator 5
    lambda s: s.command_length(1, NAN),
    lambda s: s.set_force(0, [NAN, 0.0]),
    lambda s: s.assemble([NAN, 0.6]),
    lambda s: s.set_state(np.full(18, NAN)),
    lambda s: s.velocity_analysis([0.0, NAN]),
    lambda s: s.inverse_dynamics([0.66, 0.62], [0, 0], [math.inf, 0]),
    lambda s: s.set_options(step=NAN),
    lambda s: s.set_options(step=-1.0),
    lambda s: s.set_options(rho_inf=1.5),
    lambda s: s.statics_sweep(1),
])
def test_nan_and_nonsense_input_raise_bad_input_and_change_nothing(stand, precision, call):
    s = stand(precision=precision)
    s.command_force(0, 20.0)
    s.step(3)
    before, options = s.state_bytes(), s.options
    _raises(legsim.BadInputError, "LEGSIM_ERR_BAD_INPUT", call, s)
    assert s.state_bytes() == before and s.options == options
    s.step(1)


def test_state_and_equilibrium_errors(stand):
    s = legsim.Sim()
    e = _raises(legsim.StateError, "LEGSIM_ERR_STATE", s.step, 1)  # nothing assembled
    assert "assembled" in e.text
    slot = stand(variant="slot")  # 3 degrees of freedom, 2 actuators: no equilibrium
    _raises(legsim.NoEquilibriumError, "LEGSIM_ERR_NO_EQUILIBRIUM", slot.statics)


def test_disabled_outputs_and_flags(stand):
    s = stand(disable=["reactions"])
    assert s.disabled == ["reactions"]
    s.step(5)
    _raises(legsim.DisabledError, "LEGSIM_ERR_DISABLED", s.reactions)
    every = sum(legsim.DISABLE.values())
    legsim.Sim(disable=every)  # every flag the binding knows, the library accepts
    with pytest.raises(legsim.BadInputError):
        legsim.Sim(disable=2 * max(legsim.DISABLE.values()))  # and no other
    with pytest.raises(ValueError, match="unknown disable flag"):
        legsim.Sim(disable=["no_such_flag"])
    with pytest.raises(ValueError, match="integrator"):
        legsim.Sim(integrator="euler")
    with pytest.raises(TypeError):
        s.set_options(stepsize=1e-3)


def test_wrong_sizes_and_names_are_python_errors(stand):
    s = stand()
    with pytest.raises(ValueError, match="need 2 values"):
        s.assemble([0.6])
    with pytest.raises(ValueError, match="no actuator"):
        s.command_force("middle", 1.0)
    with pytest.raises(ValueError, match="no pose"):
        s.assemble_pose("crouch")


def test_a_diverging_step_is_reported(stand):
    """RK4 with a step far beyond its stability limit under the stiff servo (kp 20 kN/m): the
    leg flails until a step fails. Which check trips first in the blow-up (the projection's
    Newton, a dead centre passed on the way, a value out of range) is a matter of round-off,
    so any of them; the call is refused and the state is the last good step's."""
    s = stand(integrator="rk4", step=0.05)
    s.command_length("upper", 0.75)
    s.command_force("lower", 1500.0)
    with pytest.raises((legsim.DivergedError, legsim.SingularError, legsim.NotConvergedError)) as e:
        s.step(200)
    assert e.value.function == "legsim_step"
    assert e.value.status_name in ("LEGSIM_ERR_DIVERGED", "LEGSIM_ERR_SINGULAR", "LEGSIM_ERR_NOT_CONVERGED")
    assert 0 < s.step_count < 200 and np.all(np.isfinite(s.q))  # the last good step's state
