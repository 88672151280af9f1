"""The core, driven in-process through the legsim Python API (python/legsim), against
the bench's independent reference model, and the bench's own in-process helpers
(legsim_bench/benchmarks/core.py). The API itself is tested in tests/python.

Needs the shared library liblegsim.so (the host CMake build, target legsim;
LEGSIM_LIB_DIR overrides where it is looked for). Skipped, with that reason, only if
it is not built.
"""
from __future__ import annotations

import numpy as np
import pytest

import legsim
from legsim_bench.benchmarks import core as lc
from model_files import LEG_TOML

if not legsim.library_available("double"):
    pytest.skip("liblegsim.so is not built (cmake --build build/host, or set LEGSIM_LIB_DIR)",
                allow_module_level=True)

FREE_FALL_FOOT_01 = (0.449053671717, -0.898374031750)  # bench reference, t = 0.1 s


def stand(**kw) -> legsim.Sim:
    s = legsim.Sim(**kw)
    s.assemble_pose("stand")
    return s


def test_reactions_against_the_reference_model():
    from legsim_bench.reference import ForceCommand, LegModel
    m = LegModel.from_toml(str(LEG_TOML))
    r = m.simulate(0.1, t_eval=[0.0, 0.1], actuators=[ForceCommand(50.0), ForceCommand(0.0)],
                   rtol=1e-12, atol=1e-12)
    s = stand(integrator="rk4", step=1e-3, newton_tol=1e-13)
    s.command_force(0, 50.0)
    s.step(100)
    assert np.max(np.abs(s.q - r.q[-1])) < 1e-10
    assert np.max(np.abs(s.reactions() - r.reactions[-1])) < 1e-7


@pytest.mark.parametrize("integrator", ["rk4", "galpha"])
def test_free_fall_foot_matches_the_reference(integrator):
    s = stand(integrator=integrator, step=1e-4)
    s.step(1000)
    tol = 1e-9 if integrator == "rk4" else 1e-7
    np.testing.assert_allclose(s.foot(), FREE_FALL_FOOT_01, atol=tol)


def test_identical_runs_are_bit_identical():
    def run():
        s = stand(integrator="rk4", step=1e-3)
        s.command_force(0, -60.0)
        s.command_force(1, 10.0)
        s.step(300)
        return s.state_bytes()
    assert run() == run()


def test_timed_step_and_raw_status():
    s = stand(step=1e-3)
    ns = lc.timed_step(s, 100)
    assert ns > 0 and s.step_count == 100
    fresh = legsim.Sim()
    assert lc.step_status(fresh, 1) == legsim.Status.ERR_STATE  # raw, not raised
    with pytest.raises(legsim.StateError):
        lc.timed_step(fresh, 1)
