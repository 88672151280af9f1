"""Generalized-alpha through a lift-off that follows a slip onset within the step
(docs/design/events.md), against the bench's event-locating reference, with the case and
the helpers of firmware_core/benchmarks/event_order.py (imported, not copied).

The case (event_order.py's "liftoff"): the robot pitches on stuck feet, the left foot slips
at 96.32 ms and lifts off 23.4 us later (its normal force falls to zero in the sliding
mode). A part step over the slide that is hundreds of us long ends with N growing again and
the slip reversed: the lift-off unseen, taken at the step's end, the error 1e-2 .. 1e-5 m and
not falling with h. Located, and the slide's velocity drift taken off along its friction
(an M-orthogonal projection left a first-order part: order 1.33 or 1.03 over the last
pair), the error at the fixed time falls at the integrator's order 2 (15.5 .. 16.3 h^2 m/s^2
measured) and the lift-off's time is second order too (0.43 .. 0.48 h^2/s late)."""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

legsim = pytest.importorskip("legsim")

ROOT = Path(__file__).resolve().parents[2]
STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4)


def event_order_module():
    path = ROOT / "firmware_core" / "benchmarks" / "event_order.py"
    spec = importlib.util.spec_from_file_location("event_order", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def runs():
    eo = event_order_module()
    case = eo.cases()["liftoff"]
    ref = case.reference()
    kinds = [e.kind for e in ref.events]
    assert kinds == ["stick_to_slip", "liftoff"]
    t_liftoff = ref.events[1].t
    assert 20e-6 < t_liftoff - ref.events[0].t < 30e-6  # the slide lasts 23.4 us
    return t_liftoff, {h: eo.run_core(case, "galpha", h, ref) for h in STEPS}


def test_galpha_liftoff_error_falls_at_order_two(runs):
    _, by_h = runs
    errors = [by_h[h][0] for h in STEPS]
    orders = [math.log2(a / b) for a, b in zip(errors, errors[1:])]
    assert all(o >= 1.9 for o in orders), (errors, orders)
    # second order with its constant: 18 h^2 m/s^2 (before the fix 21.9 and 42.8 at the finest two)
    assert all(e <= 18 * h * h for e, h in zip(errors, STEPS)), errors


@pytest.mark.parametrize("h", STEPS)
def test_galpha_liftoff_located(runs, h):
    t_liftoff, by_h = runs
    events = by_h[h][2]
    # the step that holds the slip onset holds the lift-off too, located in it
    t, kinds = next((t, k) for t, k in events if "liftoff" in k)
    assert "stick_to_slip" in kinds
    # second order: 0.6 h^2 / (1 s) (before the fix 1.2 and 4.0 h^2 at the finest two)
    assert abs(t - t_liftoff) <= 0.6 * h * h, (t, t_liftoff)
