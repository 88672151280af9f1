"""Property tests (Hypothesis) of the core under random command sequences: the
fast part of the stress campaign (bench/legsim_bench/benchmarks/stress.py).

Properties, for both integrators (and the float build when it is there):
* every call returns LEGSIM_OK or a status legsim.h documents for it;
* the state (q, qd) and the reactions stay finite after every call: a failure
  is reported by a status, never by a NaN;
* a failed step leaves a state from which the stand pose re-assembles;
* identical command sequences give bit-identical q and qd.

Command sequences include force commands at and beyond max_force, length
commands near and beyond the stroke ends, near the upper actuator's dead
centre (0.75 m) and near the knee-straight lower stroke end (0.70 m).

Needs liblegsim.so (and liblegsim_f32.so for the float cases); skipped, with
that reason, only if they are not built.
"""
from __future__ import annotations

import numpy as np
import pytest

import legsim
from legsim_bench.benchmarks import core as lc

if not legsim.library_available("double"):
    pytest.skip("liblegsim.so is not built (cmake --build build/host, or set LEGSIM_LIB_DIR)",
                allow_module_level=True)

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from legsim_bench.benchmarks.stress import ALLOWED, STROKES, run_sequence  # noqa: E402

PRECISIONS = ["double"] + (["float"] if legsim.library_available("float") else [])
FMAX = 1500.0

actuator = st.integers(0, 1)
finite_force = st.floats(-FMAX, FMAX, allow_nan=False)
any_force = st.one_of(finite_force, st.sampled_from([FMAX, -FMAX, 1.0001 * FMAX, -2 * FMAX,
                                                     float("nan"), float("inf")]))


@st.composite
def length_command(draw):
    a = draw(actuator)
    lo, hi = STROKES[a]
    kind = draw(st.sampled_from(["inside", "end", "beyond", "dead_centre", "knee"]))
    if kind == "inside":
        return ("command_length", (a, draw(st.floats(lo, hi))))
    eps = 10.0 ** draw(st.floats(-10, -2))
    if kind == "end":
        return ("command_length", (a, draw(st.sampled_from([lo + eps, hi - eps, lo, hi]))))
    if kind == "beyond":
        return ("command_length", (a, draw(st.sampled_from([lo - eps, hi + eps]))))
    if kind == "dead_centre":
        return ("command_length", (0, 0.75 + draw(st.floats(-0.01, 0.01))))
    return ("command_length", (1, 0.70 - eps))


command = st.one_of(
    st.tuples(st.just("command_force"), st.tuples(actuator, any_force)),
    length_command(),
    st.tuples(st.just("set_force"),
              st.tuples(st.just(0), st.tuples(st.floats(-500, 500), st.floats(-300, 800)))),
)
segment = st.tuples(command, st.integers(1, 150))
sequence = st.lists(segment, min_size=1, max_size=12)


def flatten(segs):
    ops = []
    for cmd, n in segs:
        ops.append(cmd)
        ops.append(("step", (n,)))
    return ops


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(segs=sequence, integrator=st.sampled_from(["rk4", "galpha"]),
       precision=st.sampled_from(PRECISIONS), h=st.sampled_from([1e-4, 1e-3, 5e-3]))
def test_random_commands_never_nan_and_only_documented_statuses(segs, integrator, precision, h):
    r = run_sequence(precision, integrator, flatten(segs), h=h)
    assert r["bad"] == [], r["bad"]
    for (op, name), _ in r["counts"].items():
        assert name in {legsim.status_name(s) for s in ALLOWED[op]}, (op, name)


@settings(max_examples=10, deadline=None)
@given(segs=sequence, integrator=st.sampled_from(["rk4", "galpha"]),
       precision=st.sampled_from(PRECISIONS))
def test_identical_sequences_give_identical_bytes(segs, integrator, precision):
    ops = flatten(segs)
    a = run_sequence(precision, integrator, ops)
    b = run_sequence(precision, integrator, ops)
    assert a["digest"] == b["digest"] and a["final"] == b["final"]


@settings(max_examples=15, deadline=None)
@given(fu=st.floats(-FMAX, FMAX), fl=st.floats(-FMAX, FMAX),
       integrator=st.sampled_from(["rk4", "galpha"]), h=st.sampled_from([1e-3, 1e-2, 5e-2]))
def test_constant_forces_step_reports_or_stays_on_the_manifold(fu, fl, integrator, h):
    c = legsim.Sim(integrator=integrator, step=h)
    c.assemble_pose("stand")
    c.command_force(0, fu)
    c.command_force(1, fl)
    for _ in range(20):
        s = lc.step_status(c, 5)
        assert s in ALLOWED["step"], legsim.status_name(s)
        assert np.all(np.isfinite(c.q)) and np.all(np.isfinite(c.qd))
        if s != legsim.Status.OK:
            c.assemble_pose("stand")  # the state left behind is usable
            break
        assert c.constraint_residual() < 1e-8
        l, _ = c.actuator_lengths()
        # the stroke stops keep every length inside its stroke (to the Newton tolerance)
        for a, (lo, hi) in enumerate(STROKES):
            assert lo - 1e-8 <= l[a] <= hi + 1e-8


def test_a_stop_does_not_push_the_other_actuator_out_of_its_stroke():
    c = legsim.Sim(integrator="rk4", step=1e-2)
    c.assemble_pose("stand")
    c.command_force(0, -100.0)
    c.command_force(1, -16.0)
    worst = 0.0
    for _ in range(100):
        c.step(1)
        l, _ = c.actuator_lengths()
        worst = max(worst, max(lo - x for x, (lo, _hi) in zip(l, STROKES)))
    assert worst <= 1e-8, f"a length {worst:.2e} m below its stroke's start"


def test_strokes_in_the_stress_module_match_the_library():
    c = legsim.Sim()
    assert [tuple(s) for s in c.model.strokes] == [tuple(s) for s in STROKES]
    assert list(c.model.max_forces) == [FMAX, FMAX]
